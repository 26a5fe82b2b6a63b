#include "accel/kdtree_accel.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace tessera {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

Bounds3f paddedSphereBounds(const Sphere& s) {
    float pad = 1e-6f * (s.radius + maxComponent(glm::abs(s.center)));  // as the BVH and Embree backends
    Bounds3f b = sphereBounds(s);
    b.lower -= Vec3f(pad);
    b.upper += Vec3f(pad);
    return b;
}

bool finiteBounds(const Bounds3f& b) { return isFinite(b.lower) && isFinite(b.upper) && !b.empty(); }

float roundDown(double x) {
    float f = float(x);
    return double(f) > x ? std::nextafter(f, -kInfinity) : f;
}
float roundUp(double x) {
    float f = float(x);
    return double(f) < x ? std::nextafter(f, kInfinity) : f;
}

/// Sutherland–Hodgman clip of a convex polygon against one axis-aligned half-space
/// (keep x[axis] ≥ v when `keepAbove`, else x[axis] ≤ v). Returns the new vertex count.
int clipPolygon(const Vec3d* in, int n, Vec3d* out, int axis, double v, bool keepAbove) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const Vec3d& a = in[i];
        const Vec3d& b = in[(i + 1) % n];
        double da = keepAbove ? a[axis] - v : v - a[axis];
        double db = keepAbove ? b[axis] - v : v - b[axis];
        if (da >= 0.0) out[m++] = a;
        if ((da >= 0.0) != (db >= 0.0) && da != db) {
            double t = da / (da - db);
            Vec3d p = a + t * (b - a);
            p[axis] = v;  // exactly on the plane, whatever the rounding of t
            out[m++] = p;
        }
    }
    return m;
}

/// Exact-as-double clip of the triangle to the box; false when nothing remains.
bool clipTriangleDouble(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box, Vec3d& lo, Vec3d& hi) {
    Vec3d bufA[12], bufB[12];
    bufA[0] = Vec3d(p0), bufA[1] = Vec3d(p1), bufA[2] = Vec3d(p2);
    int n = 3;
    Vec3d* cur = bufA;
    Vec3d* nxt = bufB;
    // Cheap pre-pass: planes the triangle lies entirely on the kept side of need no clipping.
    Vec3f tlo = glm::min(p0, glm::min(p1, p2)), thi = glm::max(p0, glm::max(p1, p2));
    for (int a = 0; a < 3 && n > 0; ++a) {
        if (tlo[a] < box.lower[a]) {
            n = clipPolygon(cur, n, nxt, a, double(box.lower[a]), true);
            std::swap(cur, nxt);
        }
        if (n > 0 && thi[a] > box.upper[a]) {
            n = clipPolygon(cur, n, nxt, a, double(box.upper[a]), false);
            std::swap(cur, nxt);
        }
    }
    if (n == 0) return false;
    lo = hi = cur[0];
    for (int i = 1; i < n; ++i) lo = glm::min(lo, cur[i]), hi = glm::max(hi, cur[i]);
    return true;
}

}  // namespace

Bounds3f clipTriangleBounds(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Bounds3f& box) {
    Vec3d lo, hi;
    Bounds3f b;
    if (!clipTriangleDouble(p0, p1, p2, box, lo, hi)) return b;
    for (int a = 0; a < 3; ++a) {
        b.lower[a] = std::max(roundDown(lo[a]), box.lower[a]);
        b.upper[a] = std::min(roundUp(hi[a]), box.upper[a]);
    }
    return b;
}

KdTreeAccel::KdTreeAccel(const SceneGeometry& geometry, const AccelOptions& options, const KdConfig& config)
    : geometry_(geometry), config_(config) {
    auto start = std::chrono::steady_clock::now();
#if defined(__x86_64__) || defined(__i386__)
    useAvx2_ = __builtin_cpu_supports("avx2");
#endif
    bounds_ = geometry.bounds();

    std::vector<Bounds3f> primBounds;
    size_t total = geometry.primitiveCount();
    prims_.reserve(total);
    primBounds.reserve(total);
    for (uint32_t g = 0; g < geometry.meshes.size(); ++g) {
        const TriangleMesh& mesh = geometry.meshes[g];
        for (uint32_t i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3& t = mesh.triangles[i];
            const Vec3f &p0 = mesh.positions[t.x], &p1 = mesh.positions[t.y], &p2 = mesh.positions[t.z];
            Bounds3f b;
            b.extend(p0), b.extend(p1), b.extend(p2);
            // Exact boxes: padding them would make neighbours sharing a vertex straddle every plane
            // through it. The traversal is conservative instead (kdtree_traversal.cpp).
            if (!finiteBounds(b)) continue;  // a non-finite vertex can never be hit
            prims_.push_back({g, i});
            primBounds.push_back(b);
        }
    }
    for (uint32_t i = 0; i < geometry.spheres.size(); ++i) {
        Bounds3f b = paddedSphereBounds(geometry.spheres[i]);
        if (!finiteBounds(b) || !(geometry.spheres[i].radius > 0.f)) continue;
        prims_.push_back({geometry.sphereGeomId(), i});
        primBounds.push_back(b);
    }

    // Perfect splits: the triangle clipped to the cell (in double, rounded outward). Spheres keep
    // their box (the builder intersects it with the cell).
    KdClipFunction clip = [&](uint32_t prim, const Bounds3f& cell) -> Bounds3f {
        PrimRef ref = prims_[prim];
        if (ref.geomId == geometry_.sphereGeomId()) return primBounds[prim];
        const TriangleMesh& mesh = geometry_.meshes[ref.geomId];
        const glm::uvec3& t = mesh.triangles[ref.primId];
        const Vec3f &p0 = mesh.positions[t.x], &p1 = mesh.positions[t.y], &p2 = mesh.positions[t.z];
        return clipTriangleBounds(p0, p1, p2, cell);
    };
    KdTree tree;
    auto buildTree = [&] { tree = buildKdTree(primBounds, clip, config_); };
    if (options.threads > 0) tbb::task_arena(options.threads).execute(buildTree);
    else buildTree();
    rootCell_ = tree.bounds;
    sceneMagnitude_ = std::max(maxComponent(glm::abs(rootCell_.lower)), maxComponent(glm::abs(rootCell_.upper)));
    if (!std::isfinite(sceneMagnitude_)) sceneMagnitude_ = 0.f;
    buildStats_ = tree.stats;

    // Leaves become blocks of kLanes triangles (or a scalar list when a sphere is among them).
    nodes_ = tree.nodes;
    triangles_.reserve(tree.primIndices.size() / 2 + 1);
    for (KdNode& node : nodes_) {
        if (!node.isLeaf()) continue;
        uint32_t first = node.word0, count = node.word1 >> 2;
        bool allTriangles = true;
        for (uint32_t k = 0; k < count; ++k) allTriangles &= prims_[tree.primIndices[first + k]].geomId != geometry_.sphereGeomId();
        if (!allTriangles) {
            node = KdNode::leaf(uint32_t(mixedPrims_.size()), count << 1 | kMixedFlag);
            for (uint32_t k = 0; k < count; ++k) mixedPrims_.push_back(prims_[tree.primIndices[first + k]]);
            continue;
        }
        uint32_t blocks = (count + kLanes - 1) / kLanes;
        node = KdNode::leaf(uint32_t(triangles_.size()), blocks << 1);
        for (uint32_t b = 0; b < blocks; ++b) {
            TriangleBlock& t4 = triangles_.emplace_back();
            for (int lane = 0; lane < kLanes; ++lane) {
                uint32_t k = b * kLanes + uint32_t(lane);
                if (k >= count) {
                    for (int v = 0; v < 3; ++v)
                        for (int a = 0; a < 3; ++a) t4.p[v][a][lane] = kNaN;
                    blockIds_.push_back({kInvalidId, kInvalidId});
                    continue;
                }
                PrimRef ref = prims_[tree.primIndices[first + k]];
                const TriangleMesh& mesh = geometry_.meshes[ref.geomId];
                const glm::uvec3& tri = mesh.triangles[ref.primId];
                for (int v = 0; v < 3; ++v)
                    for (int a = 0; a < 3; ++a) t4.p[v][a][lane] = mesh.positions[tri[v]][a];
                blockIds_.push_back(ref);
            }
        }
    }
    triangles_.shrink_to_fit();
    blockIds_.shrink_to_fit();
    builderNodes_ = std::move(tree.nodes);
    primIndices_ = std::move(tree.primIndices);

    stats_.primitives = total;
    stats_.memoryBytes = nodes_.size() * sizeof(KdNode) + triangles_.size() * sizeof(TriangleBlock) +
                         blockIds_.size() * sizeof(PrimRef) +
                         mixedPrims_.size() * sizeof(PrimRef);
    stats_.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

uint64_t KdTreeAccel::structureHash() const {
    uint64_t h = 0xcbf29ce484222325ULL;
    auto add = [&](const void* data, size_t bytes) {
        const auto* p = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
    };
    add(nodes_.data(), nodes_.size() * sizeof(KdNode));
    add(triangles_.data(), triangles_.size() * sizeof(TriangleBlock));
    add(blockIds_.data(), blockIds_.size() * sizeof(PrimRef));
    add(mixedPrims_.data(), mixedPrims_.size() * sizeof(PrimRef));
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
        const KdNode& b = builderNodes_[it.node];
        uint32_t first = b.word0, count = b.word1 >> 2;
        for (uint32_t k = 0; k < count; ++k) {
            PrimRef want = prims_[primIndices_[first + k]], got;
            if (n.word1 >> 2 & kMixedFlag) got = mixedPrims_[n.word0 + k];
            else got = blockIds_[size_t(n.word0) * kLanes + k];
            if (want.geomId != got.geomId || want.primId != got.primId) return "leaf block differs from the builder's leaf";
        }
    }
    // 2. Completeness: descend with each triangle clipped to the cell; every leaf whose cell the
    //    clipped triangle enters with positive extent across the splits must reference it.
    for (uint32_t prim = 0; prim < prims_.size(); ++prim) {
        PrimRef ref = prims_[prim];
        if (ref.geomId == geometry_.sphereGeomId()) continue;
        const TriangleMesh& mesh = geometry_.meshes[ref.geomId];
        const glm::uvec3& t = mesh.triangles[ref.primId];
        const Vec3f &p0 = mesh.positions[t.x], &p1 = mesh.positions[t.y], &p2 = mesh.positions[t.z];
        std::vector<std::pair<uint32_t, Bounds3f>> stack{{0u, rootCell_}};
        while (!stack.empty()) {
            auto [index, cell] = stack.back();
            stack.pop_back();
            Vec3d lo, hi;
            if (!clipTriangleDouble(p0, p1, p2, cell, lo, hi)) continue;
            const KdNode& n = builderNodes_[index];
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
