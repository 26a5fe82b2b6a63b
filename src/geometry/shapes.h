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

/// Everything an acceleration structure sees. Geometry ids: mesh i has geomId i; all spheres together
/// form geometry `meshes.size()` with primId = sphere index (this is also how Embree numbers them).
struct SceneGeometry {
    std::vector<TriangleMesh> meshes;
    std::vector<Sphere> spheres;
    /// The decoded images the meshes' alpha masks point into, for geometry that outlives the Scene
    /// that loaded it (loadGeometryFile: validate-accel, bench-accel, the API's geometry loads).
    /// Null inside a Scene, which owns its images itself.
    std::shared_ptr<const std::vector<std::unique_ptr<Image>>> maskImages;

    uint32_t sphereGeomId() const { return uint32_t(meshes.size()); }
    size_t primitiveCount() const;
    Bounds3f bounds() const;
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
