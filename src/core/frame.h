#pragma once
/// \file frame.h
/// Orthonormal frames: shading happens in a local frame whose z axis is the shading normal.
#include "core/math.h"

namespace tessera {

/// Builds t, b with (t, b, n) right-handed and orthonormal for a unit n, without branches on
/// near-zero components (Duff et al. 2017, "Building an Orthonormal Basis, Revisited", JCGT 6(1), Listing 3).
inline void coordinateSystem(const Vec3f& n, Vec3f& t, Vec3f& b) {
    float sign = std::copysign(1.f, n.z);
    float a = -1.f / (sign + n.z);
    float c = n.x * n.y * a;
    t = Vec3f(1.f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = Vec3f(c, sign + n.y * n.y * a, -n.y);
}

struct Frame {
    Vec3f s, t, n;
    Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
    explicit Frame(const Vec3f& normal) : n(normal) { coordinateSystem(n, s, t); }
    Vec3f toLocal(const Vec3f& v) const { return {glm::dot(v, s), glm::dot(v, t), glm::dot(v, n)}; }
    Vec3f toWorld(const Vec3f& v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace tessera
