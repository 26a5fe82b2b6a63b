#pragma once
/// \file bvh_spatial.h
/// The high-quality build of our BVH: SAH with spatial splits (Stich, Friedrich & Dietrich 2009,
/// "Spatial Splits in Bounding Volume Hierarchies", HPG), selected with `--accel sbvh`. Long thin or
/// large triangles make object-split BVHs overlap badly (every ray crossing a sliver's box visits
/// it); a spatial split cuts such a reference at a plane and puts each part, with its clipped box,
/// on its own side. The output is the same BinaryBvh the object-split builder makes (bvh_builder.h),
/// except that a primitive may appear in several leaves.
#include <functional>
#include <span>

#include "accel/bvh_builder.h"
#include "geometry/clip.h"

namespace tessera {

/// Bounds of the part of primitive `prim` inside `box` (empty when they do not meet). Must contain
/// every point of the primitive inside the box, and should be tight: it becomes a node's box.
using ClipToBox = std::function<Bounds3f(uint32_t prim, const Bounds3f& box)>;

/// Builds the binary tree with object and spatial splits. `primBounds`/`centroids` as for
/// buildBinaryBvh. Single-threaded and deterministic. Spatial splits stop once the references grow
/// by `config.spatialSplitBudget` × the primitive count, and are only tried where the best object
/// split's children overlap by more than `config.spatialSplitAlpha` of the root's area (paper,
/// Section 4.5: this keeps the build near the cost of an object-split build where splits cannot pay).
/// `triangles` holds three vertices per primitive (NaN for primitives that are not triangles, whose
/// parts are then estimated by their box): the split search prices planes with the triangle cut by
/// each slab, and only the chosen split calls `clip`.
BinaryBvh buildSpatialSplitBvh(std::span<const Bounds3f> primBounds, std::span<const Vec3f> triangles,
                               const ClipToBox& clip, const BvhConfig& config);


}  // namespace tessera
