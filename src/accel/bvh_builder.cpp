#include "accel/bvh_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <tuple>
#include <utility>

#include "accel/bvh_binning.h"
#include "core/huge_page_allocator.h"

namespace tessera {
namespace {

using simd::Vf4;
using simd::Vi4;

/// One primitive as the builder moves it around: its box in two SIMD registers, the primitive index
/// in the lower corner's unused fourth lane (Embree's PrimRef layout). Partitioning these 32-byte
/// records (not indices into the caller's arrays) keeps every pass over a node sequential in memory.
/// The builder bins centroids doubled, lo + hi, which saves a multiply per use and bins alike.
struct alignas(32) Ref {
    Vf4 lo, hi;
    uint32_t index() const {
        uint32_t i;
        std::memcpy(&i, reinterpret_cast<const char*>(&lo) + 12, 4);
        return i;
    }
    TESSERA_INLINE Vf4 lower() const { return xyz(lo); }
    TESSERA_INLINE Vf4 centroid2() const { return xyz(lo) + hi; }
};

class Builder {
public:
    Builder(std::span<const Bounds3f> b, const BvhConfig& cfg, BinaryBvh& out) : primBounds_(b), config_(cfg), out_(out) {
        config_.binCount = std::clamp(config_.binCount, 2, kMaxBins);
        config_.maxLeafSize = std::clamp(config_.maxLeafSize, 1, 15);  // 4 bits in BVH8 leaf refs
        config_.sahBlockSize = std::max(config_.sahBlockSize, 1);
        config_.parallelThreshold = std::max(config_.parallelThreshold, 2);
    }

    void run() {
        size_t n = primBounds_.size();
        if (n == 0) return;
        refs_.resize(n);
        // The references and the root's two boxes in parallel (min and max are exact in any
        // order, so the boxes do not depend on the split): with two threads these serial passes
        // had been a tenth of the dragon's build.
        using BoxPair = std::pair<Box, Box>;
        auto [bounds, centroids] = tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, n, 8192), BoxPair{},
            [&](const tbb::blocked_range<size_t>& range, BoxPair boxes) {
                for (size_t i = range.begin(); i != range.end(); ++i) {
                    const Bounds3f& b = primBounds_[i];
                    float indexBits;
                    uint32_t idx = uint32_t(i);
                    std::memcpy(&indexBits, &idx, 4);
                    Ref& r = refs_[i];
                    r = Ref{Vf4{b.lower.x, b.lower.y, b.lower.z, indexBits}, Vf4{b.upper.x, b.upper.y, b.upper.z, 0.f}};
                    boxes.first.extend(r.lower(), r.hi);
                    Vf4 c = r.centroid2();
                    boxes.second.extend(c, c);
                }
                return boxes;
            },
            [](BoxPair a, const BoxPair& b) {
                a.first.extend(b.first);
                a.second.extend(b.second);
                return a;
            });
        out_.nodes.allocate(2 * n - 1);
        uint32_t cursor = 1;
        build(0, 0, uint32_t(n), bounds, centroids, 0, cursor);
        out_.primIndices.resize(n);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16384), [&](const tbb::blocked_range<size_t>& range) {
            for (size_t i = range.begin(); i != range.end(); ++i) out_.primIndices[i] = refs_[i].index();
        });
        out_.maxDepth = maxDepth_.load();
    }

private:
    std::span<const Bounds3f> primBounds_;
    BvhConfig config_;
    BinaryBvh& out_;
    std::vector<Ref, HugePageAllocator<Ref>> refs_;  // written in full by run(): not zeroed first
    std::atomic<uint32_t> maxDepth_{0};

    float blocks(uint32_t n) const { return sahBlocks(n, config_.sahBlockSize); }

    void binRange(uint32_t begin, uint32_t end, const BinMapping& map, Binning& bins) const {
        uint32_t i = begin;
        if (end - begin >= 256) {
            // Neighbouring references usually fall into the same bin (the array is partitioned
            // spatially), so one set of bins makes every update wait for the previous store of the
            // same bin. Alternating between two sets halves that dependency chain; min/max and
            // counts merge exactly.
            Binning odd(map.binCount);
            for (; i + 1 < end; i += 2) {
                const Ref& r0 = refs_[i];
                const Ref& r1 = refs_[i + 1];
                Vf4 lo0 = r0.lower(), lo1 = r1.lower();
                Vi4 b0 = map.bins(lo0 + r0.hi), b1 = map.bins(lo1 + r1.hi);
                bins.add(0, b0[0], lo0, r0.hi);
                odd.add(0, b1[0], lo1, r1.hi);
                bins.add(1, b0[1], lo0, r0.hi);
                odd.add(1, b1[1], lo1, r1.hi);
                bins.add(2, b0[2], lo0, r0.hi);
                odd.add(2, b1[2], lo1, r1.hi);
            }
            bins.merge(odd, map.binCount);
        }
        for (; i < end; ++i) {
            const Ref& r = refs_[i];
            Vf4 lo = r.lower();
            Vi4 b = map.bins(lo + r.hi);
            bins.add(0, b[0], lo, r.hi);
            bins.add(1, b[1], lo, r.hi);
            bins.add(2, b[2], lo, r.hi);
        }
    }

    /// Fills `bins` (constructed for map.binCount bins). Written into the caller's object: a
    /// Binning is 3.5 KB and returning it by value showed up as a copy in every node.
    void binPrimitives(uint32_t begin, uint32_t end, const BinMapping& map, Binning& bins) const {
        if (end - begin < uint32_t(4 * config_.parallelThreshold)) {
            binRange(begin, end, map, bins);
            return;
        }
        // Bin boxes are min/max and counts integers: the merged result is exact in any order.
        bins = tbb::parallel_reduce(
            tbb::blocked_range<uint32_t>(begin, end, 8192), Binning(map.binCount),
            [&](const tbb::blocked_range<uint32_t>& r, Binning acc) {
                binRange(r.begin(), r.end(), map, acc);
                return acc;
            },
            [&](Binning a, const Binning& b) {
                a.merge(b, map.binCount);
                return a;
            });
    }

    void makeLeaf(uint32_t slot, uint32_t begin, uint32_t end, const Box& bounds, uint32_t depth) {
        BvhBuildNode& node = out_.nodes[slot];
        node.bounds = bounds.bounds();
        node.count = end - begin;
        node.left = begin;
        uint32_t seen = maxDepth_.load(std::memory_order_relaxed);
        while (depth > seen && !maxDepth_.compare_exchange_weak(seen, depth)) {}
    }

    /// Box and (doubled) centroid box of refs_[begin, end).
    std::pair<Box, Box> rangeBoxes(uint32_t begin, uint32_t end) const {
        std::pair<Box, Box> r;
        for (uint32_t i = begin; i < end; ++i) {
            Vf4 lo = refs_[i].lower(), c = lo + refs_[i].hi;
            r.first.extend(lo, refs_[i].hi);
            r.second.extend(c, c);
        }
        return r;
    }

    /// Moves the references whose centroid lies below bin `bin` on `axis` to the front of
    /// [begin, end) (Hoare), collecting each side's centroid box on the way. Returns the boundary.
    uint32_t partition(uint32_t begin, uint32_t end, const BinMapping& map, int axis, int bin, Box& leftCentroids,
                       Box& rightCentroids) {
        Ref* refs = refs_.data();
        float b = float(bin);
        uint32_t i = begin, j = end;
        while (true) {
            while (i < j) {
                Vf4 c = refs[i].centroid2();
                if (!map.below(c, axis, b)) break;
                leftCentroids.extend(c, c), ++i;
            }
            while (i < j) {
                Vf4 c = refs[j - 1].centroid2();
                if (map.below(c, axis, b)) break;
                --j, rightCentroids.extend(c, c);
            }
            if (i >= j) break;
            std::swap(refs[i], refs[j - 1]);
        }
        return i;
    }

    /// Builds the subtree of refs_[begin, end) at node `slot`. Node slots: a subtree of n
    /// primitives owns the 2n − 1 slots from its root's (the most a binary tree over n primitives
    /// needs), so that subtrees built in parallel land at the same slots whatever the thread count.
    /// Below parallelThreshold a subtree is built serially and takes its slots from the front of its
    /// range (`cursor`, in pairs of siblings, depth-first): the nodes it writes are packed together
    /// and the rest of its range (about two thirds with leaves of several primitives) is never
    /// touched, which saved the page faults of ~40 MB on the dragon.
    void build(uint32_t slot, uint32_t begin, uint32_t end, const Box& bounds, const Box& centroidBox, uint32_t depth,
               uint32_t& cursor) {
        uint32_t n = end - begin;
        // A leaf that no split can beat: a split costs at least traversalCost.
        if (n <= uint32_t(config_.maxLeafSize) && config_.intersectionCost * blocks(n) <= config_.traversalCost)
            return makeLeaf(slot, begin, end, bounds, depth);

        uint32_t mid = begin;
        ObjectSplit split;
        // Fewer bins than primitives cannot find more planes: small nodes use about one per primitive.
        int binCount = std::min(config_.binCount, std::max(4, int(n)));
        BinMapping map(centroidBox, binCount);
        bool degenerateCentroids = !(centroidBox.hi[0] > centroidBox.lo[0] || centroidBox.hi[1] > centroidBox.lo[1] ||
                                     centroidBox.hi[2] > centroidBox.lo[2]);
        if (!degenerateCentroids && int(depth) < config_.maxSahDepth) {
            Binning bins(binCount);
            binPrimitives(begin, end, map, bins);
            split = findObjectSplit(bins, binCount, config_.sahBlockSize);
            float area = bounds.halfArea();
            float leafCost = config_.intersectionCost * blocks(n);
            float splitCost = area > 0.f ? config_.traversalCost + config_.intersectionCost * split.cost / area : kInfinity;
            if (n <= uint32_t(config_.maxLeafSize) && leafCost <= splitCost) return makeLeaf(slot, begin, end, bounds, depth);
        } else if (n <= uint32_t(config_.maxLeafSize)) {
            return makeLeaf(slot, begin, end, bounds, depth);
        }

        Box leftBox, rightBox, leftCentroids, rightCentroids;
        if (split.axis >= 0) {
            // The children's boxes are the unions of their bins, already known from the sweep.
            mid = partition(begin, end, map, split.axis, split.bin, leftCentroids, rightCentroids);
            leftBox = split.left;
            rightBox = split.right;
        } else {
            // No SAH split (identical centroids or too deep): object median along the widest
            // centroid axis; ties broken by primitive index so the order is fully determined.
            Ref* refs = refs_.data();
            mid = begin + n / 2;
            if (!degenerateCentroids) {
                Vf4 e = centroidBox.hi - centroidBox.lo;
                int axis = e[0] >= e[1] && e[0] >= e[2] ? 0 : (e[1] >= e[2] ? 1 : 2);
                std::nth_element(refs + begin, refs + mid, refs + end, [&](const Ref& a, const Ref& b) {
                    float ca = a.centroid2()[axis], cb = b.centroid2()[axis];
                    return ca < cb || (ca == cb && a.index() < b.index());
                });
            }
            std::tie(leftBox, leftCentroids) = rangeBoxes(begin, mid);
            std::tie(rightBox, rightCentroids) = rangeBoxes(mid, end);
        }

        bool parallel = n >= uint32_t(config_.parallelThreshold);
        uint32_t leftSlot = parallel ? slot + 1 : cursor;
        uint32_t rightSlot = parallel ? slot + 2 * (mid - begin) : cursor + 1;
        if (!parallel) cursor += 2;
        BvhBuildNode& node = out_.nodes[slot];
        node.bounds = bounds.bounds();
        node.count = 0;
        node.left = leftSlot;
        node.right = rightSlot;

        if (parallel) {
            uint32_t leftCursor = leftSlot + 1, rightCursor = rightSlot + 1;
            tbb::parallel_invoke([&] { build(leftSlot, begin, mid, leftBox, leftCentroids, depth + 1, leftCursor); },
                                 [&] { build(rightSlot, mid, end, rightBox, rightCentroids, depth + 1, rightCursor); });
        } else {
            build(leftSlot, begin, mid, leftBox, leftCentroids, depth + 1, cursor);
            build(rightSlot, mid, end, rightBox, rightCentroids, depth + 1, cursor);
        }
    }
};

}  // namespace

BinaryBvh buildBinaryBvh(std::span<const Bounds3f> primBounds, const BvhConfig& config) {
    BinaryBvh out;
    Builder(primBounds, config, out).run();
    return out;
}

}  // namespace tessera
