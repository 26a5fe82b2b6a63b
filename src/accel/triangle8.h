#pragma once
/// \file triangle8.h
/// The k-d tree's leaf kernel: one ray against eight triangles stored as structure of arrays,
/// p[vertex][axis][lane], with the watertight test of Woop, Benthin & Wald 2013 ("Watertight
/// Ray/Triangle Intersection", JCGT 2(1)). Operation for operation the 4-wide kernel of
/// triangle4.h (and so bit-identical to intersectTriangle in geometry/intersect.cpp), eight lanes
/// at once: one instruction per step inside `target("avx2")` code, two SSE halves elsewhere (the
/// portable path). Unused lanes hold NaN vertices, which the test rejects without a mask.
#include <cstdint>
#include <utility>

#include "accel/bvh_simd.h"
#include "core/ray.h"

namespace tessera {

/// Per-ray constants of the watertight test (paper, Section 3.1), splatted to eight lanes once.
struct TriRay8 {
    int kx, ky, kz;
    float tMin;
    simd::Vf8 ox, oy, oz, sx, sy, sz;
    TESSERA_INLINE explicit TriRay8(const Ray& ray) : tMin(ray.tMin) {
        Vec3f ad = glm::abs(ray.d);
        kz = ad.x > ad.y ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
        kx = (kz + 1) % 3;
        ky = (kx + 1) % 3;
        if (ray.d[kz] < 0.f) std::swap(kx, ky);
        sx = simd::splat8(ray.d[kx] / ray.d[kz]);
        sy = simd::splat8(ray.d[ky] / ray.d[kz]);
        sz = simd::splat8(1.f / ray.d[kz]);
        ox = simd::splat8(ray.o[kx]), oy = simd::splat8(ray.o[ky]), oz = simd::splat8(ray.o[kz]);
    }
};

struct Triangle8Candidate {
    float t, u, v;
    int lane;  ///< −1: no lane hit
};

/// The nearest lane hit in (tMin, tMax), or lane −1. With `kAnyHit`, any hitting lane (same
/// arithmetic, so the same answer as the closest-hit test) without the search for the nearest.
template <bool kAnyHit>
TESSERA_INLINE Triangle8Candidate intersectTriangle8(const TriRay8& r, const float (&p)[3][3][8], float tMax) {
    using namespace simd;
    const int kx = r.kx, ky = r.ky, kz = r.kz;
    const Vf8 ox = r.ox, oy = r.oy, oz = r.oz, sx = r.sx, sy = r.sy, sz = r.sz;
    Vf8 aX = load8(p[0][kx]) - ox, aY = load8(p[0][ky]) - oy, aZ = load8(p[0][kz]) - oz;
    Vf8 bX = load8(p[1][kx]) - ox, bY = load8(p[1][ky]) - oy, bZ = load8(p[1][kz]) - oz;
    Vf8 cX = load8(p[2][kx]) - ox, cY = load8(p[2][ky]) - oy, cZ = load8(p[2][kz]) - oz;
    Vf8 ax = aX - sx * aZ, ay = aY - sy * aZ;
    Vf8 bx = bX - sx * bZ, by = bY - sy * bZ;
    Vf8 cx = cX - sx * cZ, cy = cY - sy * cZ;
    Vf8 U = cx * by - cy * bx;
    Vf8 V = ax * cy - ay * cx;
    Vf8 W = bx * ay - by * ax;
    Vf8 zero{};
    uint32_t zeroLanes = moveMask8((U == zero) | (V == zero) | (W == zero));
    if (zeroLanes) [[unlikely]] {
        // An edge function is exactly 0: redo it in double precision (paper, Section 3.3), so that
        // edges shared by two triangles are neither missed nor hit twice.
        for (int i = 0; i < 8; ++i) {
            if (!(zeroLanes >> i & 1)) continue;
            U[i] = float(double(cx[i]) * double(by[i]) - double(cy[i]) * double(bx[i]));
            V[i] = float(double(ax[i]) * double(cy[i]) - double(ay[i]) * double(cx[i]));
            W[i] = float(double(bx[i]) * double(ay[i]) - double(by[i]) * double(ax[i]));
        }
    }
    Vi8 sameSign = ((U >= zero) & (V >= zero) & (W >= zero)) | ((U <= zero) & (V <= zero) & (W <= zero));
    Vf8 det = U + V + W;
    Vi8 valid = sameSign & (det != zero);
    if (!moveMask8(valid)) return {0.f, 0.f, 0.f, -1};
    Vf8 T = U * (sz * aZ) + V * (sz * bZ) + W * (sz * cZ);
    Vf8 invDet = splat8(1.f) / det;
    Vf8 t = T * invDet;
    valid &= (t > splat8(r.tMin)) & (t < splat8(tMax));
    uint32_t bits = moveMask8(valid);
    if constexpr (kAnyHit) return {0.f, 0.f, 0.f, bits ? __builtin_ctz(bits) : -1};
    Triangle8Candidate best{tMax, 0.f, 0.f, -1};
    while (bits) {
        int i = __builtin_ctz(bits);
        bits &= bits - 1;
        if (t[i] < best.t) best = {t[i], V[i] * invDet[i], W[i] * invDet[i], i};
    }
    return best;
}

}  // namespace tessera
