/// \file kdtree_traversal.cpp
/// Front-to-back stack traversal of the k-d tree's wide nodes (kdtree_wide.h): Havran's
/// "TA_B^rec" family (Havran 2000, thesis Section 4; pbrt-v3; Wald's thesis Section 7.2) with the
/// three binary levels of a treelet decided in one 8-lane step. Each lane (a slot: up to three
/// planes with a side each) clips the current segment; the entered slots are visited in the binary
/// traversal's near-first order, the others pushed. The closest-hit kernel stops as soon as a hit
/// lies inside the current leaf's segment (nothing behind can be closer); the any-hit kernel stops
/// at the first hit.
#include <cmath>
#include <cstring>

#include "accel/bvh_simd.h"
#include "accel/mixed_leaf.h"
#include "accel/triangle_simd.h"
#include "accel/kdtree_accel.h"
#include "geometry/intersect.h"

namespace tessera {

using namespace simd;


namespace {

/// |x| enlarged by two ulps (inf stays inf): Ize 2013's conservative far reciprocal.
inline float twoUlpsLarger(float x) {
    uint32_t bits;
    std::memcpy(&bits, &x, 4);
    if ((bits & 0x7fffffffu) >= 0x7f7ffffeu) return std::copysign(kInfinity, x);
    bits += 2;
    std::memcpy(&x, &bits, 4);
    return x;
}

/// t + 4 ulps, for comparisons of two computed distances along the same ray.
inline float padUp(float t) { return t + std::abs(t) * 0x1p-21f; }

struct StackEntry {
    uint32_t ref;
    float tMin, tMax;
};

/// A wide node's (and the traversal's) depth is a third of the binary depth; each level pushes at
/// most 7 entries.
constexpr int kStackSize = 7 * (kKdMaxDepth / 3 + 1) + 1;

using Candidate = TriangleCandidate;

/// Lane i takes lane idx[i] (vpermps / vpermd inside the AVX2 build; GCC lowers it lane by lane
/// elsewhere, with the same bits).
TESSERA_INLINE Vf8 permute8(Vf8 v, Vi8 idx) {
#if defined(__clang__)
    Vf8 r;
    for (int i = 0; i < 8; ++i) r[i] = v[idx[i] & 7];
    return r;
#else
    return __builtin_shuffle(v, idx);
#endif
}
TESSERA_INLINE Vi8 permute8(Vi8 v, Vi8 idx) {
#if defined(__clang__)
    Vi8 r;
    for (int i = 0; i < 8; ++i) r[i] = v[idx[i] & 7];
    return r;
#else
    return __builtin_shuffle(v, idx);
#endif
}

// Slot s (lane s) applies, at level l, plane (1 << l) − 1 + (s >> (3 − l)) from the side given by
// bit 2 − l of s (kdtree_wide.h).
const Vi8 kPlaneAxisShift = {0, 2, 4, 6, 8, 10, 12, 0};
const Vi8 kLevelPlane[3] = {{0, 0, 0, 0, 0, 0, 0, 0}, {1, 1, 1, 1, 2, 2, 2, 2}, {3, 3, 4, 4, 5, 5, 6, 6}};
const Vi8 kLevelAbove[3] = {{0, 0, 0, 0, -1, -1, -1, -1}, {0, 0, -1, -1, 0, 0, -1, -1}, {0, -1, 0, -1, 0, -1, 0, -1}};
const Vi8 kLaneIndex = {0, 1, 2, 3, 4, 5, 6, 7};

/// Per-ray values of the wide-node test, lanes 0–2 per axis (lanes 3–7 unused).
struct WideRay {
    Vf8 org, inv, pad;  ///< origin, 1/d, the plane padding eps·|1/d| (0 where d = 0)
    Vi8 down;           ///< all ones where the ray moves downward (from the sign of 1/d, so −0.0 too)
};

/// The slots of a wide node that the segment [tMin, tMax] enters, as a bit mask. For each slot
/// (lane) and level, the plane distance t = (split − o[axis])·(1/d[axis]) (origin and 1/d permuted
/// into the lanes by the plane's axis) bounds the segment from one side: a slot on the near side of
/// the plane (below it for a ray moving up, above it for one moving down) keeps [−inf, t], one on
/// the far side [t, +inf]; the slot's segment is the intersection (max of the entries, min of the
/// exits). NaN distances (no plane at that level, or an origin in the plane of a zero direction
/// component, which visits both sides) leave it unchanged: they are the first operand of the
/// NaN-ignoring max/min. The visit decision uses the planes padded by eps·|1/d| (a cell is visited if
/// the ray passes within eps of it, kdtree_traversal's robustness rule), the returned segments
/// `entry`/`exit` are the exact ones (the early exit stays exact). Padding every level of the
/// treelet against the exact segment from above it visits a superset of the binary traversal's
/// cells. `key` is each slot's rank in the binary near-first order: bit 2 − l set when the slot lies
/// on the far side of its level-l plane (distinct among the occupied slots, so a sort by key is the
/// binary traversal's depth-first near-first order, also for padded or NaN decisions).
template <bool kAvx>
TESSERA_INLINE uint32_t enterSlots(const KdWideNode& n, const WideRay& r, float tMin, float tMax, Vf8& entry, Vf8& exit, Vi8& key) {
    const Vf8 planes = load8(n.split);  // lane 7 holds the meta word (a normal float), never used
    const Vi8 axis = ((Vi8{} + int32_t(n.meta)) >> kPlaneAxisShift) & 3;
    const Vf8 o = permute8(r.org, axis), inv = permute8(r.inv, axis), pad = permute8(r.pad, axis);
    const Vi8 down = permute8(r.down, axis);
    const Vf8 t = (planes - o) * inv;
    const Vf8 tLo = t - pad, tHi = t + pad;
    const Vf8 inf = splat8(kInfinity), negInf = splat8(-kInfinity);
    Vf8 e = splat8(tMin), x = splat8(tMax), ePad = e, xPad = x;
    Vi8 flip{};
    for (int l = 0; l < 3; ++l) {
        const Vi8 idx = kLevelPlane[l];
        const Vf8 tl = permute8(t, idx), lo = permute8(tLo, idx), hi = permute8(tHi, idx);
        const Vi8 dl = permute8(down, idx);
        const Vi8 far = dl ^ kLevelAbove[l];
        e = maxNanB(far ? tl : negInf, e);
        x = minNanB(far ? inf : tl, x);
        ePad = maxNanB(far ? lo : negInf, ePad);
        xPad = minNanB(far ? inf : hi, xPad);
        flip |= dl & (4 >> l);
    }
    entry = e, exit = x;
    key = kLaneIndex ^ flip;
    return moveMask8Isa<kAvx>(ePad <= xPad) & n.slotMask();
}

}  // namespace

template <bool kAnyHit, bool kAvx>
TESSERA_INLINE bool KdTreeAccel::traverse(const Ray& ray, Hit* hit) const {
    if (wide_.empty() || !isTraceableRay(ray)) return false;
    Vec3f invD;
    for (int a = 0; a < 3; ++a) invD[a] = 1.f / ray.d[a];  // ±inf for ±0.0

    // Robustness. Primitive boxes and perfect splits are exact, but the watertight test may report
    // a hit up to a few ulps of the coordinates' magnitude (relative to the ray origin) outside the
    // exact triangle. So the traversal visits every cell that the ray passes within `eps` of:
    // 16 ulps of the largest coordinate involved. Across a plane of axis a that is a distance of
    // eps·|1/d_a| along the ray (large for rays almost parallel to the plane), which pads each
    // visit decision. Segment bounds stay unpadded, so the early exit stays exact.
    const float eps = 0x1p-19f * (sceneMagnitude_ + maxComponent(glm::abs(ray.o)));
    bool upward[3];
    WideRay wideRay{};
    for (int a = 0; a < 3; ++a) {
        upward[a] = !std::signbit(invD[a]);  // from 1/d, so −0.0 counts as downward
        wideRay.org[a] = ray.o[a];
        wideRay.inv[a] = invD[a];
        wideRay.pad[a] = ray.d[a] != 0.f ? eps * std::abs(invD[a]) : 0.f;
        wideRay.down[a] = upward[a] ? 0 : -1;
    }

    // Clip the ray to the root cell grown by eps: conservative slabs (Ize 2013), NaN-safe operand
    // order (a 0·inf NaN, from an origin on a slab plane of a zero direction component, leaves the
    // interval alone).
    float tMin = ray.tMin, tMax = ray.tMax;
    for (int a = 0; a < 3; ++a) {
        float nearPlane = upward[a] ? rootCell_.lower[a] - eps : rootCell_.upper[a] + eps;
        float farPlane = upward[a] ? rootCell_.upper[a] + eps : rootCell_.lower[a] - eps;
        float tn = (nearPlane - ray.o[a]) * invD[a];
        float tf = (farPlane - ray.o[a]) * twoUlpsLarger(invD[a]);
        tMin = tn > tMin ? tn : tMin;
        tMax = tf < tMax ? tf : tMax;
    }
    if (!(tMin <= tMax)) return false;

    TriRay8 triRay(ray);
    float tHit = ray.tMax;  // closest hit so far (closest-hit kernel)
    const TriangleBlock* bestBlock = nullptr;
    int bestLane = -1;
    MixedCandidate bestMixed;
    float bestU = 0.f, bestV = 0.f;

    StackEntry stack[kStackSize];
    int sp = 0;
    uint32_t ref = 0;  // the root wide node
    const char* wideBase = reinterpret_cast<const char*>(wide_.data());
    while (true) {
        if (!(ref & kKdLeafBit)) {
            const KdWideNode& node = *reinterpret_cast<const KdWideNode*>(wideBase + ref);
            Vf8 entry, exit;
            Vi8 key;
            uint32_t mask = enterSlots<kAvx>(node, wideRay, tMin, tMax, entry, exit, key);
            if (mask) {
                if (!(mask & (mask - 1))) {  // one slot: no ordering needed
                    int i = __builtin_ctz(mask);
                    ref = node.child[i], tMin = entry[i], tMax = exit[i];
                    continue;
                }
                if constexpr (kAnyHit) {
                    // No ordering for any-hit queries: push all but one.
                    int first = __builtin_ctz(mask);
                    mask &= mask - 1;
                    while (mask) {
                        int i = __builtin_ctz(mask);
                        mask &= mask - 1;
                        stack[sp++] = {node.child[i], entry[i], exit[i]};
                    }
                    ref = node.child[first], tMin = entry[first], tMax = exit[first];
                    continue;
                } else {
                    // Near-first: the slots by key (distinct, < 8), the farthest pushed first.
                    int32_t keys[8];
                    std::memcpy(keys, &key, sizeof keys);
                    int slotOfKey[8];
                    uint32_t byKey = 0;
                    while (mask) {
                        int i = __builtin_ctz(mask);
                        mask &= mask - 1;
                        slotOfKey[keys[i]] = i;
                        byKey |= 1u << keys[i];
                    }
                    const int nearest = slotOfKey[__builtin_ctz(byKey)];
                    byKey &= byKey - 1;
                    while (byKey) {
                        int k = 31 - __builtin_clz(byKey);
                        byKey ^= 1u << k;
                        int i = slotOfKey[k];
                        stack[sp++] = {node.child[i], entry[i], exit[i]};
                    }
                    ref = node.child[nearest], tMin = entry[nearest], tMax = exit[nearest];
                    continue;
                }
            }
        } else {
            const LeafSpan leaf = leafSpan(ref);
            if (!leaf.mixed) {
                const TriangleBlock* blocks = triangles_.data() + leaf.first;
                for (uint32_t b = 0; b < leaf.count; ++b) {
                    Candidate c = intersectTriangles<8, kAnyHit>(triRay, blocks[b].p, tHit);
                    if (c.lane < 0) continue;
                    if constexpr (kAnyHit) return true;
                    tHit = c.t, bestU = c.u, bestV = c.v;
                    bestBlock = &blocks[b], bestLane = c.lane;
                }
            } else if (intersectMixedLeaf<kAnyHit>(geometry_, ray, &mixedPrims_[leaf.first], leaf.count, tHit, bestMixed)) {
                if constexpr (kAnyHit) return true;
                bestBlock = nullptr;
            }
            // Early exit: a hit inside this leaf's segment is closer than anything behind it.
            if (tHit <= tMax && tHit < ray.tMax) break;
        }
        // Next segment along the ray, unless the closest hit lies before it.
        do {
            if (sp == 0) goto done;
            --sp;
        } while (stack[sp].tMin > padUp(tHit));
        ref = stack[sp].ref;
        tMin = stack[sp].tMin;
        tMax = stack[sp].tMax;
    }
done:
    if constexpr (kAnyHit) {
        return false;
    } else {
        if (bestBlock) {
            Vec3f p[3];
            for (int v = 0; v < 3; ++v) p[v] = {bestBlock->p[v][0][bestLane], bestBlock->p[v][1][bestLane], bestBlock->p[v][2][bestLane]};
            hit->t = tHit, hit->u = bestU, hit->v = bestV;
            const PrimRef& id = blockIds_[size_t(bestBlock - triangles_.data()) * kLanes + size_t(bestLane)];
            hit->geomId = id.geomId;
            hit->primId = id.primId;
            hit->ng = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
            return true;
        }
        if (bestMixed.geomId != kInvalidId) {
            mixedHitRecord(geometry_, ray, bestMixed, tHit, *hit);
            return true;
        }
        return false;
    }
}

#if defined(TESSERA_X86)
__attribute__((target("avx2"))) bool KdTreeAccel::intersectAvx2(const Ray& ray, Hit& hit) const { return traverse<false, true>(ray, &hit); }
__attribute__((target("avx2"))) bool KdTreeAccel::occludedAvx2(const Ray& ray) const { return traverse<true, true>(ray, nullptr); }
#else
bool KdTreeAccel::intersectAvx2(const Ray& ray, Hit& hit) const { return traverse<false, false>(ray, &hit); }
bool KdTreeAccel::occludedAvx2(const Ray& ray) const { return traverse<true, false>(ray, nullptr); }
#endif

bool KdTreeAccel::intersect(const Ray& ray, Hit& hit) const {
    return useAvx2_ ? intersectAvx2(ray, hit) : traverse<false, false>(ray, &hit);
}
bool KdTreeAccel::occluded(const Ray& ray) const { return useAvx2_ ? occludedAvx2(ray) : traverse<true, false>(ray, nullptr); }

}  // namespace tessera
