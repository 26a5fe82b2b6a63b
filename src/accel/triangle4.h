#pragma once
/// \file triangle4.h
/// The leaf kernel shared by our BVH and k-d tree: one ray against four triangles stored as
/// structure of arrays, p[vertex][axis][lane], with the watertight test of Woop, Benthin & Wald
/// 2013 ("Watertight Ray/Triangle Intersection", JCGT 2(1)). The arithmetic repeats
/// intersectTriangle (geometry/intersect.cpp) operation for operation, four lanes at once, so t, u, v
/// are bit-identical to the brute-force backend. Unused lanes hold NaN vertices, which the test
/// rejects without a separate mask.
#include <cstdint>
#include <utility>

#include "accel/bvh_simd.h"
#include "core/ray.h"

namespace tessera {

/// Per-ray constants of the watertight test (paper, Section 3.1), computed once per ray.
struct TriRay {
    int kx, ky, kz;
    float tMin;
    // Splatted once per ray: selecting o[kx] with a run-time index inside every leaf test compiled
    // to a chain of compares and branches ahead of each leaf's first load.
    simd::Vf4 ox, oy, oz, sx, sy, sz;
    explicit TriRay(const Ray& ray) : tMin(ray.tMin) {
        Vec3f ad = glm::abs(ray.d);
        kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
        kx = (kz + 1) % 3;
        ky = (kx + 1) % 3;
        if (ray.d[kz] < 0.f) std::swap(kx, ky);
        sx = simd::splat4(ray.d[kx] / ray.d[kz]);
        sy = simd::splat4(ray.d[ky] / ray.d[kz]);
        sz = simd::splat4(1.f / ray.d[kz]);
        ox = simd::splat4(ray.o[kx]), oy = simd::splat4(ray.o[ky]), oz = simd::splat4(ray.o[kz]);
    }
};

struct TriangleCandidate {
    float t, u, v;
    int lane;  ///< −1: no lane hit
};

/// The nearest lane hit in (tMin, tMax), or lane −1. With `kAnyHit`, any hitting lane (same
/// arithmetic, so the same answer as the closest-hit test), without the serial search for the
/// nearest lane and without barycentrics.
template <bool kAnyHit>
TESSERA_INLINE TriangleCandidate intersectTriangle4(const TriRay& r, const float (&p)[3][3][4], float tMax) {
    using namespace simd;
    const int kx = r.kx, ky = r.ky, kz = r.kz;
    const Vf4 ox = r.ox, oy = r.oy, oz = r.oz, sx = r.sx, sy = r.sy, sz = r.sz;
    Vf4 aX = load4(p[0][kx]) - ox, aY = load4(p[0][ky]) - oy, aZ = load4(p[0][kz]) - oz;
    Vf4 bX = load4(p[1][kx]) - ox, bY = load4(p[1][ky]) - oy, bZ = load4(p[1][kz]) - oz;
    Vf4 cX = load4(p[2][kx]) - ox, cY = load4(p[2][ky]) - oy, cZ = load4(p[2][kz]) - oz;
    Vf4 ax = aX - sx * aZ, ay = aY - sy * aZ;
    Vf4 bx = bX - sx * bZ, by = bY - sy * bZ;
    Vf4 cx = cX - sx * cZ, cy = cY - sy * cZ;
    Vf4 U = cx * by - cy * bx;
    Vf4 V = ax * cy - ay * cx;
    Vf4 W = bx * ay - by * ax;
    Vf4 zero{};
    uint32_t zeroLanes = moveMask4((U == zero) | (V == zero) | (W == zero));
    if (zeroLanes) [[unlikely]] {
        // An edge function is exactly 0: redo it in double precision (paper, Section 3.3), so that
        // edges shared by two triangles are neither missed nor hit twice.
        for (int i = 0; i < 4; ++i) {
            if (!(zeroLanes >> i & 1)) continue;
            U[i] = float(double(cx[i]) * double(by[i]) - double(cy[i]) * double(bx[i]));
            V[i] = float(double(ax[i]) * double(cy[i]) - double(ay[i]) * double(cx[i]));
            W[i] = float(double(bx[i]) * double(ay[i]) - double(by[i]) * double(ax[i]));
        }
    }
    Vi4 sameSign = ((U >= zero) & (V >= zero) & (W >= zero)) | ((U <= zero) & (V <= zero) & (W <= zero));
    Vf4 det = U + V + W;
    Vi4 valid = sameSign & (det != zero);
    if (!moveMask4(valid)) return {0.f, 0.f, 0.f, -1};
    Vf4 T = U * (sz * aZ) + V * (sz * bZ) + W * (sz * cZ);
    Vf4 invDet = splat4(1.f) / det;
    Vf4 t = T * invDet;
    valid &= (t > splat4(r.tMin)) & (t < splat4(tMax));
    uint32_t bits = moveMask4(valid);
    if constexpr (kAnyHit) return {0.f, 0.f, 0.f, bits ? __builtin_ctz(bits) : -1};
    TriangleCandidate best{tMax, 0.f, 0.f, -1};
    while (bits) {
        int i = __builtin_ctz(bits);
        bits &= bits - 1;
        if (t[i] < best.t) best = {t[i], V[i] * invDet[i], W[i] * invDet[i], i};
    }
    return best;
}

}  // namespace tessera
