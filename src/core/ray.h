#pragma once
/// \file ray.h
/// Rays and the self-intersection-free spawning of secondary rays.
#include <cstring>

#include "core/math.h"

namespace tessera {

/// A ray o + t·d for t in [tMin, tMax]. `d` need not be unit length (shadow rays use the segment).
struct Ray {
    Vec3f o{0.f};
    Vec3f d{0.f, 0.f, 1.f};
    float tMin = 0.f;
    float tMax = kInfinity;
};

/// Moves a surface point off its surface along the geometric normal `n` (facing the side the new ray
/// leaves on) by a fixed number of ulps of each coordinate, so that the spawned ray can use tMin = 0
/// without re-hitting the surface, at any distance from the origin (Wächter & Binder 2019, "A Fast
/// and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6, Listing 6-1). An
/// epsilon in world units would fail either on the radius-1e4 walls (too small) or on tiny geometry.
inline Vec3f offsetRayOrigin(const Vec3f& p, const Vec3f& n) {
    constexpr float kOrigin = 1.f / 32.f;
    constexpr float kFloatScale = 1.f / 65536.f;
    constexpr float kIntScale = 256.f;
    Vec3f out;
    for (int i = 0; i < 3; ++i) {
        int32_t offsetUlps = int32_t(kIntScale * n[i]);
        int32_t bits;
        std::memcpy(&bits, &p[i], 4);
        bits += (p[i] < 0.f) ? -offsetUlps : offsetUlps;
        float moved;
        std::memcpy(&moved, &bits, 4);
        out[i] = std::abs(p[i]) < kOrigin ? p[i] + kFloatScale * n[i] : moved;
    }
    return out;
}

/// A ray leaving the surface point `p` (geometric normal `ng`, any orientation) in direction `d`.
inline Ray spawnRay(const Vec3f& p, const Vec3f& ng, const Vec3f& d) {
    Vec3f n = glm::dot(ng, d) < 0.f ? -ng : ng;
    return Ray{offsetRayOrigin(p, n), d, 0.f, kInfinity};
}

/// A shadow ray from surface point `p0` (normal `n0`) to surface point `p1` (normal `n1`; zero for a
/// point light). Both ends are offset off their surfaces, so t in [0, 1) covers exactly the open segment.
inline Ray spawnShadowRay(const Vec3f& p0, const Vec3f& n0, const Vec3f& p1, const Vec3f& n1) {
    Vec3f dir = p1 - p0;
    Vec3f a = offsetRayOrigin(p0, glm::dot(n0, dir) < 0.f ? -n0 : n0);
    Vec3f b = glm::dot(n1, n1) > 0.f ? offsetRayOrigin(p1, glm::dot(n1, dir) > 0.f ? -n1 : n1) : p1;
    // 1 - 2^-20: stops just short of the (offset) light point without skipping real occluders.
    return Ray{a, b - a, 0.f, 1.f - 0x1p-20f};
}

}  // namespace tessera
