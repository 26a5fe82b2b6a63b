#pragma once
/// \file mixed_leaf.h
/// Leaves that hold spheres (and the triangles sharing a leaf with them) are tested one primitive
/// at a time with the scalar reference tests of geometry/intersect.h, the same ones the brute-force
/// and Embree backends use, so their hit records match exactly. Shared by the BVH and the k-d tree.
#include <cstdint>

#include "accel/accel.h"
#include "accel/primitive_refs.h"
#include "geometry/alpha_mask.h"
#include "geometry/intersect.h"

namespace tessera {

/// The closest hit so far among mixed-leaf primitives (geomId kInvalidId: none).
struct MixedCandidate {
    uint32_t geomId = kInvalidId, primId = kInvalidId;
    float u = 0.f, v = 0.f;  ///< triangles only: barycentrics
};

/// Tests `count` primitives against (ray.tMin, tHit). On a closer hit updates tHit and `best` and
/// returns true; with kAnyHit returns true at the first hit. With kMasked (scenes with cut-outs),
/// hits that a triangle's alpha mask drops do not count; without it masks are not looked at.
template <bool kAnyHit, bool kMasked>
inline bool intersectMixedLeaf(const SceneGeometry& g, const Ray& ray, const PrimRef* prims, uint32_t count, float& tHit,
                               MixedCandidate& best) {
    bool found = false;
    Ray clipped = ray;
    for (uint32_t k = 0; k < count; ++k) {
        clipped.tMax = tHit;
        const PrimRef& p = prims[k];
        if (p.geomId == g.sphereGeomId()) {
            const Sphere& s = g.spheres[p.primId];
            double t = intersectSphere(s.center, s.radius, clipped);
            if (t < 0.0 || !(float(t) < tHit)) continue;
            if constexpr (kAnyHit) return true;
            tHit = float(t);
            best = {p.geomId, p.primId, 0.f, 0.f};
        } else {
            const TriangleMesh& mesh = g.meshes[p.geomId];
            const glm::uvec3& tri = mesh.triangles[p.primId];
            TriangleHit th;
            if (!intersectTriangle(clipped, mesh.positions[tri.x], mesh.positions[tri.y], mesh.positions[tri.z], th)) continue;
            if constexpr (kMasked)
                if (mesh.alphaMask && !alphaMaskKeeps(mesh, p.primId, th.u, th.v)) continue;  // a cut-out's hole
            if constexpr (kAnyHit) return true;
            tHit = th.t;
            best = {p.geomId, p.primId, th.u, th.v};
        }
        found = true;
    }
    return found;
}

/// The hit record of sphere `primId` hit at distance t (already rounded to float): normal and (u, v)
/// computed once, for the closest hit only, by every backend alike (the search itself needs only t).
inline void sphereHitRecord(const SceneGeometry& g, const Ray& ray, uint32_t primId, float t, Hit& hit) {
    const Sphere& s = g.spheres[primId];
    Vec3f n = sphereHitNormal(s.center, ray, t);
    Vec2f uv = sphereUv(n);
    hit.t = t;
    hit.u = uv.x, hit.v = uv.y;
    hit.geomId = g.sphereGeomId();
    hit.primId = primId;
    hit.ng = n;
}

/// The closest of all of `g`'s spheres along `ray`, tested one by one (brute force, and the Embree
/// backend's few spheres): returns its index, kInvalidId if none, and lowers ray.tMax to its t. A t
/// below tMax in double may still round up to tMax: every backend then skips it.
inline uint32_t closestSphereInLoop(const SceneGeometry& g, Ray& ray) {
    uint32_t closest = kInvalidId;
    for (uint32_t i = 0; i < g.spheres.size(); ++i) {
        double t = intersectSphere(g.spheres[i].center, g.spheres[i].radius, ray);
        if (t < 0.0 || !(float(t) < ray.tMax)) continue;
        ray.tMax = float(t);
        closest = i;
    }
    return closest;
}

/// Whether any of `g`'s spheres blocks `ray`, tested one by one.
inline bool anySphereInLoopOccludes(const SceneGeometry& g, const Ray& ray) {
    for (const Sphere& s : g.spheres) {
        double t = intersectSphere(s.center, s.radius, ray);
        if (t >= 0.0 && float(t) < ray.tMax) return true;
    }
    return false;
}

/// The hit record of a mixed-leaf candidate hit at distance t.
inline void mixedHitRecord(const SceneGeometry& g, const Ray& ray, const MixedCandidate& c, float t, Hit& hit) {
    if (c.geomId == g.sphereGeomId()) return sphereHitRecord(g, ray, c.primId, t, hit);
    hit.t = t;
    hit.geomId = c.geomId;
    hit.primId = c.primId;
    const TriangleMesh& mesh = g.meshes[c.geomId];
    const glm::uvec3& tri = mesh.triangles[c.primId];
    const Vec3f &p0 = mesh.positions[tri.x], &p1 = mesh.positions[tri.y], &p2 = mesh.positions[tri.z];
    hit.u = c.u, hit.v = c.v;
    hit.ng = glm::normalize(glm::cross(p1 - p0, p2 - p0));
}

}  // namespace tessera
