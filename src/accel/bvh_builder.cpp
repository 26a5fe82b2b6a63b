#include "accel/bvh_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <numeric>

namespace tessera {
namespace {

constexpr int kMaxBins = 64;

float halfArea(const Bounds3f& b) {
    // Half the surface area: SAH only compares ratios, and empty boxes must count as 0.
    if (b.empty()) return 0.f;
    Vec3f d = b.upper - b.lower;
    return d.x * d.y + d.y * d.z + d.z * d.x;
}

/// Per-axis bins of one node: box and count of the primitives whose centroid falls in each bin.
struct Binning {
    std::array<std::array<Bounds3f, kMaxBins>, 3> bounds;
    std::array<std::array<uint32_t, kMaxBins>, 3> counts{};

    void merge(const Binning& o, int binCount) {
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < binCount; ++i) {
                bounds[a][i].extend(o.bounds[a][i]);
                counts[a][i] += o.counts[a][i];
            }
    }
};

/// Maps a centroid coordinate to its bin: k · (c − min) / extent, clamped (Wald 2007, eq. 1). The
/// same function bins and partitions, so a chosen split can never leave a side empty.
struct BinMapping {
    Vec3f lower, scale;
    int binCount;
    BinMapping(const Bounds3f& centroidBounds, int bins) : lower(centroidBounds.lower), binCount(bins) {
        Vec3f extent = centroidBounds.upper - centroidBounds.lower;
        for (int a = 0; a < 3; ++a)
            scale[a] = extent[a] > 0.f ? float(bins) * (1.f - 1e-6f) / extent[a] : 0.f;
    }
    int bin(const Vec3f& c, int axis) const {
        int i = int((c[axis] - lower[axis]) * scale[axis]);
        return std::clamp(i, 0, binCount - 1);
    }
};

class Builder {
public:
    Builder(std::span<const Bounds3f> b, std::span<const Vec3f> c, const BvhConfig& cfg, BinaryBvh& out)
        : primBounds_(b), centroids_(c), config_(cfg), out_(out) {
        config_.binCount = std::clamp(config_.binCount, 2, kMaxBins);
        config_.maxLeafSize = std::clamp(config_.maxLeafSize, 1, 15);  // 4 bits in BVH8 leaf refs
        config_.sahBlockSize = std::max(config_.sahBlockSize, 1);
    }

    void run() {
        size_t n = primBounds_.size();
        out_.primIndices.resize(n);
        std::iota(out_.primIndices.begin(), out_.primIndices.end(), 0u);
        if (n == 0) return;
        out_.nodes.resize(2 * n - 1);
        auto [bounds, centroidBounds] = rangeBounds(0, uint32_t(n));
        build(0, 0, uint32_t(n), bounds, centroidBounds, 0);
        out_.maxDepth = maxDepth_.load();
    }

private:
    std::span<const Bounds3f> primBounds_;
    std::span<const Vec3f> centroids_;
    BvhConfig config_;
    BinaryBvh& out_;
    std::atomic<uint32_t> maxDepth_{0};

    float blocks(uint32_t n) const { return float((n + uint32_t(config_.sahBlockSize) - 1) / uint32_t(config_.sahBlockSize)); }

    std::pair<Bounds3f, Bounds3f> rangeBounds(uint32_t begin, uint32_t end) const {
        using Pair = std::pair<Bounds3f, Bounds3f>;
        const uint32_t* idx = out_.primIndices.data();
        // Min/max are exact, so any reduction order gives the same boxes.
        return tbb::parallel_reduce(
            tbb::blocked_range<uint32_t>(begin, end, 16384), Pair{},
            [&](const tbb::blocked_range<uint32_t>& r, Pair acc) {
                for (uint32_t i = r.begin(); i != r.end(); ++i) {
                    acc.first.extend(primBounds_[idx[i]]);
                    acc.second.extend(centroids_[idx[i]]);
                }
                return acc;
            },
            [](Pair a, const Pair& b) {
                a.first.extend(b.first);
                a.second.extend(b.second);
                return a;
            });
    }

    void binRange(uint32_t begin, uint32_t end, const BinMapping& map, Binning& bins) const {
        const uint32_t* idx = out_.primIndices.data();
        for (uint32_t i = begin; i < end; ++i) {
            uint32_t p = idx[i];
            const Vec3f& c = centroids_[p];
            for (int a = 0; a < 3; ++a) {
                int b = map.bin(c, a);
                bins.bounds[a][b].extend(primBounds_[p]);
                ++bins.counts[a][b];
            }
        }
    }

    Binning binPrimitives(uint32_t begin, uint32_t end, const BinMapping& map) const {
        if (end - begin < uint32_t(4 * config_.parallelThreshold)) {
            Binning bins;
            binRange(begin, end, map, bins);
            return bins;
        }
        // Bin boxes are min/max and counts integers: the merged result is exact in any order.
        return tbb::parallel_reduce(
            tbb::blocked_range<uint32_t>(begin, end, 8192), Binning{},
            [&](const tbb::blocked_range<uint32_t>& r, Binning acc) {
                binRange(r.begin(), r.end(), map, acc);
                return acc;
            },
            [&](Binning a, const Binning& b) {
                a.merge(b, config_.binCount);
                return a;
            });
    }

    struct Split {
        int axis = -1, bin = 0;
        float cost = kInfinity;
    };

    /// Sweeps the bins of each axis from both ends and returns the cheapest plane (in units of
    /// half-area × blocks; the node's constant terms are added by the caller).
    Split findSplit(const Binning& bins) const {
        Split best;
        int k = config_.binCount;
        for (int a = 0; a < 3; ++a) {
            std::array<float, kMaxBins> rightCost{};
            Bounds3f acc;
            uint32_t count = 0;
            for (int i = k - 1; i > 0; --i) {
                acc.extend(bins.bounds[a][i]);
                count += bins.counts[a][i];
                rightCost[i] = halfArea(acc) * blocks(count);
            }
            acc = Bounds3f();
            count = 0;
            uint32_t total = 0;
            for (int i = 0; i < k; ++i) total += bins.counts[a][i];
            for (int i = 1; i < k; ++i) {
                acc.extend(bins.bounds[a][i - 1]);
                count += bins.counts[a][i - 1];
                if (count == 0 || count == total) continue;
                float cost = halfArea(acc) * blocks(count) + rightCost[i];
                if (cost < best.cost) best = {a, i, cost};  // strict: lowest axis, then bin, wins ties
            }
        }
        return best;
    }

    void makeLeaf(uint32_t slot, uint32_t begin, uint32_t end, const Bounds3f& bounds, uint32_t depth) {
        BvhBuildNode& node = out_.nodes[slot];
        node.bounds = bounds;
        node.count = end - begin;
        node.left = begin;
        uint32_t seen = maxDepth_.load(std::memory_order_relaxed);
        while (depth > seen && !maxDepth_.compare_exchange_weak(seen, depth)) {}
    }

    void build(uint32_t slot, uint32_t begin, uint32_t end, const Bounds3f& bounds, const Bounds3f& centroidBounds,
               uint32_t depth) {
        uint32_t n = end - begin;
        if (n == 1) return makeLeaf(slot, begin, end, bounds, depth);

        uint32_t* idx = out_.primIndices.data();
        uint32_t mid = begin;
        Split split;
        BinMapping map(centroidBounds, config_.binCount);
        bool degenerateCentroids = centroidBounds.upper == centroidBounds.lower;
        if (!degenerateCentroids && int(depth) < config_.maxSahDepth) {
            split = findSplit(binPrimitives(begin, end, map));
            float area = halfArea(bounds);
            float leafCost = config_.intersectionCost * blocks(n);
            float splitCost = area > 0.f ? config_.traversalCost + config_.intersectionCost * split.cost / area : kInfinity;
            if (n <= uint32_t(config_.maxLeafSize) && leafCost <= splitCost)
                return makeLeaf(slot, begin, end, bounds, depth);
        } else if (n <= uint32_t(config_.maxLeafSize)) {
            return makeLeaf(slot, begin, end, bounds, depth);
        }

        if (split.axis >= 0) {
            int axis = split.axis, bin = split.bin;
            mid = uint32_t(std::partition(idx + begin, idx + end, [&](uint32_t p) { return map.bin(centroids_[p], axis) < bin; }) - idx);
        } else {
            // No SAH split (identical centroids or too deep): object median along the widest
            // centroid axis; ties broken by primitive index so the order is fully determined.
            mid = begin + n / 2;
            if (!degenerateCentroids) {
                Vec3f e = centroidBounds.upper - centroidBounds.lower;
                int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
                std::nth_element(idx + begin, idx + mid, idx + end, [&](uint32_t a, uint32_t b) {
                    float ca = centroids_[a][axis], cb = centroids_[b][axis];
                    return ca < cb || (ca == cb && a < b);
                });
            }
        }

        uint32_t leftSlot = slot + 1, rightSlot = slot + 2 * (mid - begin);
        BvhBuildNode& node = out_.nodes[slot];
        node.bounds = bounds;
        node.count = 0;
        node.left = leftSlot;
        node.right = rightSlot;

        auto buildLeft = [&] {
            auto [b, c] = childBounds(begin, mid);
            build(leftSlot, begin, mid, b, c, depth + 1);
        };
        auto buildRight = [&] {
            auto [b, c] = childBounds(mid, end);
            build(rightSlot, mid, end, b, c, depth + 1);
        };
        if (n >= uint32_t(config_.parallelThreshold)) tbb::parallel_invoke(buildLeft, buildRight);
        else {
            buildLeft();
            buildRight();
        }
    }

    std::pair<Bounds3f, Bounds3f> childBounds(uint32_t begin, uint32_t end) const {
        if (end - begin >= uint32_t(4 * config_.parallelThreshold)) return rangeBounds(begin, end);
        std::pair<Bounds3f, Bounds3f> r;
        const uint32_t* idx = out_.primIndices.data();
        for (uint32_t i = begin; i < end; ++i) {
            r.first.extend(primBounds_[idx[i]]);
            r.second.extend(centroids_[idx[i]]);
        }
        return r;
    }
};

}  // namespace

BinaryBvh buildBinaryBvh(std::span<const Bounds3f> primBounds, std::span<const Vec3f> centroids, const BvhConfig& config) {
    BinaryBvh out;
    Builder(primBounds, centroids, config, out).run();
    return out;
}

}  // namespace tessera
