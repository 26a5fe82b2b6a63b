/// \file kdtree_accel.cpp
/// Building the k-d tree: the binary SAH tree (kdtree_builder.h), its leaves turned into blocks of
/// eight triangles, the tree collapsed into wide nodes (kdtree_wide.h); and the tree's invariant
/// check. The traversal kernels are in kdtree_traversal.cpp.
#include "core/fnv1a.h"
#include "accel/kdtree_accel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <tbb/task_arena.h>

#include "accel/triangle_simd.h"

namespace tessera {

KdTreeAccel::KdTreeAccel(const SceneGeometry& geometry, const AccelOptions& options, const KdConfig& config)
    : geometry_(geometry), config_(config) {
    auto start = std::chrono::steady_clock::now();
    bounds_ = geometry.bounds();
    for (const TriangleMesh& m : geometry.meshes) hasCutOuts_ |= m.alphaMask && !m.triangles.empty();
    // Exact boxes: padding them would make neighbours sharing a vertex straddle every plane through
    // it. The traversal is conservative instead (kdtree_traversal.cpp).
    KdTree tree;
    auto build = [&] {  // the gathering too runs in the build's TBB arena
        GatheredPrimitives gathered = gatherPrimitives(geometry, /*padTriangles=*/false);
        prims_ = std::move(gathered.refs);
        tree = buildBinaryTree(gathered.bounds);
    };
    if (options.threads > 0) tbb::task_arena(options.threads).execute(build);  // the builder's TBB tasks
    else build();
    rootCell_ = tree.bounds;
    sceneMagnitude_ = std::max(maxComponent(glm::abs(rootCell_.lower)), maxComponent(glm::abs(rootCell_.upper)));
    if (!std::isfinite(sceneMagnitude_)) sceneMagnitude_ = 0.f;
    buildStats_ = tree.stats;
    nodes_ = std::move(tree.nodes);
    primIndices_ = std::move(tree.primIndices);
    buildLeafBlocks();
    wide_ = collapseKdTree(nodes_, leafRefs_);

    stats_.primitives = geometry.primitiveCount();
    // What the traversal reads: wide nodes, leaf table and leaf blocks (the binary nodes are kept
    // for the invariant checks only).
    stats_.memoryBytes = wide_.size() * sizeof(KdWideNode) + leafTable_.size() * sizeof(KdLeafRecord) +
                         triangles_.size() * sizeof(TriangleBlock) + blockIds_.size() * sizeof(PrimRef) +
                         mixedPrims_.size() * sizeof(PrimRef);
    stats_.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

KdTree KdTreeAccel::buildBinaryTree(std::span<const Bounds3f> primBounds) const {
    // Perfect splits: the triangle clipped to the cell (in double, rounded outward). Spheres keep
    // their box (the builder intersects it with the cell).
    KdClipFunction clip = [&](uint32_t prim, const Bounds3f& cell) -> Bounds3f {
        PrimRef ref = prims_[prim];
        if (ref.geomId == geometry_.sphereGeomId()) return primBounds[prim];
        Vec3f v[3];
        triangleVertices(geometry_, ref, v);
        return clipTriangleBounds(v[0], v[1], v[2], cell);
    };
    return buildKdTree(primBounds, clip, config_);
}

uint32_t KdTreeAccel::tableRef(KdLeafRecord rec) {
    if (leafTable_.size() >= kKdRefIndexLimit) throw std::runtime_error("kdtree: more than 2^26 large leaves");
    leafTable_.push_back(rec);
    return kKdLeafBit | uint32_t(leafTable_.size() - 1) << 6;
}

void KdTreeAccel::buildLeafBlocks() {
    // Leaves become blocks of kLanes triangles (or a scalar list when a sphere is among them), and
    // their references the slots of the wide nodes.
    leafRefs_.assign(nodes_.size(), kKdNoLeaf);
    triangles_.reserve(primIndices_.size() / 2 + 1);
    for (size_t i = 0; i < nodes_.size(); ++i) {
        const KdNode& node = nodes_[i];
        if (!node.isLeaf()) continue;
        uint32_t first = node.word0, count = node.word1 >> 2;
        if (count == 0) continue;  // empty: no slot in the wide nodes
        leafRefs_[i] = makeLeaf(&primIndices_[first], count);
    }
    triangles_.shrink_to_fit();
    blockIds_.shrink_to_fit();
}

uint32_t KdTreeAccel::makeLeaf(const uint32_t* order, uint32_t count) {
    if (!allTriangles(geometry_, prims_, order, count)) {
        uint32_t ref = tableRef({uint32_t(mixedPrims_.size()), count << 1 | kMixedFlag});
        for (uint32_t k = 0; k < count; ++k) mixedPrims_.push_back(prims_[order[k]]);
        return ref;
    }
    uint32_t blocks = (count + kLanes - 1) / kLanes, firstBlock = uint32_t(triangles_.size());
    uint32_t ref = blocks <= kKdMaxInlineBlocks && firstBlock < kKdRefIndexLimit ? kKdLeafBit | blocks << 2 | firstBlock << 6
                                                                                  : tableRef({firstBlock, blocks << 1});
    if (holdsMaskedTriangle(order, count)) ref |= kKdMaskedLeafBit;
    for (uint32_t b = 0; b < blocks; ++b) {
        TriangleBlock& block = triangles_.emplace_back();
        uint32_t inBlock = std::min(uint32_t(kLanes), count - b * kLanes);
        fillTriangleLanes(geometry_, prims_, order + b * kLanes, inBlock, block.p);
        for (uint32_t lane = 0; lane < uint32_t(kLanes); ++lane)
            blockIds_.push_back(lane < inBlock ? prims_[order[b * kLanes + lane]] : PrimRef{kInvalidId, kInvalidId});
    }
    return ref;
}

bool KdTreeAccel::holdsMaskedTriangle(const uint32_t* order, uint32_t count) const {
    for (uint32_t k = 0; k < count; ++k)
        if (geometry_.meshes[prims_[order[k]].geomId].alphaMask) return true;
    return false;
}

uint64_t KdTreeAccel::structureHash() const {
    uint64_t h = kFnv1a64Offset;
    h = fnv1a64(nodes_.data(), nodes_.size() * sizeof(KdNode), h);
    h = fnv1a64(wide_.data(), wide_.size() * sizeof(KdWideNode), h);
    h = fnv1a64(leafTable_.data(), leafTable_.size() * sizeof(KdLeafRecord), h);
    h = fnv1a64(triangles_.data(), triangles_.size() * sizeof(TriangleBlock), h);
    h = fnv1a64(blockIds_.data(), blockIds_.size() * sizeof(PrimRef), h);
    h = fnv1a64(mixedPrims_.data(), mixedPrims_.size() * sizeof(PrimRef), h);
    return h;
}

std::string KdTreeAccel::checkInvariants() const {
    if (nodes_.empty()) return prims_.empty() ? std::string() : "no nodes for " + std::to_string(prims_.size()) + " primitives";
    // 1. Structure: splits strictly inside their cells, children in range, depth within the limit,
    //    leaf blocks holding exactly the builder's references.
    struct Item {
        uint32_t node;
        Bounds3f cell;
        int depth;
    };
    std::vector<Item> todo{{0u, rootCell_, 0}};
    size_t visited = 0;
    while (!todo.empty()) {
        Item it = todo.back();
        todo.pop_back();
        if (++visited > nodes_.size()) return "a node is reachable more than once";
        if (it.depth > buildStats_.depthLimit) return "depth " + std::to_string(it.depth) + " beyond the limit";
        const KdNode& n = nodes_[it.node];
        if (!n.isLeaf()) {
            int a = n.axis();
            float s = n.split();
            if (!(s > it.cell.lower[a] && s < it.cell.upper[a]))
                return "split of node " + std::to_string(it.node) + " not strictly inside its cell";
            if (n.aboveChild() <= it.node + 1 || n.aboveChild() >= nodes_.size()) return "bad child index in node " + std::to_string(it.node);
            Bounds3f below = it.cell, above = it.cell;
            below.upper[a] = s, above.lower[a] = s;
            todo.push_back({it.node + 1, below, it.depth + 1});
            todo.push_back({n.aboveChild(), above, it.depth + 1});
            continue;
        }
        uint32_t first = n.word0, count = n.word1 >> 2;
        if (count == 0) {
            if (leafRefs_[it.node] != kKdNoLeaf) return "empty leaf " + std::to_string(it.node) + " has a reference";
            continue;
        }
        if (leafRefs_[it.node] == kKdNoLeaf || !(leafRefs_[it.node] & kKdLeafBit)) return "leaf " + std::to_string(it.node) + " has no leaf reference";
        LeafSpan span = leafSpan(leafRefs_[it.node]);
        uint32_t capacity = span.mixed ? span.count : span.count * kLanes;
        if (count > capacity || (!span.mixed && count <= capacity - kLanes)) return "leaf " + std::to_string(it.node) + " has the wrong number of blocks";
        for (uint32_t k = 0; k < capacity; ++k) {
            PrimRef want = k < count ? prims_[primIndices_[first + k]] : PrimRef{kInvalidId, kInvalidId}, got;
            if (span.mixed) got = mixedPrims_[span.first + k];
            else got = blockIds_[size_t(span.first) * kLanes + k];
            if (want.geomId != got.geomId || want.primId != got.primId) return "leaf block differs from the builder's leaf";
        }
        if (!span.mixed && bool(leafRefs_[it.node] & kKdMaskedLeafBit) != holdsMaskedTriangle(&primIndices_[first], count))
            return "alpha-mask flag of leaf " + std::to_string(it.node) + " differs from its triangles";
    }
    // 1b. The wide nodes: exactly the binary tree's cells and non-empty leaves.
    if (std::string problem = checkKdWideTree(wide_, nodes_, leafRefs_); !problem.empty()) return problem;
    // 2. Completeness: descend with each triangle clipped to the cell; every leaf whose cell the
    //    clipped triangle enters with positive extent across the splits must reference it.
    for (uint32_t prim = 0; prim < prims_.size(); ++prim) {
        PrimRef ref = prims_[prim];
        if (ref.geomId == geometry_.sphereGeomId()) continue;
        Vec3f p[3];
        triangleVertices(geometry_, ref, p);
        std::vector<std::pair<uint32_t, Bounds3f>> stack{{0u, rootCell_}};
        while (!stack.empty()) {
            auto [index, cell] = stack.back();
            stack.pop_back();
            Vec3d lo, hi;
            if (!clipTriangleDouble(p[0], p[1], p[2], cell, lo, hi)) continue;
            const KdNode& n = nodes_[index];
            if (n.isLeaf()) {
                auto begin = primIndices_.begin() + n.word0, end = begin + (n.word1 >> 2);
                if (!std::binary_search(begin, end, prim))
                    return "triangle " + std::to_string(ref.primId) + " of geometry " + std::to_string(ref.geomId) +
                           " missing from a leaf its clipped extent enters (node " + std::to_string(index) + ")";
                continue;
            }
            int a = n.axis();
            double s = n.split();
            Bounds3f below = cell, above = cell;
            below.upper[a] = float(s), above.lower[a] = float(s);
            if (lo[a] < s) stack.push_back({index + 1, below});
            if (hi[a] > s) stack.push_back({n.aboveChild(), above});
            // A triangle lying in the plane may sit on either side: W&H's planar assignment.
        }
    }
    return {};
}

}  // namespace tessera
