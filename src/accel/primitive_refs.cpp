#include "accel/primitive_refs.h"

#include "accel/robust_bounds.h"

namespace tessera {

GatheredPrimitives gatherPrimitives(const SceneGeometry& geometry, bool padTriangles) {
    GatheredPrimitives out;
    size_t total = geometry.primitiveCount();
    out.refs.reserve(total);
    out.bounds.reserve(total);
    for (uint32_t g = 0; g < geometry.meshes.size(); ++g) {
        const TriangleMesh& mesh = geometry.meshes[g];
        for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3& t = mesh.triangles[i];
            Bounds3f b;
            b.extend(mesh.positions[t.x]);
            b.extend(mesh.positions[t.y]);
            b.extend(mesh.positions[t.z]);
            if (!finiteBounds(b)) continue;  // a non-finite vertex can never be hit
            out.refs.push_back({g, i});
            out.bounds.push_back(padTriangles ? padTriangleBox(b) : b);
        }
    }
    for (uint32_t i = 0; i < geometry.spheres.size(); ++i) {
        Bounds3f b = paddedSphereBounds(geometry.spheres[i]);
        if (!finiteBounds(b) || !(geometry.spheres[i].radius > 0.f)) continue;
        out.refs.push_back({geometry.sphereGeomId(), i});
        out.bounds.push_back(b);
    }
    return out;
}

}  // namespace tessera
