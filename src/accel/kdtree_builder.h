#pragma once
/// \file kdtree_builder.h
/// SAH k-d tree builder in O(N log N) after Wald & Havran 2006, "On building fast kd-trees for ray
/// tracing, and on doing that in O(N log N)" (IEEE RT'06): split-candidate events are sorted once,
/// every node sweeps them per axis with left/right/planar counts, and the sorted lists are split
/// stably to the children; only primitives that straddle the chosen plane are clipped to the child
/// cells ("perfect splits") and get freshly sorted events, merged into the children's lists.
/// Nodes above `KdConfig::binnedAbove` references choose their plane by binning instead and sort
/// their events only once they are small (a hybrid; still O(N log N)).
///
/// Like the BVH builder it sees primitive *boxes* (so triangles and spheres share it); perfect
/// splits additionally ask the caller to clip one primitive to a cell (`KdClipFunction`).
#include <cstdint>
#include <cstring>
#include <functional>
#include <span>
#include <vector>

#include "core/bounds.h"

namespace tessera {

/// Parameters of the SAH build. The cost of a split at plane p of cell V is (Wald & Havran 2006,
/// Section 3, "SAH" with the empty-space factor λ):
///   C(p) = λ(p) · (C_trav + C_isect · (A_L/A_V · B(N_L) + A_R/A_V · B(N_R))),
///   λ(p) = 1 − emptyBonus when N_L = 0 or N_R = 0 and the empty child spans at least
///          emptyCutMinFraction of the cell along the split axis, else 1,
/// where A are surface areas and B(n) = max(1, n / sahBlockSize) (n > 0) the SIMD leaf blocks a leaf
/// of n primitives costs (ours tests 8 triangles at once, triangle_simd.h, so 1..8 triangles cost one
/// test; linear beyond, not rounded up: see KdBuilder::blocks). A leaf costs C_isect·B(N).
/// Defaults chosen on the Stanford dragons with the traversal of kdtree_traversal.cpp: across the
/// settings tried (C_trav 1–8, C_isect 1–10, bonus 0–0.5, blocks of 4 or 8) rays/s moved less than
/// the run-to-run noise, while lower C_trav/C_isect ratios raised memory and build time, so the
/// defaults favour those (the k-d tree section of writeup.md).
struct KdConfig {
    /// Cost of one traversal step (inner node), relative to intersectionCost.
    float traversalCost = 3.0f;
    /// Cost of intersecting one leaf block of `sahBlockSize` primitives.
    float intersectionCost = 1.5f;
    /// Primitives one leaf test handles together; 1 gives the classic per-primitive SAH.
    int sahBlockSize = 8;
    /// Fraction of the cost saved when one child is empty (W&H use λ = 0.8, i.e. 0.2; pbrt 0.5).
    /// 0.5: against 0.2, diffuse rays 3-7% faster on Conference and Sibenik (a 200k-triangle dragon:
    /// within its noise), other ray kinds and build time within 2%, memory equal or less.
    float emptyBonus = 0.5f;
    /// The bonus needs an empty child at least this thick (fraction of the cell along the axis).
    /// Without it, once C_trav < emptyBonus/(1 − emptyBonus)·C_isect·B(N), cutting off *any* sliver
    /// of empty space looks profitable and every leaf descends to the depth limit.
    float emptyCutMinFraction = 0.1f;
    /// Depth limit; 0 means 8 + 1.3·log2 N (pbrt-v3, W&H), capped at kKdMaxDepth.
    int maxDepth = 0;
    /// Splits whose SAH cost exceeds the leaf cost are still tried this many times along a path
    /// (they may pay off deeper down, pbrt-v3's "bad refines"); a subtree that in the end costs more
    /// than a leaf is retracted into one. 0 by default: with 1, the build of the Conference room
    /// retracted 15,724 subtrees (against 22,048 inner nodes kept), and the trees of Conference and
    /// of a 200k-triangle dragon had the same SAH cost (to 4e-6) for 15-20% more build time.
    int maxBadRefines = 0;
    /// Clip straddling primitives to the child cells (W&H "perfect splits"); false keeps their boxes.
    bool perfectSplits = true;
    /// Nodes with more primitives than this choose their split from `binCount` equal bins per axis
    /// over their (clipped) primitive boxes instead of sweeping sorted events; at or below it, a
    /// node sorts its events once and the exact W&H sweep takes over for its subtree. 0 sweeps
    /// exactly everywhere (the pure W&H build). Binning touches each reference once per level with
    /// no event lists to rewrite (Shevtsov et al. 2007, "Highly parallel fast KD-tree
    /// construction", bin k-d trees the same way); the big upper levels hardly need exact planes,
    /// while the levels near the surface, where rays spend their steps, keep them. Both parts are
    /// O(n) per level: still O(N log N).
    /// 1,024 with 128 bins gives trees of the SAH cost of 4,096 with 64 bins (within ±0.3% on
    /// Conference, Sibenik and a 200k-triangle dragon) in about 10% less build time.
    uint32_t binnedAbove = 1024;
    /// Bins per axis for the binned levels (candidate planes at the bins' inner boundaries).
    int binCount = 128;
    /// Sibling subtrees over more than this many references are built in parallel (TBB tasks, when
    /// the calling arena has several threads); 0 builds serially. The tree is the same either way.
    uint32_t parallelAbove = 1024;
};

/// The hard cap on depth (traversal stacks hold this many entries).
inline constexpr int kKdMaxDepth = 60;

/// 8-byte node (pbrt-v3 / Wald's thesis layout). Inner: `word0` the split position's bits,
/// `word1 = aboveChild << 2 | axis`; the below child is the next node. Leaf: `word1 & 3 == 3`,
/// `word0` and `word1 >> 2` are the leaf's payload (builder: first index into primIndices, count;
/// the accel rewrites them to its leaf blocks).
struct KdNode {
    uint32_t word0 = 0, word1 = 3;
    bool isLeaf() const { return (word1 & 3u) == 3u; }
    int axis() const { return int(word1 & 3u); }
    uint32_t aboveChild() const { return word1 >> 2; }
    /// The split position (the bits of word0).
    float split() const {
        float f;
        std::memcpy(&f, &word0, 4);
        return f;
    }
    static KdNode inner(int axis, float split, uint32_t aboveChild);
    static KdNode leaf(uint32_t first, uint32_t payload);
};

/// Returns the bounds of primitive `prim` clipped to `cell` (empty when it does not overlap it);
/// must be conservative: every point of the primitive inside the cell lies in the returned box.
using KdClipFunction = std::function<Bounds3f(uint32_t prim, const Bounds3f& cell)>;

struct KdBuildStats {
    size_t innerNodes = 0, leaves = 0, emptyLeaves = 0, references = 0;
    size_t depthLimitHits = 0, retractions = 0;
    size_t eventsSwept = 0;  ///< sum over exact (swept) nodes of their event-list lengths
    size_t refsBinned = 0;   ///< sum over binned nodes of their reference counts
    int maxDepth = 0, depthLimit = 0;
    double sahCost = 0.0;  ///< expected cost of the tree (root-relative SAH, no empty bonus)
};

struct KdTree {
    std::vector<KdNode> nodes;           ///< node 0 is the root; absent when there are no primitives
    std::vector<uint32_t> primIndices;   ///< leaves reference contiguous ranges
    Bounds3f bounds;                     ///< the root cell
    KdBuildStats stats;
};

/// Builds the tree over primitives with the given (finite, non-empty) boxes. `clip` may be empty, in
/// which case straddling primitives keep their box clipped to the child cell; it is called from
/// several threads at once. Deterministic: the same tree for any number of threads.
KdTree buildKdTree(std::span<const Bounds3f> primBounds, const KdClipFunction& clip, const KdConfig& config);

}  // namespace tessera
