#pragma once
/// \file kdtree_accel.h
/// Tessera's SAH k-d tree (`--accel kdtree`): built in O(N log N) with perfect splits
/// (kdtree_builder.h, Wald & Havran 2006), 8-byte nodes, front-to-back stack traversal with early
/// exit and separate closest-hit / any-hit kernels (kdtree_traversal.cpp), leaves of 8-wide SIMD
/// watertight triangle blocks (triangle_simd.h). Triangles and spheres; hit records in Embree's convention (accel.h).
#include <string>
#include <vector>

#include "accel/accel.h"
#include "accel/kdtree_builder.h"
#include "geometry/clip.h"

namespace tessera {

class KdTreeAccel final : public Accel {
public:
    KdTreeAccel(const SceneGeometry& geometry, const AccelOptions& options, const KdConfig& config = {});

    std::string_view name() const override { return "kdtree"; }
    bool intersect(const Ray& ray, Hit& hit) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3f bounds() const override { return bounds_; }
    AccelStats stats() const override { return stats_; }

    const KdConfig& config() const { return config_; }
    /// Which traversal runs: "avx2" or "sse2/portable" (the same arithmetic, so the same bits).
    std::string_view isa() const { return useAvx2_ ? "avx2" : "sse2/portable"; }
    /// Runs the portable kernels even where AVX2 is available (tests compare the two).
    void forcePortableKernels() { useAvx2_ = false; }
    const KdBuildStats& buildStats() const { return buildStats_; }
    size_t nodeCount() const { return nodes_.size(); }
    /// The nodes (leaf payloads rewritten to leaf blocks, see kMixedFlag); node 0 is the root.
    const std::vector<KdNode>& nodes() const { return nodes_; }
    /// Checks the tree (Tungsten-style): split planes strictly inside their cells, depth within the
    /// limit, leaf blocks equal to the builder's references, and completeness: every primitive is
    /// referenced by every leaf whose cell its exact clipped extent enters (checked by descending
    /// with the primitive clipped to each cell in double precision). Returns "" or the first problem.
    std::string checkInvariants() const;
    /// FNV-1a hash of nodes and leaves: equal for equal trees (determinism tests).
    uint64_t structureHash() const;

    /// Triangles one leaf block holds (and one kernel call tests).
    static constexpr int kLanes = 8;
    /// Up to kLanes triangles of one leaf, SoA: p[vertex][axis][lane]; unused lanes hold NaN
    /// vertices, which the watertight test rejects without a mask. Their ids live apart
    /// (blockIds_): only the final hit needs them, and incoherent rays are bound by the bytes a
    /// leaf test loads (288 instead of 352).
    struct alignas(32) TriangleBlock {
        float p[3][3][kLanes];
    };
    struct PrimRef {
        uint32_t geomId, primId;
    };
    /// Leaf payload (KdNode::leaf): word0 = first TriangleBlock, or first mixedPrims_ entry when
    /// the leaf holds a sphere; payload = count << 1 | mixed.
    static constexpr uint32_t kMixedFlag = 1u;

private:
    template <bool kAnyHit> bool traverse(const Ray& ray, Hit* hit) const;
    // The same traversal compiled for AVX2 (one instruction per 8-lane leaf step); chosen at run
    // time, so the default build needs no -march=native.
    bool intersectAvx2(const Ray& ray, Hit& hit) const;
    bool occludedAvx2(const Ray& ray) const;
    bool useAvx2_ = false;

    const SceneGeometry& geometry_;
    KdConfig config_;
    std::vector<PrimRef> prims_;        ///< build primitive index → (geomId, primId)
    std::vector<KdNode> nodes_;
    std::vector<uint32_t> primIndices_; ///< the builder's leaf references (invariant checks)
    std::vector<KdNode> builderNodes_;  ///< the builder's nodes (leaf ranges into primIndices_)
    std::vector<TriangleBlock> triangles_;
    std::vector<PrimRef> blockIds_;     ///< kLanes per block: the lanes' (geomId, primId)
    std::vector<PrimRef> mixedPrims_;
    Bounds3f bounds_;   ///< of the geometry (as reported)
    Bounds3f rootCell_; ///< the tree's root cell (union of the primitive boxes)
    float sceneMagnitude_ = 0.f;  ///< largest |coordinate| of the root cell (traversal tolerance)
    AccelStats stats_;
    KdBuildStats buildStats_;
};


}  // namespace tessera
