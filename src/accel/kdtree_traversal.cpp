/// \file kdtree_traversal.cpp
/// Front-to-back stack traversal of the k-d tree's wide nodes (kdtree_wide.h): Havran's
/// "TA_B^rec" family (Havran 2000, thesis Section 4; pbrt-v3; Wald's thesis Section 7.2) with the
/// three binary levels of a treelet decided in one 8-lane step. Each lane (a slot: up to three
/// planes with a side each) clips the current segment; the entered slots are visited in the binary
/// traversal's near-first order (closest-hit) or far-first (any-hit), the others pushed. The
/// closest-hit kernel drops every pushed segment that starts beyond its hit; the any-hit kernel
/// stops at the first hit. Scenes with cut-out triangles (alpha masks) run a second instantiation of
/// both (kMasked) that drops the hits the masks drop.
#include <cmath>
#include <cstring>
#include <limits>

#include "accel/accel_simd.h"
#include "accel/kdtree_accel.h"
#include "accel/mixed_leaf.h"
#include "accel/robust_bounds.h"
#include "accel/triangle_simd.h"
#include "geometry/alpha_mask.h"

namespace tessera {

using namespace simd;


namespace {

/// A wide node's (and the traversal's) depth is a third of the binary depth; each level pushes at
/// most 7 entries.
constexpr int kStackSize = 7 * (kKdMaxDepth / 3 + 1) + 1;


// Slot s (lane s) applies, at level l, plane p = (1 << l) − 1 + (s >> (3 − l)) from the side given
// by bit 2 − l of s (kdtree_wide.h); the meta word holds that plane's axis in bits 3p..3p+1.
const Vi8 kLevelPlane[3] = {{0, 0, 0, 0, 0, 0, 0, 0}, {1, 1, 1, 1, 2, 2, 2, 2}, {3, 3, 4, 4, 5, 5, 6, 6}};
const Vi8 kLevelAxisShift[3] = {{0, 0, 0, 0, 0, 0, 0, 0}, {3, 3, 3, 3, 6, 6, 6, 6}, {9, 9, 12, 12, 15, 15, 18, 18}};
/// 4 where the slot lies above its level-l plane: the side half of a WideRay table index.
const Vi8 kLevelSide[3] = {{0, 0, 0, 0, 4, 4, 4, 4}, {0, 0, 4, 4, 0, 0, 4, 4}, {0, 4, 0, 4, 0, 4, 0, 4}};

/// All lanes x: one vbroadcastss in the AVX2 build (GCC turned both `Vf8{} + x`, an addition of 0
/// in the latency chain, and `Vf8{x, x, ...}` into longer sequences).
template <bool kAvx>
TESSERA_INLINE Vf8 broadcast8(float x) {
#if defined(TESSERA_X86)
    if constexpr (kAvx) {
        Vf8 r;
        asm("vbroadcastss %1, %0" : "=x"(r) : "xm"(x));  // from memory when x is there: no ALU port
        return r;
    }
#endif
    return Vf8{x, x, x, x, x, x, x, x};
}

/// The node's meta word in all lanes: one vpbroadcastd from memory in the AVX2 build (GCC went
/// through a general register, two more shuffle-port instructions).
template <bool kAvx>
TESSERA_INLINE Vi8 broadcastMeta(const KdWideNode& n) {
#if defined(TESSERA_X86)
    if constexpr (kAvx) {
        Vi8 r;
        asm("vpbroadcastd %1, %0" : "=x"(r) : "m"(n.meta));
        return r;
    }
#endif
    return Vi8{} + int32_t(n.meta);
}

/// The part of the ray inside a cell, its bounds padded by eps at every plane on the path.
struct Segment {
    float tMin, tMax;
};

/// Per-ray tables of the wide-node test, indexed by axis + 4·side (side 1: the slot lies above the
/// plane), permuted into the slot lanes by each level's (axis, side).
struct WideRay {
    Vf8 inv;  ///< 1/d (the same for both sides)
    /// The origin moved by eps along the axis so that (split − o')·(1/d) is the plane distance
    /// padded by eps·|1/d| in the direction that widens the slot's cell: towards the origin where
    /// the plane is the slot's entry (slot on the far side), away from it where it is the exit.
    /// Moving the origin instead of padding the distance costs nothing per node. `orgEntry` holds
    /// it where the plane bounds the slot's entry (far side) and NaN where it does not (near side),
    /// `orgExit` the other way round: the distance of the bound that does not apply is then a NaN,
    /// which the NaN-ignoring max/min skip.
    Vf8 orgEntry, orgExit;
    uint32_t downBits = 0;  ///< bit a set when the ray moves downward on axis a

    /// The slot's rank in the binary traversal's near-first order: bit 2 − l set when the slot lies
    /// on the far side of its level-l plane, i.e. its side bit flipped when the ray moves downward
    /// on that plane's axis. Distinct among a node's occupied slots (their paths part at a plane
    /// that both have), so sorting by it is the binary depth-first near-first order, also for
    /// padded or NaN decisions.
    uint32_t nearFirstKey(const KdWideNode& n, int slot) const {
        const auto down = [&](int plane) { return downBits >> n.axis(plane) & 1u; };
        return uint32_t(slot) ^ (down(0) << 2 | down(1 + (slot >> 2)) << 1 | down(3 + (slot >> 1)));
    }

    /// eps: the traversal's padding; upward[a]: the ray moves up on axis a (from the sign of 1/d).
    WideRay() = default;
    WideRay(const Ray& ray, const Vec3f& invD, const bool (&upward)[3], float eps) : inv{}, orgEntry{}, orgExit{} {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        for (int a = 0; a < 3; ++a) {
            // Lane a: the side below the plane, the near side of a ray moving up; lane a + 4: the
            // side above. The far side bounds the entry, the near side the exit, each with the
            // origin moved by eps away from the side: t ∓ eps·|1/d| = (split − (o ∓ eps))/d.
            // Chosen by indexing with the direction's sign, not by branches: for incoherent rays
            // the sign is a coin toss (as in watertightAxes).
            const int up = upward[a];
            const float below[2] = {ray.o[a] - eps, nan}, above[2] = {nan, ray.o[a] + eps};
            inv[a] = inv[a + 4] = invD[a];
            orgEntry[a] = below[up], orgExit[a] = below[1 - up];
            orgEntry[a + 4] = above[up], orgExit[a + 4] = above[1 - up];
            downBits |= uint32_t(1 - up) << a;
        }
    }
};

/// The slots of a wide node that the segment `seg` enters, as a bit mask, and their segments
/// (`entry`, `exit`). For each slot (lane) and level, the plane distance t = (split − o)·(1/d) (the
/// split permuted into the slot lanes by level, origin and 1/d by the plane's axis and the slot's
/// side) bounds the segment from one side: a slot on the near side of the plane (below it for a ray
/// moving up, above it for one moving down) keeps [−inf, t], one on the far side [t, +inf]; the
/// slot's segment is the intersection (max of the entries, min of the exits). The bound that does
/// not apply is a NaN (WideRay::orgEntry/orgExit) and skipped by the NaN-ignoring max/min (the first
/// operand, chained on a non-NaN accumulator); so is a level without a plane (NaN split) and the 0·inf of an origin in
/// the plane of a zero direction component (both sides visited, as in the binary traversal).
/// Robustness: every plane is moved by eps to widen the slot's cell (a cell is visited if the ray
/// passes within eps of it, see startRay), and the segments carried down are these padded ones.
/// Every pair of planes on a path is thus compared padded against padded, which visits a superset
/// of the binary traversal's cells (that compared each padded plane with the exact bounds of the
/// planes above it). Comparing with the exact segment from above instead is not: a cell entered
/// only thanks to the padding has an inverted exact segment, and none of its children would pass.
template <bool kAvx>
TESSERA_INLINE uint32_t enterSlots(const KdWideNode& n, const WideRay& r, const Segment& seg, Vf8& entry, Vf8& exit) {
    const Vf8 planes = load8(n.split);  // lane 7 holds the meta word (a normal float), never used
    const Vi8 meta = broadcastMeta<kAvx>(n);
    Vf8 eP = broadcast8<kAvx>(seg.tMin), xP = broadcast8<kAvx>(seg.tMax);
    for (int l = 0; l < 3; ++l) {
        // axis + 4·side in the low three bits (the only ones a permute reads; bit 2 of the shifted
        // meta is clear).
        const Vi8 index = (meta >> kLevelAxisShift[l]) | kLevelSide[l];
        // Level 0's one plane straight from memory (a load, no shuffle).
        const Vf8 split = l == 0 ? broadcast8<kAvx>(n.split[0]) : permute8(planes, kLevelPlane[l]);
        const Vf8 inv = permute8(r.inv, index);
        eP = maxNanB((split - permute8(r.orgEntry, index)) * inv, eP);
        xP = minNanB((split - permute8(r.orgExit, index)) * inv, xP);
    }
    entry = eP, exit = xP;
    return moveMask8Isa<kAvx>(eP <= xP) & n.slotMask();
}

TESSERA_INLINE Vi8 load8i(const uint32_t* p) {
    Vi8 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
TESSERA_INLINE void store8(void* p, Vf8 v) { std::memcpy(p, &v, sizeof v); }
TESSERA_INLINE void store8(void* p, Vi8 v) { std::memcpy(p, &v, sizeof v); }

/// Per-ray set-up shared by both kernels: the wide-node tables and the ray clipped to the root cell.
/// Returns false when the ray misses the root cell (or cannot be traced). `sceneMagnitude`: the
/// largest |coordinate| of the root cell.
TESSERA_INLINE bool startRay(const Ray& ray, const Bounds3f& rootCell_, float sceneMagnitude_, WideRay& wideRay, Segment& seg) {
    if (!isTraceableRay(ray)) return false;
    Vec3f invD;
    for (int a = 0; a < 3; ++a) invD[a] = 1.f / ray.d[a];  // ±inf for ±0.0
    // Robustness. Primitive boxes and perfect splits are exact, but the watertight test may report
    // a hit up to a few ulps of the coordinates' magnitude (relative to the ray origin) outside the
    // exact triangle. So the traversal visits every cell that the ray passes within `eps` of:
    // 16 ulps of the largest coordinate involved. Across a plane of axis a that is a distance of
    // eps·|1/d_a| along the ray (large for rays almost parallel to the plane), which pads each
    // plane of every visit decision (enterSlots).
    const float eps = kKdCellPadRelative * (sceneMagnitude_ + maxComponent(glm::abs(ray.o)));
    bool upward[3];
    for (int a = 0; a < 3; ++a) upward[a] = !std::signbit(invD[a]);  // from 1/d, so −0.0 counts as downward
    wideRay = WideRay(ray, invD, upward, eps);
    // Clip the ray to the root cell grown by eps: conservative slabs (Ize 2013), NaN-safe operand
    // order (a 0·inf NaN, from an origin on a slab plane of a zero direction component, leaves the
    // interval alone).
    float tMin = ray.tMin, tMax = ray.tMax;
    for (int a = 0; a < 3; ++a) {
        const float planes[2] = {rootCell_.upper[a] + eps, rootCell_.lower[a] - eps};  // indexed, as in WideRay
        float nearPlane = planes[int(upward[a])], farPlane = planes[1 - int(upward[a])];
        float tn = (nearPlane - ray.o[a]) * invD[a];
        float tf = (farPlane - ray.o[a]) * twoUlpsLarger(invD[a]);
        tMin = tn > tMin ? tn : tMin;
        tMax = tf < tMax ? tf : tMax;
    }
    seg = {tMin, tMax};
    return tMin <= tMax;
}

}  // namespace

// Out of line: the slow path of cut-out leaves stays out of the kernels' hot loops.
__attribute__((noinline)) TriangleCandidate KdTreeAccel::filterMaskedLanes(const TriRay8& r, size_t block, float tMax,
                                                                           TriangleCandidate c) const {
    const PrimRef* ids = &blockIds_[block * kLanes];
    auto keep = [&](int lane, float u, float v) {
        const TriangleMesh& mesh = geometry_.meshes[ids[lane].geomId];
        return !mesh.alphaMask || alphaMaskKeeps(mesh, ids[lane].primId, u, v);
    };
    if (!geometry_.meshes[ids[c.lane].geomId].alphaMask) return c;
    return intersectTrianglesFiltered<kLanes>(r, triangles_[block].p, tMax, keep);
}

/// The closest-hit kernel: entered slots visited in the binary traversal's near-first order, the
/// others pushed. There is no separate early exit: once a hit is found, every pushed segment that
/// starts beyond it is dropped when popped, and in near-first order that is everything behind the
/// hit's cell. (An exact exit per segment, for the classic "hit inside this leaf" test, cost an
/// extra permute, product and min per level in every node.)
/// kAnyHit: the any-hit kernel (occluded), returning at the first hit, and visiting the entered
/// slots *far-first*: a shadow ray starts on a surface, whose finely cut cells around the origin
/// hold the surface itself and its neighbours, which rarely occlude; from the far (light) end it
/// meets an occluder, when there is one, before paying for them. Against a kernel that pushed all
/// entered slots branch-free and took them in slot order: Conference shadow rays +35% (0.46× →
/// 0.62× Embree), Sibenik and Sponza −2–3%, dragon res2 ±1% (`bench-accel --rays shadow`, CPU clock,
/// two processes each); near-first was 10–30% slower than either.
template <bool kAvx, bool kCoherent, bool kMasked, bool kAnyHit>
TESSERA_INLINE bool KdTreeAccel::intersectImpl(const Ray& ray, Hit& hit) const {
    WideRay wideRay;
    Segment seg;
    if (wide_.empty() || !startRay(ray, rootCell_, sceneMagnitude_, wideRay, seg)) return false;
    TriRay8 triRay(ray);
    float tHit = ray.tMax;  // closest hit so far
    const TriangleBlock* bestBlock = nullptr;
    int bestLane = -1;
    MixedCandidate bestMixed;
    float bestU = 0.f, bestV = 0.f;

    struct StackEntry {
        uint32_t ref;
        Segment seg;
    };
    StackEntry stack[kStackSize];
    int sp = 0;
    uint32_t ref = 0;  // the root wide node
    const char* wideBase = reinterpret_cast<const char*>(wide_.data());
    while (true) {
        if (!(ref & kKdLeafBit)) {
            const KdWideNode& node = *reinterpret_cast<const KdWideNode*>(wideBase + ref);
            Vf8 entry, exit;
            uint32_t mask = enterSlots<kAvx>(node, wideRay, seg, entry, exit);
            if (mask) {
                int nearest;
                if constexpr (!kCoherent) {
                    // Incoherent rays (as in the BVH): one and two entered slots share one
                    // branch-free path, the lowest and the highest slot (the same slot when alone,
                    // and its push is then not kept); the order is the loops' below, so both
                    // kernels return the same record.
                    const int lo = __builtin_ctz(mask), hi = 31 - __builtin_clz(mask);
                    if (!(mask & ~((1u << lo) | (1u << hi)))) {
                        const bool swap = (wideRay.nearFirstKey(node, hi) < wideRay.nearFirstKey(node, lo)) != kAnyHit;
                        const int near = swap ? hi : lo, far = swap ? lo : hi;
                        stack[sp] = {node.child[far], {entry[far], exit[far]}};
                        sp += lo != hi;
                        ref = node.child[near];
                        seg = {entry[near], exit[near]};
                        continue;
                    }
                }
                if (!(mask & (mask - 1))) {  // one slot: no ordering needed
                    nearest = __builtin_ctz(mask);
                } else {
                    // Near-first: the slots by key (distinct, < 8), the farthest pushed first.
                    int slotOfKey[8];
                    uint32_t byKey = 0;
                    while (mask) {
                        int i = __builtin_ctz(mask);
                        mask &= mask - 1;
                        uint32_t k = wideRay.nearFirstKey(node, i);
                        slotOfKey[k] = i;
                        byKey |= 1u << k;
                    }
                    if constexpr (kAnyHit) {
                        // Far-first: the last slot along the ray first, the nearest pushed first.
                        const int last = 31 - __builtin_clz(byKey);
                        nearest = slotOfKey[last];
                        byKey ^= 1u << last;
                        while (byKey) {
                            int k = __builtin_ctz(byKey);
                            byKey &= byKey - 1;
                            int i = slotOfKey[k];
                            stack[sp++] = {node.child[i], {entry[i], exit[i]}};
                        }
                    } else {
                    nearest = slotOfKey[__builtin_ctz(byKey)];
                    byKey &= byKey - 1;
                    while (byKey) {
                        int k = 31 - __builtin_clz(byKey);
                        byKey ^= 1u << k;
                        int i = slotOfKey[k];
                        stack[sp++] = {node.child[i], {entry[i], exit[i]}};
                    }
                    }
                }
                ref = node.child[nearest];
                seg = {entry[nearest], exit[nearest]};
                continue;
            }
        } else {
            const LeafSpan leaf = leafSpan(ref);
            if (!leaf.mixed) {
                const TriangleBlock* blocks = triangles_.data() + leaf.first;
                for (uint32_t b = 0; b < leaf.count; ++b) {
                    TriangleCandidate c = intersectTriangles<8, kAnyHit>(triRay, blocks[b].p, tHit);
                    if (c.lane < 0) continue;
                    if constexpr (kAnyHit) {
                        if constexpr (kMasked) {
                            if ((ref & kKdMaskedLeafBit) && filterMaskedLanes(triRay, leaf.first + b, tHit, c).lane < 0) continue;
                        }
                        return true;
                    }
                    // A cut-out triangle's hit counts only where its alpha mask keeps it; if not,
                    // the block's next-nearest lane may still be the answer.
                    if constexpr (kMasked) {
                        if (ref & kKdMaskedLeafBit) {
                            c = filterMaskedLanes(triRay, leaf.first + b, tHit, c);
                            if (c.lane < 0) continue;
                        }
                    }
                    tHit = c.t, bestU = c.u, bestV = c.v;
                    bestBlock = &blocks[b], bestLane = c.lane;
                }
            } else if (intersectMixedLeaf<kAnyHit, kMasked>(geometry_, ray, &mixedPrims_[leaf.first], leaf.count, tHit, bestMixed)) {
                if constexpr (kAnyHit) return true;
                bestBlock = nullptr;
            }
        }
        // Next segment along the ray, unless the closest hit lies before it.
        do {
            if (sp == 0) goto done;
            --sp;
        } while (stack[sp].seg.tMin > padUp(tHit));
        ref = stack[sp].ref;
        seg = stack[sp].seg;
    }
done:
    if constexpr (kAnyHit) return false;
    if (bestBlock) {
        const PrimRef id = blockIds_[size_t(bestBlock - triangles_.data()) * kLanes + size_t(bestLane)];
        triangleHitRecord(bestBlock->p, bestLane, tHit, bestU, bestV, id, hit);
        return true;
    }
    if (bestMixed.geomId != kInvalidId) {
        mixedHitRecord(geometry_, ray, bestMixed, tHit, hit);
        return true;
    }
    return false;
}

#if defined(TESSERA_X86)
__attribute__((target("avx2"))) bool KdTreeAccel::intersectAvx2(const Ray& ray, Hit& hit) const { return intersectImpl<true, false, false, false>(ray, hit); }
__attribute__((target("avx2"))) bool KdTreeAccel::intersectCoherentAvx2(const Ray& ray, Hit& hit) const { return intersectImpl<true, true, false, false>(ray, hit); }
__attribute__((target("avx2"))) bool KdTreeAccel::occludedAvx2(const Ray& ray) const {
    Hit unused;
    return intersectImpl<true, false, false, true>(ray, unused);
}
template <bool kCoherent>
__attribute__((target("avx2"))) bool KdTreeAccel::intersectMaskedAvx2(const Ray& ray, Hit& hit) const {
    return intersectImpl<true, kCoherent, true, false>(ray, hit);
}
__attribute__((target("avx2"))) bool KdTreeAccel::occludedMaskedAvx2(const Ray& ray) const {
    Hit unused;
    return intersectImpl<true, false, true, true>(ray, unused);
}
#endif

template <bool kCoherent>
__attribute__((noinline)) bool KdTreeAccel::intersectMasked(const Ray& ray, Hit& hit) const {
#if defined(TESSERA_X86)
    if (isa_.avx2()) return intersectMaskedAvx2<kCoherent>(ray, hit);
#endif
    return intersectImpl<false, kCoherent, true, false>(ray, hit);
}

__attribute__((noinline)) bool KdTreeAccel::occludedMasked(const Ray& ray) const {
#if defined(TESSERA_X86)
    if (isa_.avx2()) return occludedMaskedAvx2(ray);
#endif
    Hit unused;
    return intersectImpl<false, false, true, true>(ray, unused);
}

bool KdTreeAccel::intersect(const Ray& ray, Hit& hit) const {
    if (hasCutOuts_) return intersectMasked<false>(ray, hit);
#if defined(TESSERA_X86)
    if (isa_.avx2()) return intersectAvx2(ray, hit);
#endif
    return intersectImpl<false, false, false, false>(ray, hit);
}

bool KdTreeAccel::intersectCoherent(const Ray& ray, Hit& hit) const {
    if (hasCutOuts_) return intersectMasked<true>(ray, hit);
#if defined(TESSERA_X86)
    if (isa_.avx2()) return intersectCoherentAvx2(ray, hit);
#endif
    return intersectImpl<false, true, false, false>(ray, hit);
}

bool KdTreeAccel::occluded(const Ray& ray) const {
    if (hasCutOuts_) return occludedMasked(ray);
#if defined(TESSERA_X86)
    if (isa_.avx2()) return occludedAvx2(ray);
#endif
    Hit unused;
    return intersectImpl<false, false, false, true>(ray, unused);
}

}  // namespace tessera
