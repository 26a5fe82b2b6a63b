#include "accel/photon_map.h"

#include <algorithm>
#include <numeric>

#include "core/thread_pool.h"

namespace tessera {
namespace {

/// The finite points of `points`, with their input indices.
std::vector<PhotonRef> gatherFinite(std::span<const Vec3f> points) {
    std::vector<PhotonRef> refs;
    refs.reserve(points.size());
    for (size_t i = 0; i < points.size(); ++i)
        if (isFinite(points[i])) refs.push_back({points[i], uint32_t(i)});
    return refs;
}

/// Levels built by the calling thread before the subtrees are handed to the pool: 2⁶ = 64
/// subtrees, whatever the thread count, so the tree does not depend on it.
constexpr int kSerialLevels = 6;

}  // namespace

void PhotonKdTree::build(std::span<const Vec3f> points, ThreadPool* pool) {
    nodes_ = gatherFinite(points);
    axis_.assign(nodes_.size(), 0);
    if (nodes_.empty()) return;
    // The top levels split serially and leave up to 2^kSerialLevels ranges, which build
    // independently: each node's split only reorders the points of its own range.
    std::vector<Range> subtrees;
    buildLevels({0u, uint32_t(nodes_.size())}, kSerialLevels, &subtrees);
    auto buildSubtree = [&](size_t i) { buildLevels(subtrees[i], -1, nullptr); };
    if (pool && pool->threads() > 1) pool->parallelFor(subtrees.size(), buildSubtree);
    else
        for (size_t i = 0; i < subtrees.size(); ++i) buildSubtree(i);
}

void PhotonKdTree::buildLevels(Range root, int levels, std::vector<Range>* below) {
    std::vector<std::pair<Range, int>> stack{{root, 0}};
    while (!stack.empty()) {
        auto [r, depth] = stack.back();
        stack.pop_back();
        if (r.second - r.first <= 1) continue;
        if (levels >= 0 && depth == levels) {
            below->push_back(r);
            continue;
        }
        splitRange(r.first, r.second);
        const uint32_t m = r.first + (r.second - r.first) / 2;
        stack.push_back({{m + 1, r.second}, depth + 1});
        stack.push_back({{r.first, m}, depth + 1});
    }
}

void PhotonKdTree::splitRange(uint32_t begin, uint32_t end) {
    // Split the node [begin, end) at its median on the axis of largest extent (Jensen 2001,
    // §6.3.1): the median point goes to the middle position, smaller coordinates before it, larger
    // after. Ties are ordered by input index, so the layout is a function of the points alone.
    Bounds3f box;
    for (uint32_t k = begin; k < end; ++k) box.extend(nodes_[k].p);
    const Vec3f extent = box.diagonal();
    const int a = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const uint32_t m = begin + (end - begin) / 2;
    std::nth_element(nodes_.begin() + begin, nodes_.begin() + m, nodes_.begin() + end, [a](const PhotonRef& u, const PhotonRef& v) {
        return u.p[a] < v.p[a] || (u.p[a] == v.p[a] && u.index < v.index);
    });
    axis_[m] = uint8_t(a);
}

void PhotonHashGrid::build(std::span<const Vec3f> points, float radius, ThreadPool* pool, size_t tableSize) {
    const std::vector<PhotonRef> refs = gatherFinite(points);
    radius_ = radius > 0.f && std::isfinite(radius) ? radius : 0.f;
    const size_t n = radius_ > 0.f ? refs.size() : 0;
    bucketEnd_.assign(std::max<size_t>(tableSize > 0 ? tableSize : n, 1), 0);
    points_.resize(n);
    if (n == 0) return;
    Bounds3f box;
    for (const PhotonRef& r : refs) box.extend(r.p);
    origin_ = box.lower;
    invCellSize_ = 1.0 / (2.0 * double(radius_));
    // Counting sort by bucket (stable: input order inside a bucket). The hashes are computed in
    // parallel; the counts and the scatter are serial passes.
    std::vector<uint32_t> bucket(n);
    constexpr size_t kChunk = 4096;
    auto hashChunk = [&](size_t c) {
        for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i)
            bucket[i] = bucketOf(cellOf(refs[i].p, 0), cellOf(refs[i].p, 1), cellOf(refs[i].p, 2));
    };
    const size_t chunks = (n + kChunk - 1) / kChunk;
    if (pool && pool->threads() > 1) pool->parallelFor(chunks, hashChunk);
    else
        for (size_t c = 0; c < chunks; ++c) hashChunk(c);
    for (uint32_t b : bucket) ++bucketEnd_[b];
    std::partial_sum(bucketEnd_.begin(), bucketEnd_.end(), bucketEnd_.begin());
    // Scatter from the back so that each bucket keeps input order; bucketEnd_[b] ends at the start
    // of bucket b, and one rotation turns starts into ends.
    for (size_t i = n; i-- > 0;) points_[--bucketEnd_[bucket[i]]] = refs[i];
    std::rotate(bucketEnd_.begin(), bucketEnd_.begin() + 1, bucketEnd_.end());
    bucketEnd_.back() = uint32_t(n);
}

}  // namespace tessera
