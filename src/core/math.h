#pragma once
/// \file math.h
/// Vector types (GLM) and the small scalar helpers every layer uses.
#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace tessera {

using Vec2f = glm::vec2;
using Vec3f = glm::vec3;
using Vec4f = glm::vec4;
using Vec2i = glm::ivec2;
using Vec3d = glm::dvec3;
using Mat4f = glm::mat4;
using Mat4d = glm::dmat4;
/// Linear Rec.709 RGB radiance / reflectance. Tessera renders in RGB, like Cycles and Mitsuba's rgb variants.
using Rgb = glm::vec3;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;
inline constexpr float kInv2Pi = 0.15915494309189533577f;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();
/// Largest float below 1: keeps [0,1) samples strictly below 1 after float rounding.
inline constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

inline float luminance(const Rgb& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }
inline float maxComponent(const Vec3f& v) { return std::max(v.x, std::max(v.y, v.z)); }
inline bool isBlack(const Rgb& c) { return c.r == 0.f && c.g == 0.f && c.b == 0.f; }
inline bool isFinite(const Vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline float safeSqrt(float x) { return std::sqrt(std::max(0.f, x)); }
inline float sqr(float x) { return x * x; }

}  // namespace tessera
