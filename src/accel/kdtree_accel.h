#pragma once
/// \file kdtree_accel.h
/// Tessera's SAH k-d tree (`--accel kdtree`): built in O(N log N) with perfect splits
/// (kdtree_builder.h, Wald & Havran 2006) into 8-byte binary nodes, then collapsed into one-cache-line
/// treelets of up to three levels (kdtree_wide.h) that the front-to-back stack traversal decides in
/// one 8-lane step, with early exit and separate closest-hit / any-hit kernels
/// (kdtree_traversal.cpp); leaves of 8-wide SIMD watertight triangle blocks (triangle_simd.h).
/// Triangles and spheres; hit records in Embree's convention (accel.h).
#include <string>
#include <vector>

#include <span>

#include "accel/accel.h"
#include "accel/kdtree_builder.h"
#include "accel/kernel_isa.h"
#include "accel/primitive_refs.h"
#include "accel/kdtree_wide.h"
#include "accel/triangle_simd.h"
#include "geometry/clip.h"

namespace tessera {

class KdTreeAccel final : public Accel {
public:
    KdTreeAccel(const SceneGeometry& geometry, const AccelOptions& options, const KdConfig& config = {});

    std::string_view name() const override { return "kdtree"; }
    bool intersect(const Ray& ray, Hit& hit) const override;
    bool intersectCoherent(const Ray& ray, Hit& hit) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3f bounds() const override { return bounds_; }
    AccelStats stats() const override { return stats_; }

    /// Which traversal runs: "avx2" or "sse2/portable" (the same arithmetic, so the same bits).
    std::string_view isa() const { return isa_.name(); }
    /// Runs the portable kernels even where AVX2 is available (tests compare the two).
    void forcePortableKernels() { isa_.forcePortable(); }
    const KdBuildStats& buildStats() const { return buildStats_; }
    /// The builder's binary nodes (leaf payloads index its references); node 0 is the root.
    const std::vector<KdNode>& nodes() const { return nodes_; }
    /// The wide nodes the traversal runs on (the binary tree collapsed, kdtree_wide.h).
    const std::vector<KdWideNode>& wideNodes() const { return wide_; }
    /// Checks the tree (Tungsten-style): split planes strictly inside their cells, depth within the
    /// limit, leaf blocks equal to the builder's references, wide nodes describing exactly the binary
    /// tree's cells (checkKdWideTree), and completeness: every primitive is referenced by every leaf
    /// whose cell its exact clipped extent enters (checked by descending with the primitive clipped
    /// to each cell in double precision). Returns "" or the first problem.
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
    /// Leaf payload (KdLeafRecord::payload): count << 1 | mixed; mixed leaves (holding a sphere)
    /// list mixedPrims_ entries, the others TriangleBlocks.
    static constexpr uint32_t kMixedFlag = 1u;

private:
    struct LeafSpan {
        uint32_t first, count;
        bool mixed;
    };
    /// Decodes a wide node's leaf reference (layout at kKdLeafBit, kdtree_wide.h).
    LeafSpan leafSpan(uint32_t ref) const {
        uint32_t count = ref >> 2 & 15u, first = ref >> 6;
        if (count) return {first, count, false};
        KdLeafRecord rec = leafTable_[first];
        return {rec.first, rec.payload >> 1, bool(rec.payload & kMixedFlag)};
    }
    /// kCoherent: branches on the entered-slot count (camera rays, intersectCoherent).
    /// kMasked: the kernels of scenes with cut-outs (alpha masks); without it, no alpha code at all,
    /// so scenes without cut-outs run exactly the kernels they ran before masks existed.
    template <bool kAvx, bool kCoherent, bool kMasked, bool kAnyHit> bool intersectImpl(const Ray& ray, Hit& hit) const;
    // The same traversal compiled for AVX2 (one instruction per 8-lane leaf step): defined, and
    // called, on x86 only (kernel_isa.h).
    bool intersectAvx2(const Ray& ray, Hit& hit) const;
    bool intersectCoherentAvx2(const Ray& ray, Hit& hit) const;
    bool occludedAvx2(const Ray& ray) const;
    /// The kernels of scenes with cut-outs (hasCutOuts_), each ISA: out of line, apart from the others.
    template <bool kCoherent> bool intersectMasked(const Ray& ray, Hit& hit) const;
    bool occludedMasked(const Ray& ray) const;
    template <bool kCoherent> bool intersectMaskedAvx2(const Ray& ray, Hit& hit) const;
    bool occludedMaskedAvx2(const Ray& ray) const;

    /// The binary tree over the gathered primitives (prims_, boxes `primBounds`).
    KdTree buildBinaryTree(std::span<const Bounds3f> primBounds) const;
    /// Turns the binary tree's leaves into triangle blocks or mixed lists, and leafRefs_.
    void buildLeafBlocks();
    /// The wide-node reference of a leaf over prims_[order[0 .. count)], its blocks appended.
    uint32_t makeLeaf(const uint32_t* order, uint32_t count);
    /// True when one of prims_[order[0 .. count)] (triangles) belongs to a mesh with an alpha mask.
    bool holdsMaskedTriangle(const uint32_t* order, uint32_t count) const;
    /// Block `block`'s answer `c` (lane ≥ 0) in a leaf holding cut-out triangles: `c` itself when
    /// its triangle is opaque, otherwise the block redone with the alpha masks (the nearest kept
    /// lane; lane −1 when none is kept). Any-hit answers (no barycentrics) are fine as `c`.
    TriangleCandidate filterMaskedLanes(const TriRay8& r, size_t block, float tMax, TriangleCandidate c) const;
    /// A leaf-table entry's reference (leaves a reference cannot describe inline).
    uint32_t tableRef(KdLeafRecord rec);

    KernelIsa isa_;

    const SceneGeometry& geometry_;
    KdConfig config_;
    std::vector<PrimRef> prims_;        ///< build primitive index → (geomId, primId)
    std::vector<KdNode> nodes_;         ///< the builder's binary nodes (leaf ranges into primIndices_)
    std::vector<uint32_t> primIndices_; ///< the builder's leaf references (invariant checks)
    std::vector<uint32_t> leafRefs_;    ///< per binary node: its wide-node leaf reference, or kKdNoLeaf
    std::vector<KdWideNode> wide_;
    std::vector<KdLeafRecord> leafTable_;  ///< leaves a reference cannot describe inline
    std::vector<TriangleBlock> triangles_;
    std::vector<PrimRef> blockIds_;     ///< kLanes per block: the lanes' (geomId, primId)
    std::vector<PrimRef> mixedPrims_;
    Bounds3f bounds_;   ///< of the geometry (as reported)
    Bounds3f rootCell_; ///< the tree's root cell (union of the primitive boxes)
    float sceneMagnitude_ = 0.f;  ///< largest |coordinate| of the root cell (traversal tolerance)
    bool hasCutOuts_ = false;  ///< some mesh with triangles has an alpha mask: the kMasked kernels run
    AccelStats stats_;
    KdBuildStats buildStats_;
};


}  // namespace tessera
