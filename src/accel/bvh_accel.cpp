/// \file bvh_accel.cpp
/// Building the BVH: the binary SAH tree (bvh_builder.h, or bvh_spatial.h with spatial splits)
/// collapsed into 8-wide nodes with leaf blocks of four triangles; and the tree's invariant check.
/// The traversal kernels are in bvh_traversal.cpp.
#include "core/fnv1a.h"
#include "accel/bvh_accel.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>

#include "accel/bvh_spatial.h"
#include "accel/robust_bounds.h"
#include "accel/triangle_simd.h"

namespace tessera {

namespace {

void setEmptyChild(BvhAccel::Node8& n, int lane) {
    for (int a = 0; a < 3; ++a) {
        n.bounds[a][lane] = kInfinity;
        n.bounds[3 + a][lane] = -kInfinity;
    }
    n.child[lane] = BvhAccel::kLeafBit;  // never visited: no ray enters an inverted box
}

/// True when box `in` lies inside box `out`.
bool inside(const Bounds3f& in, const Bounds3f& out) {
    return glm::all(glm::greaterThanEqual(in.lower, out.lower)) && glm::all(glm::lessThanEqual(in.upper, out.upper));
}

/// With spatial splits each leaf holds only a clipped part of a triangle: together the parts'
/// boxes (`leafBoxesOf[i]` for build primitive i) must still cover it. Checked on a barycentric grid
/// (vertices and edges included). Returns "" or the first uncovered point.
std::string checkLeafCoverage(const SceneGeometry& g, const std::vector<PrimRef>& prims,
                              const std::vector<std::vector<Bounds3f>>& leafBoxesOf) {
    for (size_t i = 0; i < leafBoxesOf.size(); ++i) {
        if (prims[i].geomId == g.sphereGeomId()) continue;
        Vec3f p[3];
        triangleVertices(g, prims[i], p);
        constexpr int kGrid = 6;
        for (int a = 0; a <= kGrid; ++a)
            for (int b = 0; a + b <= kGrid; ++b) {
                float u = float(a) / kGrid, v = float(b) / kGrid;
                Bounds3f point;
                point.extend((1.f - u - v) * p[0] + u * p[1] + v * p[2]);
                bool covered = false;
                for (const Bounds3f& box : leafBoxesOf[i]) covered |= inside(point, box);
                if (!covered)
                    return "triangle " + std::to_string(prims[i].primId) + " not covered by its leaves' boxes at (" +
                           std::to_string(u) + ", " + std::to_string(v) + ")";
            }
    }
    return {};
}

}  // namespace

BvhAccel::BvhAccel(const SceneGeometry& geometry, const AccelOptions& options, const BvhConfig& config)
    : geometry_(geometry), config_(config) {
    auto start = std::chrono::steady_clock::now();
    bounds_ = geometry.bounds();
    // Leaf lanes keep a mesh's alpha-mask flag in geomId's top bit (kMaskedLaneBit).
    if (geometry.meshes.size() >= size_t(kMaskedLaneBit)) throw std::runtime_error("bvh: more than 2^31 meshes");
    for (const TriangleMesh& m : geometry.meshes) hasCutOuts_ |= m.alphaMask && !m.triangles.empty();
    // The watertight test may place a hit a few ulps outside the exact triangle (its shear rounds):
    // padded boxes make sure a box face through an edge never hides such a hit.
    GatheredPrimitives gathered = gatherPrimitives(geometry, /*padTriangles=*/true);
    prims_ = std::move(gathered.refs);
    BinaryBvh bin = buildBinaryTree(gathered.bounds, options);
    buildWideTree(bin);

    stats_.primitives = geometry.primitiveCount();
    stats_.memoryBytes = nodes_.size() * sizeof(Node8) + triangles_.size() * sizeof(Triangle4) +
                         mixedPrims_.size() * sizeof(PrimRef);
    stats_.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

BinaryBvh BvhAccel::buildBinaryTree(std::span<const Bounds3f> primBounds, const AccelOptions& options) const {
    if (config_.spatialSplits) {
        // The SBVH build is serial. It prices planes with each triangle cut by a slab and clips the
        // part of a primitive inside a box, padded like the whole primitive's box.
        std::vector<Vec3f> triangleVertexList(3 * prims_.size(), Vec3f(std::numeric_limits<float>::quiet_NaN()));
        for (size_t i = 0; i < prims_.size(); ++i) {
            if (prims_[i].geomId == geometry_.sphereGeomId()) continue;
            Vec3f v[3];
            triangleVertices(geometry_, prims_[i], v);
            std::copy(v, v + 3, &triangleVertexList[3 * i]);
        }
        ClipToBox clip = [&](uint32_t i, const Bounds3f& box) {
            PrimRef p = prims_[i];
            if (p.geomId == geometry_.sphereGeomId()) return paddedSphereBounds(geometry_.spheres[p.primId]).intersection(box);
            Vec3f v[3];
            triangleVertices(geometry_, p, v);
            Bounds3f b = clipTriangleBounds(v[0], v[1], v[2], box);
            return b.empty() ? b : padTriangleBox(b);
        };
        return buildSpatialSplitBvh(primBounds, triangleVertexList, clip, config_);
    }
    BinaryBvh bin;
    auto build = [&] { bin = buildBinaryBvh(primBounds, config_); };
    if (options.threads > 0) tbb::task_arena(options.threads).execute(build);  // the build's TBB tasks
    else build();
    return bin;
}

void BvhAccel::buildWideTree(const BinaryBvh& bin) {
    if (!prims_.empty()) {
        // Exact Triangle4 count first (a walk over the binary tree costs a few ms): reserving a guess
        // and shrinking afterwards copied ~50 MB on the dragon.
        size_t blocks = 0;
        std::vector<uint32_t> todo{0u};
        while (!todo.empty()) {
            const BvhBuildNode& n = bin.nodes[todo.back()];
            todo.pop_back();
            if (n.isLeaf()) blocks += (n.count + 3) / 4;
            else todo.push_back(n.left), todo.push_back(n.right);
        }
        triangles_.reserve(blocks);
        if (bin.nodes[0].isLeaf()) {
            // A wide root is always an inner node: one leaf child, seven empty lanes.
            nodes_.emplace_back();
            for (int i = 0; i < 8; ++i) setEmptyChild(nodes_[0], i);
            const Bounds3f& b = bin.nodes[0].bounds;
            for (int a = 0; a < 3; ++a) {
                nodes_[0].bounds[a][0] = b.lower[a];
                nodes_[0].bounds[3 + a][0] = b.upper[a];
            }
            nodes_[0].child[0] = makeLeaf(bin, bin.nodes[0]);
        } else {
            collapse(bin, 0);
        }
    }
    nodes_.shrink_to_fit();
    // Inner child references become byte offsets from the node array: the traversal then adds
    // instead of multiplying by 224 on the path from one node's box test to the next node's load.
    if (nodes_.size() * sizeof(Node8) >= size_t(kLeafBit)) throw std::runtime_error("bvh: more than 2 GiB of nodes");
    for (Node8& n : nodes_)
        for (uint32_t& c : n.child)
            if (!(c & kLeafBit)) c *= uint32_t(sizeof(Node8));
}

uint32_t BvhAccel::makeLeaf(const BinaryBvh& bin, const BvhBuildNode& leaf) {
    const uint32_t* order = &bin.primIndices[leaf.first()];
    if (!allTriangles(geometry_, prims_, order, leaf.count)) {
        uint32_t first = uint32_t(mixedPrims_.size());
        for (uint32_t i = 0; i < leaf.count; ++i) mixedPrims_.push_back(prims_[order[i]]);
        return kLeafBit | kMixedBit | (first << 4) | leaf.count;
    }
    uint32_t firstBlock = uint32_t(triangles_.size());
    uint32_t blocks = (leaf.count + 3) / 4;
    for (uint32_t b = 0; b < blocks; ++b) {
        Triangle4& t = triangles_.emplace_back();
        uint32_t count = std::min(4u, leaf.count - 4 * b);
        fillTriangleLanes(geometry_, prims_, order + 4 * b, count, t.p);
        for (uint32_t lane = 0; lane < 4; ++lane) {
            PrimRef ref = lane < count ? prims_[order[4 * b + lane]] : PrimRef{kInvalidId, kInvalidId};
            bool masked = lane < count && geometry_.meshes[ref.geomId].alphaMask;
            t.geomId[lane] = ref.geomId | (masked ? kMaskedLaneBit : 0u);
            t.primId[lane] = ref.primId;
        }
    }
    // The first block's byte offset in 16-byte units (bits 2–29), so that the traversal finds it
    // with a mask and a shift (leafBlocks()).
    static_assert(sizeof(Triangle4) % 16 == 0);
    size_t units = size_t(firstBlock) * (sizeof(Triangle4) / 16);
    if (units >= (size_t(1) << 28)) throw std::runtime_error("bvh: more than 4 GiB of leaf triangles");
    return kLeafBit | (uint32_t(units) << 2) | (blocks - 1);
}

uint32_t BvhAccel::collapse(const BinaryBvh& bin, uint32_t binNode) {
    // Gather up to eight children by repeatedly opening the child of largest surface area (the one
    // most rays would visit), as in Wald et al. 2008, "Getting Rid of Packets", Section 3.
    uint32_t kids[8];
    int count = 2;
    kids[0] = bin.nodes[binNode].left;
    kids[1] = bin.nodes[binNode].right;
    while (count < 8) {
        int best = -1;
        float bestArea = -1.f;
        for (int i = 0; i < count; ++i) {
            const BvhBuildNode& k = bin.nodes[kids[i]];
            if (k.isLeaf()) continue;
            float area = k.bounds.surfaceArea();
            if (area > bestArea) bestArea = area, best = i;
        }
        if (best < 0) break;
        const BvhBuildNode& open = bin.nodes[kids[best]];
        kids[best] = open.left;
        kids[count++] = open.right;
    }
    uint32_t index = uint32_t(nodes_.size());
    nodes_.emplace_back();
    for (int i = 0; i < 8; ++i) setEmptyChild(nodes_[index], i);
    for (int i = 0; i < count; ++i) {
        const BvhBuildNode& k = bin.nodes[kids[i]];
        uint32_t ref = k.isLeaf() ? makeLeaf(bin, k) : collapse(bin, kids[i]);
        Node8& n = nodes_[index];  // re-fetched: collapse() may have grown nodes_
        for (int a = 0; a < 3; ++a) {
            n.bounds[a][i] = k.bounds.lower[a];
            n.bounds[3 + a][i] = k.bounds.upper[a];
        }
        n.child[i] = ref;
    }
    return index;
}

size_t BvhAccel::referenceCount() const {
    size_t n = mixedPrims_.size();
    for (const Triangle4& t : triangles_)
        for (int lane = 0; lane < 4; ++lane) n += t.primId[lane] != kInvalidId;
    return n;
}

uint64_t BvhAccel::structureHash() const {
    uint64_t h = kFnv1a64Offset;
    h = fnv1a64(nodes_.data(), nodes_.size() * sizeof(Node8), h);
    h = fnv1a64(triangles_.data(), triangles_.size() * sizeof(Triangle4), h);
    h = fnv1a64(mixedPrims_.data(), mixedPrims_.size() * sizeof(PrimRef), h);
    return h;
}

std::string BvhAccel::checkInvariants() const {
    std::vector<uint8_t> seen(prims_.size(), 0);
    // Dense index of (geomId, primId) among the built primitives, to count visits.
    std::vector<std::vector<uint32_t>> denseOf(geometry_.meshes.size() + 1);
    for (uint32_t g = 0; g < geometry_.meshes.size(); ++g) denseOf[g].assign(geometry_.meshes[g].triangles.size(), kInvalidId);
    denseOf.back().assign(geometry_.spheres.size(), kInvalidId);
    for (uint32_t i = 0; i < prims_.size(); ++i) denseOf[prims_[i].geomId][prims_[i].primId] = i;

    auto primBox = [&](PrimRef p) {
        Bounds3f b;
        if (p.geomId == geometry_.sphereGeomId()) return paddedSphereBounds(geometry_.spheres[p.primId]);
        const TriangleMesh& m = geometry_.meshes[p.geomId];
        for (int v = 0; v < 3; ++v) b.extend(m.positions[m.triangles[p.primId][v]]);
        return b;
    };
    std::string problem;
    std::vector<std::vector<Bounds3f>> leafBoxesOf(config_.spatialSplits ? prims_.size() : 0);
    auto visitPrim = [&](PrimRef p, const Bounds3f& leafBox) {
        if (p.geomId >= denseOf.size() || p.primId >= denseOf[p.geomId].size() || denseOf[p.geomId][p.primId] == kInvalidId) {
            problem = "leaf references an unknown primitive";
            return;
        }
        uint32_t dense = denseOf[p.geomId][p.primId];
        bool again = seen[dense];
        seen[dense] = 1;
        if (config_.spatialSplits) leafBoxesOf[dense].push_back(leafBox);
        if (!config_.spatialSplits) {
            if (again) problem = "primitive " + std::to_string(p.primId) + " reached twice";
            if (!inside(primBox(p), leafBox)) problem = "primitive " + std::to_string(p.primId) + " outside its leaf box";
        } else {
            // Spatial splits reference a primitive from several leaves, each holding a clipped part.
            Bounds3f b = primBox(p).intersection(leafBox);
            if (b.empty()) problem = "primitive " + std::to_string(p.primId) + " does not meet its leaf box";
        }
    };
    std::vector<std::pair<uint32_t, Bounds3f>> todo;
    if (!nodes_.empty()) {
        Bounds3f all;
        all.lower = Vec3f(-kInfinity), all.upper = Vec3f(kInfinity);
        todo.push_back({0u, all});
    }
    size_t visitedNodes = 0;
    while (!todo.empty() && problem.empty()) {
        auto [index, parentBox] = todo.back();
        todo.pop_back();
        if (++visitedNodes > nodes_.size()) return "a node is reachable more than once";
        const Node8& n = nodes_[index];
        for (int i = 0; i < 8; ++i) {
            Bounds3f box;
            for (int a = 0; a < 3; ++a) box.lower[a] = n.bounds[a][i], box.upper[a] = n.bounds[3 + a][i];
            if (box.empty()) continue;
            if (!inside(box, parentBox)) return "child box outside its parent box in node " + std::to_string(index);
            uint32_t ref = n.child[i];
            if (!(ref & kLeafBit)) {
                if (ref % sizeof(Node8) || ref / sizeof(Node8) >= nodes_.size()) return "child reference outside the node array";
                todo.push_back({uint32_t(ref / sizeof(Node8)), box});
            }
            else if (!(ref & kMixedBit)) {
                uint32_t first = uint32_t(leafBlocks(ref) - triangles_.data()), blocks = (ref & 3u) + 1;
                for (uint32_t b = 0; b < blocks; ++b)
                    for (int lane = 0; lane < 4; ++lane)
                        if (triangles_[first + b].primId[lane] != kInvalidId) {
                            uint32_t geomId = triangles_[first + b].geomId[lane];
                            bool masked = geomId & kMaskedLaneBit;
                            geomId &= ~kMaskedLaneBit;
                            if (geomId < geometry_.meshes.size() && masked != bool(geometry_.meshes[geomId].alphaMask))
                                return "alpha-mask flag of a leaf lane differs from its mesh";
                            visitPrim({geomId, triangles_[first + b].primId[lane]}, box);
                        }
            } else {
                uint32_t first = (ref & ~(kLeafBit | kMixedBit)) >> 4, count = ref & 15u;
                for (uint32_t k = 0; k < count; ++k) visitPrim(mixedPrims_[first + k], box);
            }
        }
    }
    if (!problem.empty()) return problem;
    for (size_t i = 0; i < seen.size(); ++i)
        if (!seen[i]) return "primitive " + std::to_string(prims_[i].primId) + " of geometry " + std::to_string(prims_[i].geomId) + " unreachable";
    return checkLeafCoverage(geometry_, prims_, leafBoxesOf);
}

}  // namespace tessera
