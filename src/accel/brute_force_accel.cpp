#include "accel/brute_force_accel.h"

#include "accel/mixed_leaf.h"
#include "geometry/alpha_mask.h"
#include "geometry/intersect.h"

namespace tessera {

BruteForceAccel::BruteForceAccel(const SceneGeometry& geometry) : geometry_(geometry), bounds_(geometry.bounds()) {}

bool BruteForceAccel::intersect(const Ray& rayIn, Hit& hit) const {
    if (!isTraceableRay(rayIn)) return false;
    Ray ray = rayIn;
    bool found = false;
    for (uint32_t g = 0; g < geometry_.meshes.size(); ++g) {
        const TriangleMesh& mesh = geometry_.meshes[g];
        for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3& tri = mesh.triangles[i];
            const Vec3f &p0 = mesh.positions[tri.x], &p1 = mesh.positions[tri.y], &p2 = mesh.positions[tri.z];
            TriangleHit th;
            if (!intersectTriangle(ray, p0, p1, p2, th)) continue;
            if (mesh.alphaMask && !alphaMaskKeeps(mesh, i, th.u, th.v)) continue;  // a cut-out's hole
            ray.tMax = th.t;
            hit.t = th.t;
            hit.u = th.u;
            hit.v = th.v;
            hit.geomId = g;
            hit.primId = i;
            hit.ng = glm::normalize(glm::cross(p1 - p0, p2 - p0));
            found = true;
        }
    }
    uint32_t closestSphere = closestSphereInLoop(geometry_, ray);
    if (closestSphere != kInvalidId) {
        sphereHitRecord(geometry_, ray, closestSphere, ray.tMax, hit);
        found = true;
    }
    return found;
}

bool BruteForceAccel::occluded(const Ray& ray) const {
    if (!isTraceableRay(ray)) return false;
    for (const TriangleMesh& mesh : geometry_.meshes) {
        for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3& tri = mesh.triangles[i];
            TriangleHit th;
            if (intersectTriangle(ray, mesh.positions[tri.x], mesh.positions[tri.y], mesh.positions[tri.z], th) &&
                (!mesh.alphaMask || alphaMaskKeeps(mesh, i, th.u, th.v)))
                return true;
        }
    }
    return anySphereInLoopOccludes(geometry_, ray);
}

AccelStats BruteForceAccel::stats() const {
    AccelStats s;
    s.primitives = geometry_.primitiveCount();
    return s;
}

}  // namespace tessera
