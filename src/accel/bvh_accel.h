#pragma once
/// \file bvh_accel.h
/// Tessera's own BVH: a binned-SAH binary tree (bvh_builder.h) collapsed into an 8-wide BVH with
/// structure-of-arrays nodes (bvh_accel.cpp), traversed with SIMD box tests and 4-wide watertight
/// triangle tests (bvh_traversal.cpp). Triangles and spheres; hit records identical in convention
/// to Embree's (see accel.h).
#include <string>
#include <vector>

#include <span>

#include "accel/accel.h"
#include "accel/bvh_builder.h"
#include "accel/kernel_isa.h"
#include "accel/primitive_refs.h"
#include "accel/triangle_simd.h"
#include "core/huge_page_allocator.h"

namespace tessera {

class BvhAccel final : public Accel {
public:
    BvhAccel(const SceneGeometry& geometry, const AccelOptions& options, const BvhConfig& config = {});

    std::string_view name() const override { return config_.spatialSplits ? "sbvh" : "bvh"; }
    bool intersect(const Ray& ray, Hit& hit) const override;
    bool intersectCoherent(const Ray& ray, Hit& hit) const override;
    bool occluded(const Ray& ray) const override;
    Bounds3f bounds() const override { return bounds_; }
    AccelStats stats() const override { return stats_; }

    /// Which traversal kernels run: "avx2" or "sse2/portable".
    std::string_view isa() const { return isa_.name(); }
    /// Runs the portable kernels even where AVX2 is available (tests compare the two), and back.
    void forcePortableKernels() { isa_.forcePortable(); }
    void allowAvx2Kernels() { isa_.useBest(); }
    /// Checks the tree: every primitive with finite bounds reachable exactly once, each child box
    /// inside its parent's box, every primitive inside its leaf's box (with spatial splits: reachable
    /// at least once, and meeting each leaf box that holds it), each node's lanes ordered by the
    /// references below them, most first (the any-hit order). Returns "" or the first problem.
    std::string checkInvariants() const;
    /// Primitive references in the leaves: the primitive count, or more where spatial splits
    /// placed parts of a primitive in several leaves.
    size_t referenceCount() const;
    /// FNV-1a hash of the nodes and leaf blocks: equal for equal trees (determinism tests).
    uint64_t structureHash() const;

    /// 8-wide node: child boxes as SoA (bounds[axis][lane] lower, bounds[3 + axis][lane] upper; empty
    /// lanes hold an inverted box that no ray enters) and child references (see kLeafBit).
    struct alignas(32) Node8 {
        float bounds[6][8];
        uint32_t child[8];
    };
    /// Up to four triangles of one leaf, SoA: p[vertex][axis][lane]. Unused lanes hold NaN vertices,
    /// which the watertight test rejects without a separate mask. geomId carries kMaskedLaneBit
    /// where the lane's mesh is a cut-out (its alpha mask filters the hits).
    struct alignas(16) Triangle4 {
        float p[3][3][4];
        uint32_t geomId[4];
        uint32_t primId[4];
    };
    /// Set in Triangle4::geomId for a lane whose mesh has an alpha mask: the traversal reads it only
    /// when that lane is a leaf's answer, and only in scenes that have cut-outs (the kMasked kernels).
    static constexpr uint32_t kMaskedLaneBit = 0x80000000u;

    /// Child reference: inner node (its byte offset in the node array, once built), or a leaf
    /// (kLeafBit). Triangle-only leaf: the first Triangle4 block's byte offset / 16, << 2 | (blocks − 1).
    /// Leaf of spheres (kMixedBit; never beside triangles, separateLeafKinds): first mixedPrims_ index << 4 | count.
    static constexpr uint32_t kLeafBit = 0x80000000u;
    static constexpr uint32_t kMixedBit = 0x40000000u;

private:
    /// kCoherent: the child-ordering path for rays whose branches predict well (intersectCoherent).
    /// kMasked: the kernels of scenes with cut-outs (alpha masks); without it, no alpha code at all,
    /// so scenes without cut-outs run exactly the kernels they ran before masks existed.
    template <bool kAvx, bool kCoherent, bool kMasked> bool intersectImpl(const Ray& ray, Hit& hit) const;
    template <bool kAvx, bool kMasked> bool occludedImpl(const Ray& ray) const;
    // The kernels compiled for AVX2: defined, and called, on x86 only.
    bool intersectAvx2(const Ray& ray, Hit& hit) const;
    bool intersectCoherentAvx2(const Ray& ray, Hit& hit) const;
    bool occludedAvx2(const Ray& ray) const;
    /// The kernels of scenes with cut-outs (hasCutOuts_), each ISA: out of line, apart from the others.
    template <bool kCoherent> bool intersectMasked(const Ray& ray, Hit& hit) const;
    bool occludedMasked(const Ray& ray) const;
    template <bool kCoherent> bool intersectMaskedAvx2(const Ray& ray, Hit& hit) const;
    bool occludedMaskedAvx2(const Ray& ray) const;

    /// Block `tri`'s test redone with the alpha masks (its answer was a masked lane): the nearest
    /// kept lane, or lane −1 when none is kept.
    TriangleCandidate filterMaskedLanes(const TriRay& r, const Triangle4& tri, float tMax) const;
    void prefetchChild(uint32_t ref) const;
    /// References in the subtree of `ref`; sets `problem` where a node's lanes are out of order.
    uint32_t subtreeReferences(uint32_t ref, std::string& problem) const;
    std::string checkLaneOrder() const;
    void prefetchAny(uint32_t ref) const;
    /// The first Triangle4 block of a triangle leaf reference.
    const Triangle4* leafBlocks(uint32_t ref) const {
        return reinterpret_cast<const Triangle4*>(reinterpret_cast<const char*>(triangles_.data()) + size_t(ref & 0x3ffffffcu) * 4);
    }
    /// The inner node an inner child reference (a byte offset into nodes_) names.
    const Node8& node(uint32_t ref) const { return *reinterpret_cast<const Node8*>(reinterpret_cast<const char*>(nodes_.data()) + ref); }
    /// A triangle leaf of the binary tree (primIndices[first, first + count)) and its first block.
    struct LeafBlocks {
        uint32_t first, count, firstBlock;
    };
    /// The binary tree over the gathered primitives (prims_, boxes `primBounds`).
    BinaryBvh buildBinaryTree(std::span<const Bounds3f> primBounds) const;
    /// Turns every leaf holding both triangles and spheres into an inner node over a triangle leaf
    /// and a sphere leaf: a leaf with a sphere is tested one primitive at a time in scalar double
    /// precision (mixed_leaf.h), so the triangles beside a sphere lost the 4-wide test. In
    /// SmallVCM's Cornell box (20 triangles and a large sphere) mixed leaves took two thirds of the
    /// shadow rays' instructions.
    void separateLeafKinds(BinaryBvh& bin, std::span<const Bounds3f> primBounds) const;
    /// What a collapse writes: wide nodes in preorder, the triangle leaves to fill (their blocks
    /// numbered from 0) and the sphere leaves' primitives. References inside are relative to the
    /// part's own arrays until buildWideTree joins the parts.
    struct WideParts {
        std::vector<Node8> nodes;
        std::vector<LeafBlocks> leaves;
        uint32_t blocks = 0;
        std::vector<PrimRef> mixed;
    };
    /// Collapses the binary tree into nodes_, triangles_ and mixedPrims_: the root's subtrees in
    /// parallel, each into its own WideParts, joined in child order (the serial preorder, bit for
    /// bit, whatever the thread count).
    void buildWideTree(const BinaryBvh& bin);
    /// The wide node over binary node `binNode`'s subtree (and, first, those below it) in `out`:
    /// returns its reference; `prims` gets the subtree's primitive count.
    uint32_t collapse(const BinaryBvh& bin, uint32_t binNode, WideParts& out, uint32_t& prims) const;
    uint32_t makeLeaf(const BinaryBvh& bin, const BvhBuildNode& leaf, WideParts& out) const;
    void fillLeaves(const BinaryBvh& bin, const std::vector<LeafBlocks>& leaves, uint32_t blocks);

    const SceneGeometry& geometry_;
    BvhConfig config_;
    std::vector<PrimRef> prims_;  ///< build primitive index → (geomId, primId)
    uint32_t triangleRefs_ = 0;   ///< prims_[0, triangleRefs_) are triangles, the rest spheres
    std::vector<Node8, HugePageAllocator<Node8>> nodes_;    ///< node 0 is the root (absent for an empty scene)
    std::vector<Triangle4, HugePageAllocator<Triangle4>> triangles_;
    std::vector<PrimRef> mixedPrims_;
    Bounds3f bounds_;
    AccelStats stats_;
    KernelIsa isa_;
    /// Some mesh with triangles has an alpha mask: the queries run the kMasked kernels.
    bool hasCutOuts_ = false;
};

}  // namespace tessera
