#pragma once
/// \file photon_map.h
/// Fixed-radius queries over a set of points (photons, or the light vertices VCM merges with): every
/// point within distance r of x. Two structures behind the same query, so that the photon-mapping
/// integrators can use the faster (issue #20 asks for both to be measured; `tessera bench-photons`):
///  * PhotonKdTree: Jensen's photon map (H. W. Jensen, "Global Illumination using Photon Maps",
///    EGWR 1996; "Realistic Image Synthesis Using Photon Mapping", 2001, §6.3): a balanced k-d tree
///    stored implicitly, each node's point at the median of its range, split on the axis of largest
///    extent. Any radius per query.
///  * PhotonHashGrid: the hashed uniform grid of SmallVCM's VCM (I. Georgiev et al., "Light
///    Transport Simulation with Vertex Connection and Merging", SIGGRAPH Asia 2012; cells hashed as
///    in M. Teschner et al., "Optimized Spatial Hashing for Collision Detection of Deformable
///    Objects", VMV 2003): cells of twice the build radius, so a query of that radius touches 2×2×2
///    cells. Queries up to the build radius.
/// Both visit the points within r in an order that depends only on the points and the query, never
/// on the thread count of the build: sums over a query's points are bit-identical for any thread
/// count. A point at distance exactly r is inside (|p − x|² ≤ r²). Points with a non-finite
/// coordinate are left out of both structures (never found), and a non-finite query finds nothing.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "core/bounds.h"
#include "core/math.h"

namespace tessera {

class ThreadPool;

/// A stored point: its position and its index in the input, together (four to a cache line).
struct PhotonRef {
    Vec3f p;
    uint32_t index;
};

class PhotonKdTree {
public:
    /// Builds over `points` (copied); `pool` (may be null) builds the subtrees below the top levels
    /// in parallel. The tree is the same for any pool.
    void build(std::span<const Vec3f> points, ThreadPool* pool = nullptr);

    /// Calls visit(index into the built points) for every point with |p − x|² ≤ radius².
    template <class Visit>
    void forEachWithin(const Vec3f& x, float radius, Visit&& visit) const;

    size_t size() const { return nodes_.size(); }
    /// Bytes held: 16 per point (position and input index) and its split axis.
    size_t memoryBytes() const { return nodes_.capacity() * sizeof(PhotonRef) + axis_.capacity(); }

private:
    using Range = std::pair<uint32_t, uint32_t>;  ///< positions [first, second)
    /// Builds the subtree of `root` down to `levels` levels below it (all, when negative) and
    /// appends the unsplit ranges left at that depth to `below`.
    void buildLevels(Range root, int levels, std::vector<Range>* below);
    void splitRange(uint32_t begin, uint32_t end);

    // Node of range [b, e): its point is at m = b + (e − b)/2, left child [b, m), right [m + 1, e).
    std::vector<PhotonRef> nodes_;  ///< points in tree order
    std::vector<uint8_t> axis_;     ///< split axis of the node at each position
};

class PhotonHashGrid {
public:
    /// Builds over `points` (copied) for queries of radius ≤ `radius` (> 0). `tableSize` hash buckets
    /// (0: one per point, as SmallVCM); `pool` (may be null) hashes in parallel.
    void build(std::span<const Vec3f> points, float radius, ThreadPool* pool = nullptr, size_t tableSize = 0);

    /// Calls visit(index into the built points) for every point with |p − x|² ≤ radius², radius at
    /// most the build radius.
    template <class Visit>
    void forEachWithin(const Vec3f& x, float radius, Visit&& visit) const;

    size_t size() const { return points_.size(); }
    float radius() const { return radius_; }
    /// Bytes held: 16 per point and 4 per bucket.
    size_t memoryBytes() const { return points_.capacity() * sizeof(PhotonRef) + bucketEnd_.capacity() * sizeof(uint32_t); }

private:
    uint32_t bucketOf(int64_t cx, int64_t cy, int64_t cz) const {
        // Teschner et al. 2003's primes; unsigned arithmetic wraps by definition.
        uint64_t h = (uint64_t(cx) * 73856093u) ^ (uint64_t(cy) * 19349663u) ^ (uint64_t(cz) * 83492791u);
        return uint32_t(h % bucketEnd_.size());
    }
    /// The cell coordinate of p along axis a, in double and clamped to ±2⁶², so that the cell index
    /// is exact for any finite point and radius (clamping is monotone: neighbours stay neighbours).
    double cellCoord(const Vec3f& p, int a) const {
        return std::clamp((double(p[a]) - double(origin_[a])) * invCellSize_, -0x1p62, 0x1p62);
    }
    int64_t cellOf(const Vec3f& p, int a) const { return int64_t(std::floor(cellCoord(p, a))); }

    std::vector<PhotonRef> points_;   ///< sorted by bucket (input order inside a bucket)
    std::vector<uint32_t> bucketEnd_; ///< bucket b holds sorted positions [bucketEnd_[b−1], bucketEnd_[b])
    Vec3f origin_{0.f};
    float radius_ = 0.f;
    double invCellSize_ = 0.0;
};

template <class Visit>
void PhotonKdTree::forEachWithin(const Vec3f& x, float radius, Visit&& visit) const {
    if (nodes_.empty() || !(radius >= 0.f) || !isFinite(x)) return;
    const float r2 = radius * radius;
    // Ranges still to visit; a balanced tree of 2³² points is 32 levels deep, one far range per level.
    struct Range {
        uint32_t begin, end;
    };
    Range stack[64];
    int top = 0;
    stack[top++] = {0, uint32_t(nodes_.size())};
    while (top > 0) {
        const Range r = stack[--top];
        const uint32_t m = r.begin + (r.end - r.begin) / 2;
        const Vec3f& p = nodes_[m].p;
        const Vec3f d = p - x;
        if (glm::dot(d, d) <= r2) visit(nodes_[m].index);
        if (r.end - r.begin == 1) continue;
        const int a = axis_[m];
        const float planeDist = x[a] - p[a];
        // Left of the median: coordinates ≤ p[a]; right: ≥ p[a]. The far side can hold a point
        // within the radius only if the plane is.
        const Range left{r.begin, m}, right{m + 1, r.end};
        const Range& nearSide = planeDist < 0.f ? left : right;
        const Range& farSide = planeDist < 0.f ? right : left;
        if (planeDist * planeDist <= r2 && farSide.begin < farSide.end) stack[top++] = farSide;
        if (nearSide.begin < nearSide.end) stack[top++] = nearSide;
    }
}

template <class Visit>
void PhotonHashGrid::forEachWithin(const Vec3f& x, float radius, Visit&& visit) const {
    if (points_.empty() || !(radius >= 0.f) || radius > radius_ || !isFinite(x)) return;
    const float r2 = radius * radius;
    // Cells are 2·radius_ wide: the ball lies in the cell of x and its neighbour on the side of
    // each axis x is closer to (SmallVCM's HashGrid::Process).
    int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        double c = cellCoord(x, a), f = std::floor(c);
        int64_t cell = int64_t(f), other = c - f < 0.5 ? cell - 1 : cell + 1;
        lo[a] = std::min(cell, other);
        hi[a] = std::max(cell, other);
    }
    // Two of the eight cells may share a bucket: each bucket is visited once, in the order met.
    uint32_t seen[8];
    int nSeen = 0;
    for (int64_t cz = lo[2]; cz <= hi[2]; ++cz)
        for (int64_t cy = lo[1]; cy <= hi[1]; ++cy)
            for (int64_t cx = lo[0]; cx <= hi[0]; ++cx) {
                const uint32_t b = bucketOf(cx, cy, cz);
                bool repeated = false;
                for (int k = 0; k < nSeen; ++k) repeated |= seen[k] == b;
                if (repeated) continue;
                seen[nSeen++] = b;
                const uint32_t first = b == 0 ? 0u : bucketEnd_[b - 1], last = bucketEnd_[b];
                for (uint32_t k = first; k < last; ++k) {
                    const Vec3f d = points_[k].p - x;
                    if (glm::dot(d, d) <= r2) visit(points_[k].index);
                }
            }
}

}  // namespace tessera
