#pragma once
/// \file triangle_simd.h
/// The leaf kernel of our BVH (4 lanes) and k-d tree (8 lanes): one ray against W triangles stored
/// as structure of arrays, p[vertex][axis][lane], with the watertight test of Woop, Benthin & Wald
/// 2013 ("Watertight Ray/Triangle Intersection", JCGT 2(1)). The arithmetic repeats
/// intersectTriangle (geometry/intersect.cpp) operation for operation, W lanes at once, so t, u, v
/// are bit-identical to the brute-force backend at either width. Unused lanes hold NaN vertices,
/// which the test rejects without a separate mask. Eight lanes are one instruction per step inside
/// `target("avx2")` code and two SSE halves elsewhere.
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "accel/accel_simd.h"
#include "accel/primitive_refs.h"
#include "core/ray.h"
#include "geometry/hit.h"
#include "geometry/intersect.h"

namespace tessera {

/// The vector type and operations of a W-lane kernel.
template <int W>
struct Lanes;
template <>
struct Lanes<4> {
    using F = simd::Vf4;
    using I = simd::Vi4;
    static TESSERA_INLINE F load(const float* p) { return simd::load4(p); }
    static TESSERA_INLINE F splat(float x) { return simd::splat4(x); }
    static TESSERA_INLINE uint32_t mask(I m) { return simd::moveMask4(m); }
};
template <>
struct Lanes<8> {
    using F = simd::Vf8;
    using I = simd::Vi8;
    static TESSERA_INLINE F load(const float* p) { return simd::load8(p); }
    static TESSERA_INLINE F splat(float x) { return simd::splat8(x); }
    static TESSERA_INLINE uint32_t mask(I m) { return simd::moveMask8(m); }
};

/// Per-ray constants of the watertight test (paper, Section 3.1), computed once per ray.
template <int W>
struct TriRayW {
    int kx, ky, kz;
    float tMin;
    // Splatted once per ray: selecting o[kx] with a run-time index inside every leaf test compiled
    // to a chain of compares and branches ahead of each leaf's first load.
    typename Lanes<W>::F ox, oy, oz, sx, sy, sz;
    TESSERA_INLINE explicit TriRayW(const Ray& ray) : tMin(ray.tMin) {
        using L = Lanes<W>;
        // Plain arrays: glm's operator[] with a run-time index compiles to a branch per access.
        const float d[3] = {ray.d.x, ray.d.y, ray.d.z}, o[3] = {ray.o.x, ray.o.y, ray.o.z};
        const WatertightAxes axes = watertightAxes(d);
        kx = axes.kx, ky = axes.ky, kz = axes.kz;
        sx = L::splat(d[kx] / d[kz]);
        sy = L::splat(d[ky] / d[kz]);
        sz = L::splat(1.f / d[kz]);
        ox = L::splat(o[kx]), oy = L::splat(o[ky]), oz = L::splat(o[kz]);
    }
};
using TriRay = TriRayW<4>;
using TriRay8 = TriRayW<8>;

struct TriangleCandidate {
    float t, u, v;
    int lane;  ///< −1: no lane hit
};

/// The nearest lane hit in (tMin, tMax), or lane −1 (among lanes at equal t, the lowest). With
/// `kAnyHit`, any hitting lane (same arithmetic, so the same answer as the closest-hit test),
/// without the serial search for the nearest lane and without barycentrics. Lanes set in
/// `skipLanes` are ignored (the alpha-mask path below; a constant 0 everywhere else, which folds away).
template <int W, bool kAnyHit>
TESSERA_INLINE TriangleCandidate intersectTriangles(const TriRayW<W>& r, const float (&p)[3][3][W], float tMax,
                                                    uint32_t skipLanes = 0) {
    using L = Lanes<W>;
    using F = typename L::F;
    using I = typename L::I;
    const int kx = r.kx, ky = r.ky, kz = r.kz;
    const F ox = r.ox, oy = r.oy, oz = r.oz, sx = r.sx, sy = r.sy, sz = r.sz;
    F aX = L::load(p[0][kx]) - ox, aY = L::load(p[0][ky]) - oy, aZ = L::load(p[0][kz]) - oz;
    F bX = L::load(p[1][kx]) - ox, bY = L::load(p[1][ky]) - oy, bZ = L::load(p[1][kz]) - oz;
    F cX = L::load(p[2][kx]) - ox, cY = L::load(p[2][ky]) - oy, cZ = L::load(p[2][kz]) - oz;
    F ax = aX - sx * aZ, ay = aY - sy * aZ;
    F bx = bX - sx * bZ, by = bY - sy * bZ;
    F cx = cX - sx * cZ, cy = cY - sy * cZ;
    F U = cx * by - cy * bx;
    F V = ax * cy - ay * cx;
    F Wf = bx * ay - by * ax;
    F zero{};
    uint32_t zeroLanes = L::mask((U == zero) | (V == zero) | (Wf == zero));
    if (zeroLanes) [[unlikely]] {
        // An edge function is exactly 0: redo it in double precision (paper, Section 3.3), so that
        // edges shared by two triangles are neither missed nor hit twice.
        for (int i = 0; i < W; ++i) {
            if (!(zeroLanes >> i & 1)) continue;
            U[i] = float(double(cx[i]) * double(by[i]) - double(cy[i]) * double(bx[i]));
            V[i] = float(double(ax[i]) * double(cy[i]) - double(ay[i]) * double(cx[i]));
            Wf[i] = float(double(bx[i]) * double(ay[i]) - double(by[i]) * double(ax[i]));
        }
    }
    I sameSign = ((U >= zero) & (V >= zero) & (Wf >= zero)) | ((U <= zero) & (V <= zero) & (Wf <= zero));
    F det = U + V + Wf;
    I valid = sameSign & (det != zero);
    // The closest-hit test leaves here when no lane can hit (it saves the division); the any-hit
    // test goes straight on to its single final branch: there this exit is mispredicted more often
    // than the division costs.
    if constexpr (!kAnyHit)
        if (!L::mask(valid)) return {0.f, 0.f, 0.f, -1};
    F T = U * (sz * aZ) + V * (sz * bZ) + Wf * (sz * cZ);
    F invDet = L::splat(1.f) / det;
    F t = T * invDet;
    valid &= (t > L::splat(r.tMin)) & (t < L::splat(tMax));
    uint32_t bits = L::mask(valid) & ~skipLanes;
    if constexpr (kAnyHit) return {0.f, 0.f, 0.f, bits ? __builtin_ctz(bits) : -1};
    TriangleCandidate best{tMax, 0.f, 0.f, -1};
    while (bits) {
        int i = __builtin_ctz(bits);
        bits &= bits - 1;
        if (t[i] < best.t) best = {t[i], V[i] * invDet[i], Wf[i] * invDet[i], i};
    }
    return best;
}

/// intersectTriangles for a block holding cut-out triangles (geometry/alpha_mask.h): a lane counts
/// only where `keep(lane, u, v)` says so. The block is tested again without each rejected lane, so
/// a rejected lane never hides the next-nearest hit behind it; the answer is the nearest kept lane
/// (lowest lane among equal t, as intersectTriangles), or lane −1. Any-hit queries ask it too, so
/// they keep and drop the same lanes, with the same barycentrics, as closest-hit ones. Called only
/// on a masked triangle's hit: unmasked geometry never runs it.
template <int W, class Keep>
inline TriangleCandidate intersectTrianglesFiltered(const TriRayW<W>& r, const float (&p)[3][3][W], float tMax, const Keep& keep) {
    uint32_t rejected = 0;
    while (true) {
        TriangleCandidate c = intersectTriangles<W, false>(r, p, tMax, rejected);
        if (c.lane < 0 || keep(c.lane, c.u, c.v)) return c;
        rejected |= 1u << c.lane;
    }
}

/// Fills the W lanes of a leaf block, p[vertex][axis][lane], with the vertices of `count` ≤ W
/// triangles `refs[order[0 .. count)]`; the remaining lanes get NaN vertices, which the test
/// rejects (no lane mask needed).
template <int W>
inline void fillTriangleLanes(const SceneGeometry& g, const std::vector<PrimRef>& refs, const uint32_t* order,
                              uint32_t count, float (&p)[3][3][W]) {
    for (int lane = 0; lane < W; ++lane) {
        Vec3f v[3] = {Vec3f(std::numeric_limits<float>::quiet_NaN()), Vec3f(std::numeric_limits<float>::quiet_NaN()),
                      Vec3f(std::numeric_limits<float>::quiet_NaN())};
        if (uint32_t(lane) < count) triangleVertices(g, refs[order[lane]], v);
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) p[k][a][lane] = v[k][a];
    }
}

/// The hit record of lane `lane` of a leaf block hit at (t, u, v): the normal from the block's own
/// vertices, as every backend computes it (accel.h).
template <int W>
TESSERA_INLINE void triangleHitRecord(const float (&p)[3][3][W], int lane, float t, float u, float v, PrimRef id, Hit& hit) {
    Vec3f q[3];
    for (int k = 0; k < 3; ++k) q[k] = {p[k][0][lane], p[k][1][lane], p[k][2][lane]};
    hit.t = t, hit.u = u, hit.v = v;
    hit.geomId = id.geomId;
    hit.primId = id.primId;
    hit.ng = glm::normalize(glm::cross(q[1] - q[0], q[2] - q[0]));
}

}  // namespace tessera
