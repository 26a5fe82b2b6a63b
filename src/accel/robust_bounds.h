#pragma once
/// \file robust_bounds.h
/// The floating-point padding that keeps the BVH and k-d tree traversals conservative: a box or
/// cell that a ray enters (or passes within rounding distance of) is never culled by rounding.
/// Padding is relative to the magnitudes involved, in ulps of float (2^-23 relative per ulp).
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/bounds.h"

namespace tessera {

/// Raises a t bound by 4 ulps (padUp). A computed box entry distance may exceed the exact one by
/// about 1.5 ulps (one subtraction, one product).
inline constexpr float kTPadRelative = 0x1p-21f;
/// Pads a triangle's box in the BVH by 8 ulps of its coordinates' magnitude: the watertight test
/// may place a hit a few ulps outside the exact triangle (its shear rounds).
inline constexpr float kTriangleBoxPadRelative = 0x1p-20f;
/// The k-d traversal visits every cell the ray passes within 16 ulps of the largest coordinate
/// involved (kdtree_traversal.cpp, startRay): its primitive boxes and perfect splits are exact.
inline constexpr float kKdCellPadRelative = 0x1p-19f;

/// |x| enlarged by two ulps (x finite or ±inf; inf stays inf): the conservative far reciprocal of
/// Ize 2013 ("Robust BVH Ray Traversal", JCGT 2(2), Section 3). Bit arithmetic instead of two
/// std::nextafter calls, which cost more than the whole box setup of a ray.
inline float twoUlpsLarger(float x) {
    uint32_t bits;
    std::memcpy(&bits, &x, 4);
    if ((bits & 0x7fffffffu) >= 0x7f7ffffeu) return std::copysign(kInfinity, x);
    bits += 2;  // the magnitude is in the low 31 bits: +2 moves two floats away from zero
    std::memcpy(&x, &bits, 4);
    return x;
}

/// A t bound raised by 4 ulps, for comparing two computed distances along the same ray: boxes are
/// culled against the padded closest hit, so a primitive lying on a box face is never culled by
/// rounding (Ize 2013, Section 3 bounds the far side; this covers the near side).
inline float padUp(float t) { return t + std::abs(t) * kTPadRelative; }

/// `b` grown by kTriangleBoxPadRelative of its coordinates' magnitude on every side.
inline Bounds3f padTriangleBox(Bounds3f b) {
    Vec3f pad = kTriangleBoxPadRelative * glm::max(glm::abs(b.lower), glm::abs(b.upper));
    b.lower -= pad;
    b.upper += pad;
    return b;
}

}  // namespace tessera
