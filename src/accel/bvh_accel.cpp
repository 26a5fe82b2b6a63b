/// \file bvh_accel.cpp
/// Building the BVH: the binary SAH tree (bvh_builder.h, or bvh_spatial.h with spatial splits)
/// collapsed into 8-wide nodes with leaf blocks of four triangles; and the tree's invariant check.
/// The traversal kernels are in bvh_traversal.cpp.
#include "core/fnv1a.h"
#include "accel/bvh_accel.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
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
    // Everything from the gathering on runs in the build's TBB arena (its thread count).
    auto build = [&] {
        GatheredPrimitives gathered = gatherPrimitives(geometry, /*padTriangles=*/true);
        prims_ = std::move(gathered.refs);
        // gatherPrimitives lists triangles before spheres: build primitive i is a triangle when i < triangleRefs_.
        triangleRefs_ = uint32_t(std::partition_point(prims_.begin(), prims_.end(), [&](const PrimRef& p) {
                                     return p.geomId != geometry.sphereGeomId();
                                 }) - prims_.begin());
        BinaryBvh bin = buildBinaryTree(gathered.bounds);
        separateLeafKinds(bin, gathered.bounds);
        buildWideTree(bin);
    };
    if (options.threads > 0) tbb::task_arena(options.threads).execute(build);  // the build's TBB tasks
    else build();

    stats_.primitives = geometry.primitiveCount();
    stats_.memoryBytes = nodes_.size() * sizeof(Node8) + triangles_.size() * sizeof(Triangle4) +
                         mixedPrims_.size() * sizeof(PrimRef);
    stats_.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void BvhAccel::separateLeafKinds(BinaryBvh& bin, std::span<const Bounds3f> primBounds) const {
    if (triangleRefs_ == 0 || triangleRefs_ == prims_.size()) return;  // one kind only
    std::vector<uint32_t> mixed, reached, todo{0u};
    while (!todo.empty()) {
        uint32_t k = todo.back();
        todo.pop_back();
        reached.push_back(k);
        const BvhBuildNode& n = bin.nodes[k];
        if (!n.isLeaf()) {
            todo.push_back(n.left), todo.push_back(n.right);
            continue;
        }
        const uint32_t* order = &bin.primIndices[n.first()];
        bool triangles = false, spheres = false;
        for (uint32_t i = 0; i < n.count; ++i) (order[i] < triangleRefs_ ? triangles : spheres) = true;
        if (triangles && spheres) mixed.push_back(k);
    }
    if (mixed.empty()) return;
    std::sort(mixed.begin(), mixed.end());  // new slots in slot order: the tree stays deterministic
    // Only the nodes the tree reaches are copied, at their slots: most of the 2n − 1 slots were
    // never written, and copying them would touch every page the builder left alone.
    BinaryBvh::NodeArray grown;
    grown.allocate(bin.nodes.size + 2 * mixed.size());
    for (uint32_t k : reached) grown[k] = bin.nodes[k];
    uint32_t next = uint32_t(bin.nodes.size);
    for (uint32_t k : mixed) {
        BvhBuildNode& leaf = grown[k];
        uint32_t* order = &bin.primIndices[leaf.first()];
        uint32_t* firstSphere =
            std::stable_partition(order, order + leaf.count, [&](uint32_t i) { return i < triangleRefs_; });
        uint32_t triangleCount = uint32_t(firstSphere - order);
        // A part's box: its primitives' boxes, clipped to the leaf's (with spatial splits a leaf
        // holds only the parts of its primitives inside its box).
        auto part = [&](uint32_t first, uint32_t count) {
            BvhBuildNode n;
            for (uint32_t i = 0; i < count; ++i) n.bounds.extend(primBounds[bin.primIndices[first + i]]);
            n.bounds = n.bounds.intersection(leaf.bounds);
            n.count = count;
            n.left = first;
            return n;
        };
        grown[next] = part(leaf.first(), triangleCount);
        grown[next + 1] = part(leaf.first() + triangleCount, leaf.count - triangleCount);
        leaf.count = 0;
        leaf.left = next, leaf.right = next + 1;
        next += 2;
    }
    bin.nodes = std::move(grown);
    ++bin.maxDepth;
}

BinaryBvh BvhAccel::buildBinaryTree(std::span<const Bounds3f> primBounds) const {
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
    return buildBinaryBvh(primBounds, config_);
}

namespace {

/// The children of one wide node: starting from binary node `binNode`'s two, the child of largest
/// surface area (the one most rays would visit) is opened until there are eight or only leaves
/// are left (Wald et al. 2008, "Getting Rid of Packets", Section 3). An opened child is replaced
/// by its two in place, so the children stay in the binary tree's left-to-right order (leaves
/// then come out in the order of BinaryBvh::primIndices). Returns their count.
int gatherChildren(const BinaryBvh& bin, uint32_t binNode, uint32_t (&kids)[8]) {
    float area[8];
    auto areaOf = [&](uint32_t k) { return bin.nodes[k].isLeaf() ? -1.f : bin.nodes[k].bounds.surfaceArea(); };
    kids[0] = bin.nodes[binNode].left, kids[1] = bin.nodes[binNode].right;
    area[0] = areaOf(kids[0]), area[1] = areaOf(kids[1]);
    int count = 2;
    while (count < 8) {
        int best = -1;
        float bestArea = -1.f;
        for (int i = 0; i < count; ++i)
            if (area[i] > bestArea) bestArea = area[i], best = i;
        if (best < 0) break;
        const BvhBuildNode& open = bin.nodes[kids[best]];
        for (int i = count; i > best + 1; --i) kids[i] = kids[i - 1], area[i] = area[i - 1];
        kids[best] = open.left, kids[best + 1] = open.right;
        area[best] = areaOf(open.left), area[best + 1] = areaOf(open.right);
        ++count;
    }
    return count;
}

/// The number of wide nodes the collapse of binary node `root` makes (the same gathering, nothing written).
size_t countWideNodes(const BinaryBvh& bin, uint32_t root) {
    size_t count = 0;
    std::vector<uint32_t> todo{root};
    while (!todo.empty()) {
        uint32_t node = todo.back();
        todo.pop_back();
        ++count;
        uint32_t kids[8];
        int n = gatherChildren(bin, node, kids);
        for (int i = 0; i < n; ++i)
            if (!bin.nodes[kids[i]].isLeaf()) todo.push_back(kids[i]);
    }
    return count;
}

/// A child reference of a part's node, moved to where the part lands in the joined arrays.
uint32_t relocateRef(uint32_t ref, uint32_t nodeBytes, size_t blockUnits, uint32_t mixedBase) {
    if (!(ref & BvhAccel::kLeafBit)) return ref + nodeBytes;
    if (ref & BvhAccel::kMixedBit) {
        uint32_t first = (ref & ~(BvhAccel::kLeafBit | BvhAccel::kMixedBit)) >> 4;
        return BvhAccel::kLeafBit | BvhAccel::kMixedBit | ((first + mixedBase) << 4) | (ref & 15u);
    }
    size_t units = ((ref >> 2) & 0x0fffffffu) + blockUnits;
    if (units >= (size_t(1) << 28)) throw std::runtime_error("bvh: more than 4 GiB of leaf triangles");
    return BvhAccel::kLeafBit | (uint32_t(units) << 2) | (ref & 3u);
}

/// Writes wide node `n` over `count` children (binary nodes `kids`, references `refs`, primitive
/// counts `counts`). Lanes ordered by the primitives below them, most first: the any-hit traversal
/// enters the hit lanes from the last, so it tries the smallest subtrees (often a leaf) first, as
/// Embree's builder and any-hit traversal do: shadow rays on Sponza and Conference then visit
/// 17–41% fewer nodes and leaves than in the gathering order. Stable, so the order is fully determined.
void writeWideNode(BvhAccel::Node8& n, const BinaryBvh& bin, const uint32_t* kids, const uint32_t* refs,
                   const uint32_t* counts, int count) {
    int lane[8];
    for (int i = 0; i < count; ++i) lane[i] = i;
    std::stable_sort(lane, lane + count, [&](int a, int b) { return counts[a] > counts[b]; });
    for (int i = 0; i < 8; ++i) setEmptyChild(n, i);
    for (int i = 0; i < count; ++i) {
        const Bounds3f& b = bin.nodes[kids[lane[i]]].bounds;
        for (int a = 0; a < 3; ++a) {
            n.bounds[a][i] = b.lower[a];
            n.bounds[3 + a][i] = b.upper[a];
        }
        n.child[i] = refs[lane[i]];
    }
}

}  // namespace

void BvhAccel::buildWideTree(const BinaryBvh& bin) {
    if (prims_.empty()) return;
    // A wide root is always an inner node; over a binary leaf it has one leaf child.
    uint32_t kids[8] = {0};
    const int count = bin.nodes[0].isLeaf() ? 1 : gatherChildren(bin, 0, kids);
    // Each root child's subtree into its own part, in parallel; every part reserves its exact
    // node count first (growing the node array and shrinking it afterwards copied it twice).
    std::vector<WideParts> parts(static_cast<size_t>(count));
    uint32_t refs[8], counts[8];
    auto collapseChild = [&](int i) {
        const BvhBuildNode& k = bin.nodes[kids[i]];
        if (k.isLeaf()) {
            refs[i] = makeLeaf(bin, k, parts[size_t(i)]), counts[i] = k.count;
        } else {
            parts[size_t(i)].nodes.reserve(countWideNodes(bin, kids[i]));
            refs[i] = collapse(bin, kids[i], parts[size_t(i)], counts[i]);
        }
    };
    // Below the builder's parallel threshold the tasks cost more than the collapse (and a small
    // scene builds without spawning any).
    if (bin.primIndices.size() >= size_t(config_.parallelThreshold)) tbb::parallel_for(0, count, collapseChild);
    else
        for (int i = 0; i < count; ++i) collapseChild(i);
    size_t nodeCount = 1, leafCount = 0, mixedCount = 0;
    for (const WideParts& part : parts) nodeCount += part.nodes.size(), leafCount += part.leaves.size(), mixedCount += part.mixed.size();
    if (nodeCount * sizeof(Node8) >= size_t(kLeafBit)) throw std::runtime_error("bvh: more than 2 GiB of nodes");
    // Joined in child order: the root, then each part's nodes, leaves and sphere primitives, with
    // its references moved by the parts before it.
    nodes_.resize(nodeCount);
    std::vector<LeafBlocks> leaves;
    leaves.reserve(leafCount);
    mixedPrims_.reserve(mixedCount);
    uint32_t nodeBase = 1, blockBase = 0;
    for (int i = 0; i < count; ++i) {
        WideParts& part = parts[size_t(i)];
        const uint32_t nodeBytes = nodeBase * uint32_t(sizeof(Node8)), mixedBase = uint32_t(mixedPrims_.size());
        const size_t blockUnits = size_t(blockBase) * (sizeof(Triangle4) / 16);
        refs[i] = relocateRef(refs[i], nodeBytes, blockUnits, mixedBase);
        for (size_t k = 0; k < part.nodes.size(); ++k) {
            Node8& n = nodes_[nodeBase + k];
            n = part.nodes[k];
            for (int lane = 0; lane < 8; ++lane)
                if (!(n.bounds[0][lane] > n.bounds[3][lane]))  // empty lanes keep their reference
                    n.child[lane] = relocateRef(n.child[lane], nodeBytes, blockUnits, mixedBase);
        }
        for (LeafBlocks leaf : part.leaves) leaf.firstBlock += blockBase, leaves.push_back(leaf);
        mixedPrims_.insert(mixedPrims_.end(), part.mixed.begin(), part.mixed.end());
        nodeBase += uint32_t(part.nodes.size());
        blockBase += part.blocks;
        part = WideParts{};  // its memory back before the leaves are filled
    }
    if (bin.nodes[0].isLeaf()) kids[0] = 0;
    writeWideNode(nodes_[0], bin, kids, refs, counts, count);
    fillLeaves(bin, leaves, blockBase);
}

void BvhAccel::fillLeaves(const BinaryBvh& bin, const std::vector<LeafBlocks>& leaves, uint32_t blocks) {
    // Every block belongs to one leaf, and every leaf writes only its own: the leaves are filled in
    // parallel, in primIndices order (the vertex reads, the slow part, then follow the mesh).
    triangles_.resize(blocks);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size(), 512), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t l = range.begin(); l != range.end(); ++l) {
            const LeafBlocks& leaf = leaves[l];
            const uint32_t* order = &bin.primIndices[leaf.first];
            for (uint32_t b = 0; b < (leaf.count + 3) / 4; ++b) {
                Triangle4& t = triangles_[leaf.firstBlock + b];
                uint32_t count = std::min(4u, leaf.count - 4 * b);
                fillTriangleLanes(geometry_, prims_, order + 4 * b, count, t.p);
                for (uint32_t lane = 0; lane < 4; ++lane) {
                    PrimRef ref = lane < count ? prims_[order[4 * b + lane]] : PrimRef{kInvalidId, kInvalidId};
                    bool masked = lane < count && geometry_.meshes[ref.geomId].alphaMask;
                    t.geomId[lane] = ref.geomId | (masked ? kMaskedLaneBit : 0u);
                    t.primId[lane] = ref.primId;
                }
            }
        }
    });
}

uint32_t BvhAccel::makeLeaf(const BinaryBvh& bin, const BvhBuildNode& leaf, WideParts& out) const {
    const uint32_t* order = &bin.primIndices[leaf.first()];
    bool allTriangles = true;
    for (uint32_t i = 0; i < leaf.count; ++i) allTriangles &= order[i] < triangleRefs_;
    if (!allTriangles) {
        uint32_t first = uint32_t(out.mixed.size());
        for (uint32_t i = 0; i < leaf.count; ++i) out.mixed.push_back(prims_[order[i]]);
        return kLeafBit | kMixedBit | (first << 4) | leaf.count;
    }
    // Blocks are numbered here and filled later (fillLeaves).
    uint32_t firstBlock = out.blocks;
    out.blocks += (leaf.count + 3) / 4;
    out.leaves.push_back({leaf.first(), leaf.count, firstBlock});
    // The first block's byte offset in 16-byte units (bits 2–29), so that the traversal finds it
    // with a mask and a shift (leafBlocks()).
    static_assert(sizeof(Triangle4) % 16 == 0);
    size_t units = size_t(firstBlock) * (sizeof(Triangle4) / 16);
    if (units >= (size_t(1) << 28)) throw std::runtime_error("bvh: more than 4 GiB of leaf triangles");
    return kLeafBit | (uint32_t(units) << 2) | ((leaf.count + 3) / 4 - 1);
}

uint32_t BvhAccel::collapse(const BinaryBvh& bin, uint32_t binNode, WideParts& out, uint32_t& prims) const {
    uint32_t kids[8];
    int count = gatherChildren(bin, binNode, kids);
    uint32_t index = uint32_t(out.nodes.size());
    out.nodes.emplace_back();
    uint32_t refs[8], counts[8];
    prims = 0;
    for (int i = 0; i < count; ++i) {
        const BvhBuildNode& k = bin.nodes[kids[i]];
        if (k.isLeaf()) refs[i] = makeLeaf(bin, k, out), counts[i] = k.count;
        else refs[i] = collapse(bin, kids[i], out, counts[i]);
        prims += counts[i];
    }
    writeWideNode(out.nodes[index], bin, kids, refs, counts, count);
    // Inner child references are byte offsets from the node array: the traversal then adds
    // instead of multiplying by 224 on the path from one node's box test to the next node's load.
    return index * uint32_t(sizeof(Node8));
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
                for (uint32_t k = 0; k < count; ++k) {
                    if (mixedPrims_[first + k].geomId != geometry_.sphereGeomId())
                        return "a triangle in a sphere leaf (separateLeafKinds keeps the kinds apart)";
                    visitPrim(mixedPrims_[first + k], box);
                }
            }
        }
    }
    if (!problem.empty()) return problem;
    for (size_t i = 0; i < seen.size(); ++i)
        if (!seen[i]) return "primitive " + std::to_string(prims_[i].primId) + " of geometry " + std::to_string(prims_[i].geomId) + " unreachable";
    if (std::string order = checkLaneOrder(); !order.empty()) return order;
    return checkLeafCoverage(geometry_, prims_, leafBoxesOf);
}

uint32_t BvhAccel::subtreeReferences(uint32_t ref, std::string& problem) const {
    if (ref & kLeafBit) {
        if (ref & kMixedBit) return ref & 15u;
        uint32_t n = 0;
        const Triangle4* blocks = leafBlocks(ref);
        for (uint32_t b = 0; b <= (ref & 3u); ++b)
            for (int lane = 0; lane < 4; ++lane) n += blocks[b].primId[lane] != kInvalidId;
        return n;
    }
    const Node8& n = node(ref);
    uint32_t total = 0, previous = ~0u;
    for (int i = 0; i < 8; ++i) {
        if (n.bounds[0][i] > n.bounds[3][i]) continue;  // an empty lane
        uint32_t count = subtreeReferences(n.child[i], problem);
        if (count > previous && problem.empty())
            problem = "lanes of node " + std::to_string(ref / sizeof(Node8)) + " not ordered by subtree size";
        previous = count, total += count;
    }
    return total;
}

std::string BvhAccel::checkLaneOrder() const {
    std::string problem;
    if (!nodes_.empty()) subtreeReferences(0, problem);
    return problem;
}

}  // namespace tessera
