#include "accel/kdtree_wide.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace tessera {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

uint32_t floatBits(float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    return b;
}

/// Plane index of level `level` on the path of slot `slot` (breadth-first numbering).
int planeOf(int slot, int level) { return (1 << level) - 1 + (slot >> (3 - level)); }

class Collapser {
public:
    Collapser(std::span<const KdNode> binary, std::span<const uint32_t> leafRefs, std::vector<KdWideNode>& out)
        : binary_(binary), leafRefs_(leafRefs), out_(out) {}

    /// A new wide node for the treelet rooted at binary node `b`; returns its byte offset.
    uint32_t collapse(uint32_t b) {
        size_t index = out_.size();
        if (index >= kKdRefIndexLimit) throw std::runtime_error("kdtree: more than 2^26 wide nodes");
        KdWideNode& n = out_.emplace_back();
        for (float& s : n.split) s = kNaN;
        fill(index, b, 0, 0);
        return uint32_t(index * sizeof(KdWideNode));
    }

private:
    // out_ may grow inside the recursion: the node is re-fetched by index after every call.
    void fill(size_t w, uint32_t b, int depth, uint32_t code) {
        const KdNode& n = binary_[b];
        if (n.isLeaf()) {
            uint32_t ref = leafRefs_[b];
            if (ref == kKdNoLeaf) return;  // empty: no slot, never visited
            uint32_t slot = code << (3 - depth);
            out_[w].child[slot] = ref;
            out_[w].meta |= 1u << (KdWideNode::kSlotShift + slot);
            return;
        }
        if (depth == 3) {
            uint32_t ref = collapse(b);
            out_[w].child[code] = ref;
            out_[w].meta |= 1u << (KdWideNode::kSlotShift + code);
            return;
        }
        int plane = (1 << depth) - 1 + int(code);
        out_[w].split[plane] = n.split();
        out_[w].meta |= uint32_t(n.axis()) << (3 * plane);
        fill(w, b + 1, depth + 1, code * 2);
        fill(w, n.aboveChild(), depth + 1, code * 2 + 1);
    }

    std::span<const KdNode> binary_;
    std::span<const uint32_t> leafRefs_;
    std::vector<KdWideNode>& out_;
};

}  // namespace

std::vector<KdWideNode> collapseKdTree(std::span<const KdNode> binary, std::span<const uint32_t> leafRefs) {
    std::vector<KdWideNode> out;
    if (binary.empty()) return out;
    out.reserve(binary.size() / 4 + 1);
    Collapser(binary, leafRefs, out).collapse(0);
    out.shrink_to_fit();
    return out;
}

std::string checkKdWideTree(std::span<const KdWideNode> wide, std::span<const KdNode> binary, std::span<const uint32_t> leafRefs) {
    if (binary.empty()) return wide.empty() ? std::string() : "wide nodes without a binary tree";
    if (wide.empty()) return "no wide nodes";
    std::vector<uint8_t> leafSeen(binary.size(), 0), wideSeen(wide.size(), 0);
    // (wide node, binary node of its treelet root)
    std::vector<std::pair<uint32_t, uint32_t>> todo{{0u, 0u}};
    while (!todo.empty()) {
        auto [w, root] = todo.back();
        todo.pop_back();
        const std::string where = "wide node " + std::to_string(w);
        if (wideSeen[w]++) return where + " reachable more than once";
        const KdWideNode& n = wide[w];
        bool spareBitsClear = true;
        for (int p = 0; p < 7; ++p) spareBitsClear &= !(n.meta >> (3 * p + 2) & 1u);
        if (!spareBitsClear || (n.meta >> (KdWideNode::kSlotShift + 8)) != (KdWideNode::kMetaAlways >> (KdWideNode::kSlotShift + 8)))
            return where + ": bad meta word";
        std::vector<bool> planeUsed(7, false);
        for (int slot = 0; slot < 8; ++slot) {
            // Walk the slot's path in the binary tree, checking the planes the traversal applies.
            uint32_t b = root;
            int depth = 0;
            for (; depth < 3 && !binary[b].isLeaf(); ++depth) {
                int p = planeOf(slot, depth);
                if (floatBits(n.split[p]) != floatBits(binary[b].split()) || n.axis(p) != binary[b].axis())
                    return where + ", slot " + std::to_string(slot) + ": plane " + std::to_string(p) + " differs from binary node " + std::to_string(b);
                planeUsed[size_t(p)] = true;
                b = (slot >> (2 - depth) & 1) ? binary[b].aboveChild() : b + 1;
            }
            bool canonical = (slot & ((1 << (3 - depth)) - 1)) == 0;  // a leaf at depth d: the first slot under it
            bool occupied = n.slotMask() >> slot & 1;
            if (!binary[b].isLeaf()) {  // depth 3: an inner child
                if (!occupied) return where + ", slot " + std::to_string(slot) + ": inner binary node " + std::to_string(b) + " has no slot";
                uint32_t ref = n.child[slot];
                if ((ref & kKdLeafBit) || ref % sizeof(KdWideNode) || ref / sizeof(KdWideNode) >= wide.size())
                    return where + ", slot " + std::to_string(slot) + ": bad inner reference";
                todo.push_back({uint32_t(ref / sizeof(KdWideNode)), b});
                continue;
            }
            bool empty = leafRefs[b] == kKdNoLeaf;
            if (!canonical || empty) {
                if (occupied) return where + ", slot " + std::to_string(slot) + " occupied but its cell is " + (empty ? "an empty leaf" : "covered by another slot");
                continue;
            }
            if (!occupied) return where + ", slot " + std::to_string(slot) + ": non-empty leaf " + std::to_string(b) + " has no slot";
            if (n.child[slot] != leafRefs[b] || !(n.child[slot] & kKdLeafBit))
                return where + ", slot " + std::to_string(slot) + ": reference differs from leaf " + std::to_string(b);
            if (leafSeen[b]++) return "leaf " + std::to_string(b) + " reachable more than once";
        }
        for (int p = 0; p < 7; ++p) {
            if (!planeUsed[size_t(p)] && (!std::isnan(n.split[p]) || n.axis(p) != 0))
                return where + ": plane " + std::to_string(p) + " lies below a leaf but is not NaN";
        }
    }
    for (size_t w = 0; w < wide.size(); ++w)
        if (!wideSeen[w]) return "wide node " + std::to_string(w) + " unreachable";
    // Every non-empty binary leaf reachable from the binary root must have been reached.
    std::vector<uint32_t> stack{0u};
    while (!stack.empty()) {
        uint32_t b = stack.back();
        stack.pop_back();
        if (!binary[b].isLeaf()) {
            stack.push_back(b + 1), stack.push_back(binary[b].aboveChild());
            continue;
        }
        if (leafRefs[b] != kKdNoLeaf && !leafSeen[b]) return "non-empty leaf " + std::to_string(b) + " unreachable through the wide nodes";
    }
    return {};
}

}  // namespace tessera
