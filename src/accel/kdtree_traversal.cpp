/// \file kdtree_traversal.cpp
/// Front-to-back stack traversal of the k-d tree (Havran's "TA_B^rec" family as in pbrt-v3 and
/// Wald's thesis, Section 7.2): per node, one plane distance decides whether the ray's segment
/// [tMin, tMax] visits the near child, the far child or both; the far part is pushed. The closest-hit
/// kernel stops as soon as a hit lies inside the current leaf's segment (nothing behind can be
/// closer); the any-hit kernel stops at the first hit.
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
    uint32_t node;
    float tMin, tMax;
};

using Candidate = TriangleCandidate;

}  // namespace

template <bool kAnyHit>
TESSERA_INLINE bool KdTreeAccel::traverse(const Ray& ray, Hit* hit) const {
    if (nodes_.empty() || !isTraceableRay(ray)) return false;
    Vec3f invD;
    for (int a = 0; a < 3; ++a) invD[a] = 1.f / ray.d[a];  // ±inf for ±0.0

    // Robustness. Primitive boxes and perfect splits are exact, but the watertight test may report
    // a hit up to a few ulps of the coordinates' magnitude (relative to the ray origin) outside the
    // exact triangle. So the traversal visits every cell that the ray passes within `eps` of:
    // 16 ulps of the largest coordinate involved. Across a plane of axis a that is a distance of
    // eps·|1/d_a| along the ray (large for rays almost parallel to the plane), which pads each
    // visit decision. Segment bounds stay unpadded, so the early exit stays exact.
    const float eps = 0x1p-19f * (sceneMagnitude_ + maxComponent(glm::abs(ray.o)));
    Vec3f padT;
    bool upward[3];
    for (int a = 0; a < 3; ++a) {
        padT[a] = ray.d[a] != 0.f ? eps * std::abs(invD[a]) : 0.f;
        upward[a] = !std::signbit(invD[a]);  // from 1/d, so −0.0 counts as downward
    }
    // Per-axis values as plain arrays for the inner loop: glm's operator[] with a run-time index
    // compiles to a switch, i.e. an unpredictable three-way branch on the axis at every node.
    float orgA[4], invA[4], padA[4];
    uint32_t downMask[4];
    for (int a = 0; a < 3; ++a) orgA[a] = ray.o[a], invA[a] = invD[a], padA[a] = padT[a], downMask[a] = upward[a] ? 0u : ~0u;
    orgA[3] = invA[3] = padA[3] = 0.f, downMask[3] = 0u;

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

    StackEntry stack[kKdMaxDepth + 4];
    int sp = 0;
    uint32_t index = 0;
    const KdNode* nodes = nodes_.data();
    while (true) {
        const KdNode node = nodes[index];
        if (!node.isLeaf()) {
            // The above child lies far from this node in the depth-first layout; fetching it now
            // overlaps its cache miss with this step (it is visited next, or pushed and popped).
            __builtin_prefetch(nodes + node.aboveChild());
            const int a = node.axis();
            const float split = node.split();
            const float tPlane = (split - orgA[a]) * invA[a];
            // The ray is below the plane before tPlane when moving upward. NaN (origin in the plane,
            // direction parallel to it) fails both tests below: both children are visited.
            const uint32_t below = index + 1, above = node.aboveChild();
            const uint32_t swap = (below ^ above) & downMask[a];
            const uint32_t firstChild = below ^ swap, secondChild = above ^ swap;
            const bool skipFirst = tMin > tPlane + padA[a];
            const bool skipSecond = tPlane - padA[a] > tMax;
            // Branch-free step (the three-way choice is a coin toss for incoherent rays): the far
            // entry is always written and kept only when both children are visited.
            const bool both = !skipFirst && !skipSecond;
            stack[sp] = {secondChild, tPlane > tMin ? tPlane : tMin, tMax};
            sp += both;
            index = (skipFirst && !skipSecond) ? secondChild : firstChild;
            tMax = (both && tPlane < tMax) ? tPlane : tMax;
            continue;
        }
        // Leaf.
        const uint32_t count = node.word1 >> 3;
        if (!(node.word1 >> 2 & kMixedFlag)) {
            const TriangleBlock* blocks = triangles_.data() + node.word0;
            for (uint32_t b = 0; b < count; ++b) {
                Candidate c = intersectTriangles<8, kAnyHit>(triRay, blocks[b].p, tHit);
                if (c.lane < 0) continue;
                if constexpr (kAnyHit) return true;
                tHit = c.t, bestU = c.u, bestV = c.v;
                bestBlock = &blocks[b], bestLane = c.lane;
            }
        } else if (intersectMixedLeaf<kAnyHit>(geometry_, ray, &mixedPrims_[node.word0], count, tHit, bestMixed)) {
            if constexpr (kAnyHit) return true;
            bestBlock = nullptr;
        }
        // Early exit: a hit inside this leaf's segment is closer than anything behind it.
        if (tHit <= tMax && tHit < ray.tMax) break;
        // Next segment along the ray, unless the closest hit lies before it.
        do {
            if (sp == 0) goto done;
            --sp;
        } while (stack[sp].tMin > padUp(tHit));
        index = stack[sp].node;
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
__attribute__((target("avx2"))) bool KdTreeAccel::intersectAvx2(const Ray& ray, Hit& hit) const { return traverse<false>(ray, &hit); }
__attribute__((target("avx2"))) bool KdTreeAccel::occludedAvx2(const Ray& ray) const { return traverse<true>(ray, nullptr); }
#else
bool KdTreeAccel::intersectAvx2(const Ray& ray, Hit& hit) const { return traverse<false>(ray, &hit); }
bool KdTreeAccel::occludedAvx2(const Ray& ray) const { return traverse<true>(ray, nullptr); }
#endif

bool KdTreeAccel::intersect(const Ray& ray, Hit& hit) const {
    return useAvx2_ ? intersectAvx2(ray, hit) : traverse<false>(ray, &hit);
}
bool KdTreeAccel::occluded(const Ray& ray) const { return useAvx2_ ? occludedAvx2(ray) : traverse<true>(ray, nullptr); }

}  // namespace tessera
