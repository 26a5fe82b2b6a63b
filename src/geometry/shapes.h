#pragma once
/// \file shapes.h
/// The two shapes Tessera models: triangle meshes and analytic spheres, both in world space, and the
/// SceneGeometry that every acceleration structure is built from.
#include <glm/vec3.hpp>
#include <memory>
#include <string>
#include <vector>

#include "core/bounds.h"
#include "core/math.h"
#include "geometry/alpha_mask.h"

namespace tessera {

inline constexpr uint32_t kInvalidId = 0xffffffffu;

struct TriangleMesh {
    std::string name;               ///< for messages, e.g. "meshes[2].primitives[0]"
    std::vector<Vec3f> positions;   ///< world space
    std::vector<Vec3f> normals;     ///< optional per-vertex shading normals (world space, unit)
    std::vector<glm::uvec3> triangles;
    uint32_t materialId = 0;
    std::vector<Vec2f> texcoords[2];  ///< optional TEXCOORD_0 / TEXCOORD_1 per vertex
    std::vector<Vec4f> tangents;      ///< optional per-vertex tangents (world xyz, unit; w = ±1 bitangent sign)
    std::shared_ptr<const AlphaMask> alphaMask;  ///< set for cut-out materials: hits are filtered by it

    bool hasTexcoords(int set) const { return !texcoords[set].empty(); }
    /// TEXCOORD_`set` interpolated at barycentrics (u, v) of triangle `primId` (u, v weigh vertices
    /// 1 and 2, as in Hit); (0, 0) when the mesh has no such set. The one interpolation that alpha
    /// masks, material textures and textured emitters share.
    Vec2f texcoordAt(int set, uint32_t primId, float u, float v) const {
        const std::vector<Vec2f>& uv = texcoords[set];
        if (uv.empty()) return Vec2f(0.f);
        const glm::uvec3& t = triangles[primId];
        return (1.f - u - v) * uv[t.x] + u * uv[t.y] + v * uv[t.z];
    }
};

struct Sphere {
    std::string name;
    Vec3f center{0.f};
    float radius = 1.f;
    uint32_t materialId = 0;
};

/// One placement of a prototype (SceneGeometry::prototypes): object-to-world affine transform and
/// its inverse (computed in double precision, then rounded; geometry/instances.h builds them).
struct MeshInstance {
    uint32_t prototype = 0;
    Mat4f objectToWorld{1.f};
    Mat4f worldToObject{1.f};
};

/// Everything an acceleration structure sees. Geometry ids: mesh i has geomId i; all spheres together
/// form geometry `meshes.size()` with primId = sphere index (this is also how Embree numbers them).
/// Instanced meshes (two-level structures): `prototypes` hold object-space meshes stored once (no
/// spheres, no nested instances), `instances` place them; a hit on one carries instId = the
/// instance's index and geomId/primId of the prototype's mesh and triangle (geometry/hit.h).
struct SceneGeometry {
    std::vector<TriangleMesh> meshes;
    std::vector<Sphere> spheres;
    std::vector<SceneGeometry> prototypes;
    std::vector<MeshInstance> instances;
    /// The decoded images the meshes' alpha masks point into, for geometry that outlives the Scene
    /// that loaded it (loadGeometryFile: validate-accel, bench-accel, the API's geometry loads).
    /// Null inside a Scene, which owns its images itself.
    std::shared_ptr<const std::vector<std::unique_ptr<Image>>> maskImages;

    uint32_t sphereGeomId() const { return uint32_t(meshes.size()); }
    /// Primitives of the flat geometry (meshes and spheres) that one structure over it holds.
    size_t primitiveCount() const;
    /// Triangles the instances place, counted once per instance (what flattening would store).
    size_t instancedPrimitiveCount() const;
    /// The box of everything, instances included (each by its prototype's box transformed).
    Bounds3f bounds() const;
    /// The mesh of a hit with ids (geomId, instId) as in Hit; null for a sphere.
    const TriangleMesh* meshOf(uint32_t geomId, uint32_t instId) const {
        if (instId != kInvalidId) return &prototypes[instances[instId].prototype].meshes[geomId];
        return geomId < meshes.size() ? &meshes[geomId] : nullptr;
    }
};

inline Bounds3f sphereBounds(const Sphere& s) {
    Bounds3f b;
    b.lower = s.center - Vec3f(s.radius);
    b.upper = s.center + Vec3f(s.radius);
    return b;
}

/// The box our structures and the Embree backend give a sphere: float rounding of centre ± radius
/// must never cut off part of it, so it is padded relative to the sphere's magnitude.
inline Bounds3f paddedSphereBounds(const Sphere& s) {
    float pad = 1e-6f * (s.radius + maxComponent(glm::abs(s.center)));
    Bounds3f b = sphereBounds(s);
    b.lower -= Vec3f(pad);
    b.upper += Vec3f(pad);
    return b;
}

/// Finite and not empty: a primitive with such a box can be hit.
inline bool finiteBounds(const Bounds3f& b) { return isFinite(b.lower) && isFinite(b.upper) && !b.empty(); }

}  // namespace tessera
