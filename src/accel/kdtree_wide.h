#pragma once
/// \file kdtree_wide.h
/// Wide k-d tree nodes: the binary k-d tree collapsed, after the build, into treelets of up to three
/// levels (up to 7 split planes, up to 8 child slots), each one cache line and traversed as one unit
/// with 8 SIMD lanes (kdtree_traversal.cpp). This is the collapse of a binary tree into wide nodes
/// that Wald et al. 2008 ("Getting Rid of Packets", Section 3) apply to BVHs, done for a k-d tree:
/// the tree stays a k-d tree (binary splits, the W&H SAH build untouched, every cell the same); only
/// the unit of traversal changes. Empty leaves get no slot, so rays never step into them: on the
/// dragon two thirds of the leaves a ray reached in the binary traversal were empty.
///
/// A slot's cell inside the treelet is the intersection of at most three half-spaces: those of the
/// planes on its path from the treelet root, each with a side. The traversal clips the ray's segment
/// to them in all slots at once (Havran 2000, PhD thesis "Heuristic Ray Shooting Algorithms",
/// Section 4, gives the binary near/far classification that each level of a slot repeats).
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "accel/kdtree_builder.h"

namespace tessera {

/// One treelet, 64 bytes. Slot s ∈ [0, 8) is a path from the treelet root: bit 2 of s the side of
/// plane level 0, bit 1 of level 1, bit 0 of level 2 (1 = above the plane). A leaf reached at depth
/// d < 3 sits in the slot whose lower 3 − d bits are 0; the other slots under it stay empty.
struct alignas(64) KdWideNode {
    /// Planes in breadth-first order: [0] the treelet root, [1 + b0] its children, [3 + 2·b0 + b1]
    /// its grandchildren (b0, b1 the sides taken). NaN where the treelet has no plane (the path ended
    /// in a leaf): a NaN plane distance leaves every lane's interval unchanged (NaN-ignoring min/max),
    /// so a missing plane costs no special case.
    float split[7];
    /// Bits 3p..3p+1: the axis of plane p (0 where there is none), bit 3p + 2 clear, so that the
    /// traversal turns (meta >> 3p) into a lane permutation index with one `or` (vpermps reads the
    /// low three bits only); bits 21..28: the slots holding a child; bit 30 always set. The traversal
    /// loads split[] as 8 lanes, this word being the 8th: with bit 30 set and bit 29 clear it is a
    /// normal finite float, never a denormal that would slow the lane's arithmetic.
    uint32_t meta = kMetaAlways;
    /// Slot references: an inner node as its byte offset into the node array (a multiple of 64, bit 0
    /// clear); a leaf with bit 0 set, see kKdLeafBit.
    uint32_t child[8] = {};

    static constexpr uint32_t kMetaAlways = 1u << 30;
    static constexpr int kSlotShift = 21;
    int axis(int plane) const { return int(meta >> (3 * plane) & 3u); }
    uint32_t slotMask() const { return meta >> kSlotShift & 0xffu; }
};
static_assert(sizeof(KdWideNode) == 64, "one cache line per wide node");

/// Leaf references in a wide node: bit 0 set; bit 1 kKdMaskedLeafBit; bits 2..5 the number of triangle blocks (1..15) and
/// bits 6..31 the first block, or bits 2..5 zero and bits 6..31 an index into the leaf table (leaves
/// of more than 15 blocks, or holding a sphere).
inline constexpr uint32_t kKdLeafBit = 1u;
/// Set in a leaf reference (bit 1) when the leaf holds a triangle of a cut-out mesh (alpha mask):
/// only then does the traversal look up whether the triangle it hit is masked.
inline constexpr uint32_t kKdMaskedLeafBit = 2u;
inline constexpr uint32_t kKdMaxInlineBlocks = 15;
inline constexpr uint32_t kKdRefIndexLimit = 1u << 26;
/// Marks an empty leaf in the per-binary-node reference list (it gets no slot).
inline constexpr uint32_t kKdNoLeaf = ~0u;

/// A leaf the reference cannot describe inline: first block (or first mixed primitive), payload =
/// count << 1 | mixed, as in the builder's KdNode leaves.
struct KdLeafRecord {
    uint32_t first, payload;
};

/// Collapses the binary tree into wide nodes (node 0 the root, depth-first, parents first).
/// `leafRefs[i]` is the reference of binary leaf i, kKdNoLeaf when it is empty.
std::vector<KdWideNode> collapseKdTree(std::span<const KdNode> binary, std::span<const uint32_t> leafRefs);

/// Checks that the wide nodes describe exactly the binary tree: every slot's planes (split bits,
/// axis, side) equal its path's planes, levels below a leaf hold no plane, empty leaves have no slot,
/// every non-empty leaf is reachable exactly once with its reference, and every wide node once.
/// Returns "" or the first problem.
std::string checkKdWideTree(std::span<const KdWideNode> wide, std::span<const KdNode> binary, std::span<const uint32_t> leafRefs);

}  // namespace tessera
