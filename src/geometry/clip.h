#pragma once
/// \file clip.h
/// A triangle clipped to an axis-aligned box (Sutherland–Hodgman, in double precision). The k-d
/// tree's perfect splits and the BVH's spatial splits both need the exact part of a triangle in a
/// cell: its box becomes a node's box, so it must contain every point of that part.
#include "core/bounds.h"

namespace tessera {

/// The triangle clipped to `box`, as the double-precision bounds of the clipped polygon; false when
/// nothing remains.
bool clipTriangleDouble(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box, Vec3d& lo, Vec3d& hi);

/// Bounds of triangle (p0, p1, p2) clipped to `box`, rounded outward to float (and kept inside the
/// box); empty when the triangle does not reach the box.
Bounds3f clipTriangleBounds(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box);

}  // namespace tessera
