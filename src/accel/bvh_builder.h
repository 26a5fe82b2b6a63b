#pragma once
/// \file bvh_builder.h
/// Binned SAH builder of a binary BVH. It sees only primitive bounds and centroids (madmann91/bvh,
/// Embree's PrimRef), so triangles, spheres and anything else with a box share it. The wide BVH
/// (bvh_accel.h) collapses its output.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <span>
#include <vector>

#include "core/bounds.h"

namespace tessera {

/// Parameters of the binned SAH build (Wald 2007, "On fast Construction of SAH-based Bounding Volume
/// Hierarchies": cost = C_trav + C_isect · (A_L·N_L + A_R·N_R) / A, with the primitive counts
/// rounded up to whole leaf blocks as Embree does, because a leaf tests `sahBlockSize` primitives at
/// once). Defaults chosen on the Stanford dragon with the BVH8 traversal of bvh_traversal.cpp.
struct BvhConfig {
    /// Cost of visiting one (binary) node, relative to intersectionCost.
    float traversalCost = 1.0f;
    /// Cost of intersecting one leaf block of `sahBlockSize` primitives.
    float intersectionCost = 1.0f;
    /// Primitives a leaf test handles together (the SIMD width of the leaf test).
    int sahBlockSize = 4;
    /// Largest leaf; larger nodes are always split (at the object median when SAH finds no split).
    /// Eight (two 4-wide blocks, leaving SAH to choose between one and two) rather than four: fewer
    /// wide nodes and less memory, faster to build and to trace on the dragon (docs/perf-log.md).
    int maxLeafSize = 8;
    /// Number of centroid bins per axis (all three axes are binned); 16–32 is the usual range.
    int binCount = 32;
    /// Subtrees with at least this many primitives are built as parallel tasks, and nodes with at
    /// least 4× as many bin their primitives in parallel. Output does not depend on it.
    int parallelThreshold = 4096;
    /// Beyond this depth splits are object medians, which bounds the depth (and traversal stacks)
    /// even for pathological inputs where SAH peels off one primitive at a time.
    int maxSahDepth = 48;
    /// Spatial splits (SBVH, bvh_spatial.h; `--accel sbvh`): off in the default build.
    bool spatialSplits = false;
    /// Extra references spatial splits may create, as a fraction of the primitive count.
    float spatialSplitBudget = 0.3f;
    /// Spatial splits are tried only where the best object split's children overlap by more than
    /// this fraction of the root's surface area (Stich et al. 2009, α = 1e-5).
    float spatialSplitAlpha = 1e-5f;
};

/// One node of the binary tree. Inner: `count == 0`, children at `left` and `right`. Leaf: primitives
/// `primIndices[first .. first + count)`.
struct BvhBuildNode {
    Bounds3f bounds;
    uint32_t count = 0;
    uint32_t left = 0;   ///< inner: left child; leaf: first index into primIndices
    uint32_t right = 0;  ///< inner: right child
    bool isLeaf() const { return count > 0; }
    uint32_t first() const { return left; }
};

/// The builder's output. Node 0 is the root (absent when there are no primitives). Slots of `nodes`
/// not reachable from the root exist (each subtree reserves 2n − 1 slots so that subtrees can be
/// built in parallel and still land at the same indices whatever the thread count), unwritten.
struct BinaryBvh {
    /// 2n − 1 slots, allocated without being written: most stay unused (leaves hold several
    /// primitives), and value-initialising ~60 MB of nodes for the dragon cost a tenth of the build
    /// in page faults alone. Only slots the builder writes are ever read.
    struct NodeArray {
        struct Free {
            void operator()(BvhBuildNode* p) const { std::free(p); }
        };
        std::unique_ptr<BvhBuildNode[], Free> data;
        size_t size = 0;
        void allocate(size_t n) {
            // BvhBuildNode is an aggregate, hence an implicit-lifetime type: malloc'd storage holds
            // its objects once written (C++20, P0593).
            data.reset(static_cast<BvhBuildNode*>(std::malloc(n * sizeof(BvhBuildNode))));
            if (n && !data) throw std::bad_alloc();
            size = n;
        }
        BvhBuildNode& operator[](size_t i) { return data[i]; }
        const BvhBuildNode& operator[](size_t i) const { return data[i]; }
    };
    NodeArray nodes;
    std::vector<uint32_t> primIndices;  ///< primitive order: leaves reference contiguous ranges
    uint32_t maxDepth = 0;
};

/// Builds the tree over primitives with the given bounds, binned by their centres (primitives whose
/// bounds are empty or not finite must be left out by the caller). Runs in the calling thread's TBB
/// arena; the tree is identical for any number of threads.
BinaryBvh buildBinaryBvh(std::span<const Bounds3f> primBounds, const BvhConfig& config);

}  // namespace tessera
