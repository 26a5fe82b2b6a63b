/// \file bvh_traversal.cpp
/// The BVH's traversal kernels: closest hit (nearest-first, with a branch-free path for incoherent
/// rays and a branching one for coherent rays) and any hit (unordered), each compiled for the
/// default target and for AVX2 (kernel_isa.h), and once more with the alpha-mask test of cut-out
/// triangles (kMasked) for scenes that have them.
#include <cmath>
#include <cstring>

#include "accel/accel_simd.h"
#include "accel/bvh_accel.h"
#include "accel/mixed_leaf.h"
#include "accel/robust_bounds.h"
#include "accel/triangle_simd.h"
#include "geometry/alpha_mask.h"

namespace tessera {

using namespace simd;

namespace {

/// Traversal stack size: the builder bounds the binary depth (maxSahDepth + log2 N ≤ 80), each BVH8
/// level pushes at most 7 entries.
constexpr int kStackSize = 1024;

struct StackEntry {
    uint32_t ref;
    float tNear;
};

/// Orders two entries farther first (ties keep their order), with selects instead of a branch.
TESSERA_INLINE void farFirst(StackEntry& a, StackEntry& b) {
    bool keep = a.tNear >= b.tNear;
    StackEntry far = keep ? a : b, near = keep ? b : a;
    a = far, b = near;
}

/// Per-ray constants of the box test (Ize 2013, "Robust BVH Ray Traversal", JCGT 2(2), Section 3):
/// tNear uses 1/d rounded normally and tFar uses 1/d enlarged by 2 ulps, which makes the slab test
/// conservative despite rounding. Octant from the sign of 1/d, so −0.0 picks the far side correctly.
struct BoxRay {
    Vf8 ox, oy, oz, rdxNear, rdyNear, rdzNear, rdxFar, rdyFar, rdzFar, tMin;
    int nearX, nearY, nearZ, farX, farY, farZ;  ///< row offsets into Node8::bounds

    explicit BoxRay(const Ray& ray) {
        Vec3f rd, rdFar;
        for (int a = 0; a < 3; ++a) {
            rd[a] = 1.f / ray.d[a];  // ±inf for ±0.0: the NaN-aware min/max handle 0 · inf
            rdFar[a] = twoUlpsLarger(rd[a]);
        }
        ox = splat8(ray.o.x), oy = splat8(ray.o.y), oz = splat8(ray.o.z);
        rdxNear = splat8(rd.x), rdyNear = splat8(rd.y), rdzNear = splat8(rd.z);
        rdxFar = splat8(rdFar.x), rdyFar = splat8(rdFar.y), rdzFar = splat8(rdFar.z);
        tMin = splat8(ray.tMin);
        nearX = std::signbit(rd.x) ? 3 : 0;
        nearY = std::signbit(rd.y) ? 4 : 1;
        nearZ = std::signbit(rd.z) ? 5 : 2;
        farX = 3 - nearX, farY = 5 - nearY, farZ = 7 - nearZ;
    }

    /// Entry distances of the eight children and the mask of those the ray enters before
    /// `tMaxPadded` (splat8(padUp(tMax)), kept by the caller: recomputing it cost 7 instructions per
    /// node).
    TESSERA_INLINE Vi8 test(const BvhAccel::Node8& n, Vf8 tMaxPadded, Vf8& tNear) const {
        Vf8 txN = (load8(n.bounds[nearX]) - ox) * rdxNear;
        Vf8 tyN = (load8(n.bounds[nearY]) - oy) * rdyNear;
        Vf8 tzN = (load8(n.bounds[nearZ]) - oz) * rdzNear;
        Vf8 txF = (load8(n.bounds[farX]) - ox) * rdxFar;
        Vf8 tyF = (load8(n.bounds[farY]) - oy) * rdyFar;
        Vf8 tzF = (load8(n.bounds[farZ]) - oz) * rdzFar;
        // Two levels instead of a chain of three (the box test's latency sits between a node and
        // the next). A NaN slab (origin in the slab plane of a zero direction component) in the
        // first operand is skipped; one from tzN/tzF makes its pair NaN, and the pair is then
        // skipped too, which only loosens the test (never culls a box the ray enters).
        tNear = maxNanB(maxNanB(tyN, tzN), maxNanB(txN, tMin));
        Vf8 tFar = minNanB(minNanB(tyF, tzF), minNanB(txF, tMaxPadded));
        return tNear <= tFar;
    }
};

TESSERA_INLINE TriangleCandidate intersectTriangle4(const TriRay& r, const BvhAccel::Triangle4& tri, float tMax) {
    return intersectTriangles<4, false>(r, tri.p, tMax);
}
/// A lane the ray hits (any), or −1.
TESSERA_INLINE int occludedTriangle4(const TriRay& r, const BvhAccel::Triangle4& tri, float tMax) {
    return intersectTriangles<4, true>(r, tri.p, tMax).lane;
}

}  // namespace

// Out of line: the slow path of cut-out leaves stays out of the kernels' hot loops.
__attribute__((noinline)) TriangleCandidate BvhAccel::filterMaskedLanes(const TriRay& r, const Triangle4& tri, float tMax) const {
    auto keep = [&](int lane, float u, float v) {
        uint32_t geomId = tri.geomId[lane];
        return !(geomId & kMaskedLaneBit) || alphaMaskKeeps(geometry_.meshes[geomId & ~kMaskedLaneBit], tri.primId[lane], u, v);
    };
    return intersectTrianglesFiltered<4>(r, tri.p, tMax, keep);
}

/// Starts loading a child the ray will (probably) visit: the traversal is bound by cache misses on
/// incoherent rays (a node is 3.5 lines, a leaf block 2.75), and issuing every hit child's lines at
/// once overlaps their latencies instead of paying them one after another.
TESSERA_INLINE void BvhAccel::prefetchChild(uint32_t ref) const {
    const char* p;
    int lines;
    if (!(ref & kLeafBit)) p = reinterpret_cast<const char*>(&node(ref)), lines = 4;
    else if (!(ref & kMixedBit)) p = reinterpret_cast<const char*>(leafBlocks(ref)), lines = 3 * (int(ref & 3u) + 1);
    else return;
    for (int l = 0; l < lines; ++l) __builtin_prefetch(p + 64 * l);
}

/// prefetchChild without branches (four lines wherever the reference points; prefetches never
/// fault, so a sphere leaf's reference, which is no address, is harmless).
TESSERA_INLINE void BvhAccel::prefetchAny(uint32_t ref) const {
    const char* p = (ref & kLeafBit) ? reinterpret_cast<const char*>(leafBlocks(ref)) : reinterpret_cast<const char*>(&node(ref));
    for (int l = 0; l < 4; ++l) __builtin_prefetch(p + 64 * l);
}

template <bool kAvx, bool kCoherent, bool kMasked>
TESSERA_INLINE bool BvhAccel::intersectImpl(const Ray& ray, Hit& hit) const {
    if (nodes_.empty() || !isTraceableRay(ray)) return false;
    BoxRay boxRay(ray);
    TriRay triRay(ray);
    float tMax = ray.tMax;
    Vf8 tMaxPadded = splat8(padUp(tMax));
    const Triangle4* bestBlock = nullptr;
    int bestLane = -1;
    MixedCandidate bestMixed;
    float bestU = 0.f, bestV = 0.f;

    StackEntry stack[kStackSize];
    int sp = 0;
    uint32_t ref = 0;
    while (true) {
        if (!(ref & kLeafBit)) {
            const Node8& node = this->node(ref);
            Vf8 tNear;
            uint32_t mask = moveMask8Isa<kAvx>(boxRay.test(node, tMaxPadded, tNear));
            if (mask) {
                // Nearest-first: the hit children in far-to-near order, all but the nearest pushed.
                // The number of hit children decides the path (one: 58% of the nodes a diffuse ray
                // on the dragon tests, two: 20%, three: 5%, more: 2%; none: 15%), and for incoherent
                // rays that branch is a coin toss on the way to the next node's load.
                int i0 = __builtin_ctz(mask);
                if constexpr (!kCoherent) {
                    // Incoherent rays: one and two children share one branch-free path. With one,
                    // the "second" (the highest hit lane) is the first again and the push is not
                    // kept. The far child's lines are fetched while the near subtree is walked.
                    int i1 = 31 - __builtin_clz(mask);
                    StackEntry e0{node.child[i0], tNear[i0]}, e1{node.child[i1], tNear[i1]};
                    farFirst(e0, e1);
                    stack[sp] = e0;
                    sp += i1 != i0;
                    ref = e1.ref;
                    if (!(mask & ~((1u << i0) | (1u << i1)))) {
                        prefetchAny(e0.ref);
                        continue;
                    }
                    // Three or more: undone, and ordered below exactly as the coherent kernel
                    // orders them (lane order into the sort), so that ties in entry distance are
                    // broken alike and both kernels return the same record.
                    sp -= 1;
                }
                mask &= mask - 1;
                if constexpr (kCoherent) {
                    // Coherent rays predict the branch well, and a taken prediction lets the next
                    // node's load start before any entry distance is compared.
                    if (!mask) {
                        ref = node.child[i0];
                        continue;
                    }
                }
                int i1 = __builtin_ctz(mask);
                mask &= mask - 1;
                StackEntry e0{node.child[i0], tNear[i0]}, e1{node.child[i1], tNear[i1]};
                prefetchChild(e0.ref);
                prefetchChild(e1.ref);
                farFirst(e0, e1);
                if (!mask) {  // two children (reached by the coherent kernel only)
                    stack[sp++] = e0;
                    ref = e1.ref;
                    continue;
                }
                // Three children: three branch-free compare-and-swaps; more: an insertion sort.
                int i2 = __builtin_ctz(mask);
                mask &= mask - 1;
                StackEntry e2{node.child[i2], tNear[i2]};
                prefetchChild(e2.ref);
                farFirst(e1, e2);
                farFirst(e0, e1);
                if (!mask) {
                    stack[sp++] = e0;
                    stack[sp++] = e1;
                    ref = e2.ref;
                    continue;
                }
                StackEntry hits[8] = {e0, e1, e2};
                int n = 3;
                while (mask) {
                    int i = __builtin_ctz(mask);
                    mask &= mask - 1;
                    StackEntry e{node.child[i], tNear[i]};
                    prefetchChild(e.ref);
                    int j = n++;
                    while (j > 0 && hits[j - 1].tNear < e.tNear) hits[j] = hits[j - 1], --j;
                    hits[j] = e;
                }
                for (int i = 0; i < n - 1; ++i) stack[sp++] = hits[i];
                ref = hits[n - 1].ref;
                continue;
            }
        } else if (!(ref & kMixedBit)) {
            const Triangle4* blockPtr = leafBlocks(ref);
            uint32_t blocks = (ref & 3u) + 1;
            for (uint32_t b = 0; b < blocks; ++b) {
                const Triangle4& tri = blockPtr[b];
                TriangleCandidate c = intersectTriangle4(triRay, tri, tMax);
                if (c.lane < 0) continue;
                // A cut-out triangle's hit counts only where its alpha mask keeps it; if not, the
                // block's next-nearest lane may still be the answer.
                if constexpr (kMasked) {
                    if (tri.geomId[c.lane] & kMaskedLaneBit) {
                        c = filterMaskedLanes(triRay, tri, tMax);
                        if (c.lane < 0) continue;
                    }
                }
                tMax = c.t, bestU = c.u, bestV = c.v;
                tMaxPadded = splat8(padUp(tMax));
                bestBlock = &tri, bestLane = c.lane;
            }
        } else {
            uint32_t first = (ref & ~(kLeafBit | kMixedBit)) >> 4, count = ref & 15u;
            if (intersectMixedLeaf<false, kMasked>(geometry_, ray, &mixedPrims_[first], count, tMax, bestMixed)) {
                bestBlock = nullptr;
                tMaxPadded = splat8(padUp(tMax));
            }
        }
        // Pop the next subtree the ray may still reach before the current closest hit.
        do {
            if (sp == 0) goto done;
            --sp;
        } while (stack[sp].tNear > padUp(tMax));
        ref = stack[sp].ref;
    }
done:
    if (bestBlock) {
        PrimRef id{bestBlock->geomId[bestLane], bestBlock->primId[bestLane]};
        if constexpr (kMasked) id.geomId &= ~kMaskedLaneBit;
        triangleHitRecord(bestBlock->p, bestLane, tMax, bestU, bestV, id, hit);
        return true;
    }
    if (bestMixed.geomId != kInvalidId) {
        mixedHitRecord(geometry_, ray, bestMixed, tMax, hit);
        return true;
    }
    return false;
}

template <bool kAvx, bool kMasked>
TESSERA_INLINE bool BvhAccel::occludedImpl(const Ray& ray) const {
    if (nodes_.empty() || !isTraceableRay(ray)) return false;
    BoxRay boxRay(ray);
    TriRay triRay(ray);
    const float tMax = ray.tMax;
    const Vf8 tMaxPadded = splat8(padUp(tMax));
    uint32_t stack[kStackSize + 8];  // + 8: the AVX2 push always stores eight entries
    int sp = 0;
    uint32_t ref = 0;
    while (true) {
        if (!(ref & kLeafBit)) {
            // No run-time ordering for any-hit queries (as in Embree's any-hit traversal): the
            // builder orders each node's lanes by subtree size, largest first (collapse()), and the
            // hit lanes are entered from the last, so the smallest subtrees, often leaves that end
            // the query, come first. Comparing entry distances cost more than it saved.
            const Node8& node = this->node(ref);
            Vf8 tNear;
            uint32_t mask = moveMask8Isa<kAvx>(boxRay.test(node, tMaxPadded, tNear));
            if (mask) {
                int first = 31 - __builtin_clz(mask);
                mask &= ~(1u << first);
                if constexpr (kAvx) {
                    // All other hit children pushed at once, in lane order (the next smallest on
                    // top): a table turns the mask into vpermd indices that pack their references
                    // to the front of the register, one 32-byte store writes them, and sp grows by
                    // their count. The loop it replaces
                    // mispredicted its exit on every node (the count is a coin toss for incoherent
                    // rays).
                    Vi8 kids;
                    std::memcpy(&kids, node.child, sizeof kids);
                    Vi8 packed = permute8(kids, compactIndices(mask));
                    std::memcpy(&stack[sp], &packed, sizeof packed);
                    sp += __builtin_popcount(mask);
                    ref = node.child[first];
                    continue;
                }
                while (mask) {
                    int i = __builtin_ctz(mask);
                    mask &= mask - 1;
                    stack[sp++] = node.child[i];
                    prefetchChild(node.child[i]);
                }
                ref = node.child[first];
                continue;
            }
        } else if (!(ref & kMixedBit)) {
            const Triangle4* blockPtr = leafBlocks(ref);
            uint32_t blocks = (ref & 3u) + 1;
            for (uint32_t b = 0; b < blocks; ++b) {
                int lane = occludedTriangle4(triRay, blockPtr[b], tMax);
                if (lane < 0) continue;
                if constexpr (kMasked) {
                    if ((blockPtr[b].geomId[lane] & kMaskedLaneBit) && filterMaskedLanes(triRay, blockPtr[b], tMax).lane < 0)
                        continue;
                }
                return true;
            }
        } else {
            uint32_t first = (ref & ~(kLeafBit | kMixedBit)) >> 4, count = ref & 15u;
            MixedCandidate unused;
            float tHit = ray.tMax;
            if (intersectMixedLeaf<true, kMasked>(geometry_, ray, &mixedPrims_[first], count, tHit, unused)) return true;
        }
        if (sp == 0) return false;
        ref = stack[--sp];
    }
}

#if defined(TESSERA_X86)
__attribute__((target("avx2"))) bool BvhAccel::intersectAvx2(const Ray& ray, Hit& hit) const {
    return intersectImpl<true, false, false>(ray, hit);
}
__attribute__((target("avx2"))) bool BvhAccel::intersectCoherentAvx2(const Ray& ray, Hit& hit) const {
    return intersectImpl<true, true, false>(ray, hit);
}
__attribute__((target("avx2"))) bool BvhAccel::occludedAvx2(const Ray& ray) const { return occludedImpl<true, false>(ray); }
template <bool kCoherent>
__attribute__((target("avx2"))) bool BvhAccel::intersectMaskedAvx2(const Ray& ray, Hit& hit) const {
    return intersectImpl<true, kCoherent, true>(ray, hit);
}
__attribute__((target("avx2"))) bool BvhAccel::occludedMaskedAvx2(const Ray& ray) const { return occludedImpl<true, true>(ray); }
#endif

template <bool kCoherent>
__attribute__((noinline)) bool BvhAccel::intersectMasked(const Ray& ray, Hit& hit) const {
#if defined(TESSERA_X86)
    if (isa_.avx2()) return intersectMaskedAvx2<kCoherent>(ray, hit);
#endif
    return intersectImpl<false, kCoherent, true>(ray, hit);
}

__attribute__((noinline)) bool BvhAccel::occludedMasked(const Ray& ray) const {
#if defined(TESSERA_X86)
    if (isa_.avx2()) return occludedMaskedAvx2(ray);
#endif
    return occludedImpl<false, true>(ray);
}

bool BvhAccel::intersect(const Ray& ray, Hit& hit) const {
    if (hasCutOuts_) return intersectMasked<false>(ray, hit);
#if defined(TESSERA_X86)
    if (isa_.avx2()) return intersectAvx2(ray, hit);
#endif
    return intersectImpl<false, false, false>(ray, hit);
}

bool BvhAccel::intersectCoherent(const Ray& ray, Hit& hit) const {
    if (hasCutOuts_) return intersectMasked<true>(ray, hit);
#if defined(TESSERA_X86)
    if (isa_.avx2()) return intersectCoherentAvx2(ray, hit);
#endif
    return intersectImpl<false, true, false>(ray, hit);
}

bool BvhAccel::occluded(const Ray& ray) const {
    if (hasCutOuts_) return occludedMasked(ray);
#if defined(TESSERA_X86)
    if (isa_.avx2()) return occludedAvx2(ray);
#endif
    return occludedImpl<false, false>(ray);
}

}  // namespace tessera
