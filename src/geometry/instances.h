#pragma once
/// \file instances.h
/// Mesh instances (SceneGeometry::prototypes placed by SceneGeometry::instances): the one home of
/// each transform that backends and the scene apply, so that every structure computes the same
/// object-space ray and world-space normal bit for bit; and the flattened copy of an instanced
/// scene that the validator and the benchmark compare against.
/// The functions are out of line on purpose: compiled once, without the AVX2 flags of the kernel
/// sources, so no structure gets other rounding from contracted multiply-adds.
#include <vector>

#include "core/bounds.h"
#include "core/ray.h"
#include "geometry/hit.h"
#include "geometry/shapes.h"

namespace tessera {

/// The instance of `prototype` at `objectToWorld`, its inverse computed in double precision. False
/// (and `out` untouched) when the transform is singular or not finite: such an instance is empty.
bool makeMeshInstance(uint32_t prototype, const Mat4d& objectToWorld, MeshInstance& out);

/// The world-space ray in the instance's object space. t is unchanged: the direction is transformed
/// without normalising, so a hit at t in object space is at t along the world ray.
Ray rayToObject(const MeshInstance& inst, const Ray& worldRay);
Vec3f instancePointToWorld(const MeshInstance& inst, const Vec3f& p);
/// An object-space normal in world space by the inverse transpose, normalised; (0, 0, 0) where
/// degenerate.
Vec3f instanceNormalToWorld(const MeshInstance& inst, const Vec3f& n);
/// An object-space tangent (xyz unit, w = ±1 bitangent sign) in world space: xyz transformed as a
/// vector and normalised ((0, 0, 0) where degenerate), w flipped by a mirroring transform (the
/// bitangent is w · N × T with N and T both mapped).
Vec4f instanceTangentToWorld(const MeshInstance& inst, const Vec4f& t);
/// The world box of the object-space box `objectBox`: its eight corners transformed, padded by a
/// few ulps of its magnitude so that rounding of the object-space ray never loses a hit.
Bounds3f instanceWorldBounds(const MeshInstance& inst, const Bounds3f& objectBox);
/// The transform mirrors (negative determinant).
bool instanceMirrors(const MeshInstance& inst);

/// The flattened copy of an instanced scene: the flat meshes, then for each instance in order its
/// prototype's meshes transformed to world space (positions, normals by the inverse transpose,
/// tangents; a mirroring transform gets its winding flipped back, as the glTF loader does), then
/// the spheres. `toFlat` maps a hit record of the instanced scene to the copy's numbering.
class InstanceFlattening {
public:
    explicit InstanceFlattening(const SceneGeometry& instanced);
    SceneGeometry flatten() const;
    Hit toFlat(const Hit& hit) const;
    /// The geomId in the copy of mesh `geomId` of instance `instId`.
    uint32_t flatGeomId(uint32_t instId, uint32_t geomId) const { return firstMesh_[instId] + geomId; }

private:
    const SceneGeometry& g_;
    std::vector<uint32_t> firstMesh_;  ///< per instance: the copy's geomId of its prototype's mesh 0
    uint32_t meshCount_ = 0;           ///< meshes of the copy (its sphere geomId)
};

}  // namespace tessera
