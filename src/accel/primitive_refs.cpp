#include "accel/primitive_refs.h"

#include "accel/robust_bounds.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>

namespace tessera {

GatheredPrimitives gatherPrimitives(const SceneGeometry& geometry, bool padTriangles) {
    GatheredPrimitives out;
    size_t triangles = 0;
    for (const TriangleMesh& mesh : geometry.meshes) triangles += mesh.triangles.size();
    out.refs.resize(triangles);
    out.bounds.resize(triangles);
    // Every triangle's box in parallel, in place; a triangle with a non-finite vertex (it can
    // never be hit) is marked and dropped afterwards, keeping the order.
    std::atomic<bool> anyNonFinite{false};
    size_t offset = 0;
    for (uint32_t g = 0; g < geometry.meshes.size(); ++g) {
        const TriangleMesh& mesh = geometry.meshes[g];
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, uint32_t(mesh.triangles.size()), 8192),
                          [&](const tbb::blocked_range<uint32_t>& range) {
                              bool nonFinite = false;
                              for (uint32_t i = range.begin(); i != range.end(); ++i) {
                                  const glm::uvec3& t = mesh.triangles[i];
                                  Bounds3f b;
                                  b.extend(mesh.positions[t.x]);
                                  b.extend(mesh.positions[t.y]);
                                  b.extend(mesh.positions[t.z]);
                                  bool finite = finiteBounds(b);
                                  nonFinite |= !finite;
                                  out.refs[offset + i] = {finite ? g : kInvalidId, i};
                                  out.bounds[offset + i] = padTriangles && finite ? padTriangleBox(b) : b;
                              }
                              if (nonFinite) anyNonFinite.store(true, std::memory_order_relaxed);
                          });
        offset += mesh.triangles.size();
    }
    if (anyNonFinite.load()) {
        size_t kept = 0;
        for (size_t i = 0; i < triangles; ++i)
            if (out.refs[i].geomId != kInvalidId) out.refs[kept] = out.refs[i], out.bounds[kept] = out.bounds[i], ++kept;
        out.refs.resize(kept);
        out.bounds.resize(kept);
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
