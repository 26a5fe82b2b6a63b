#pragma once
/// \file primitive_refs.h
/// What our builders see of a scene (madmann91/bvh, Embree's PrimRef): one reference and one box per
/// primitive that can be hit. Shared by the BVH and the k-d tree.
#include <cstdint>
#include <vector>

#include "core/bounds.h"
#include "geometry/shapes.h"

namespace tessera {

/// A primitive as SceneGeometry numbers it (mesh triangle, or sphere with geomId sphereGeomId()).
struct PrimRef {
    uint32_t geomId, primId;
};

/// The build primitives: refs[i] has box bounds[i] (the builders' primitive index i).
struct GatheredPrimitives {
    std::vector<PrimRef> refs;
    std::vector<Bounds3f> bounds;
};

/// Every triangle and sphere that can be hit, in geometry order: triangles with finite vertices
/// (their exact box, or padTriangleBox's with `padTriangles`), spheres with a finite padded box and a
/// positive radius.
GatheredPrimitives gatherPrimitives(const SceneGeometry& geometry, bool padTriangles);

/// The three vertices of triangle `ref` (a mesh primitive).
inline void triangleVertices(const SceneGeometry& g, PrimRef ref, Vec3f (&p)[3]) {
    const TriangleMesh& mesh = g.meshes[ref.geomId];
    const glm::uvec3& t = mesh.triangles[ref.primId];
    p[0] = mesh.positions[t.x], p[1] = mesh.positions[t.y], p[2] = mesh.positions[t.z];
}

/// True when every reference of [first, first + count) of `order` (indices into refs) is a triangle.
inline bool allTriangles(const SceneGeometry& g, const std::vector<PrimRef>& refs, const uint32_t* order, uint32_t count) {
    bool all = true;
    for (uint32_t k = 0; k < count; ++k) all &= refs[order[k]].geomId != g.sphereGeomId();
    return all;
}

}  // namespace tessera
