#include "accel/kdtree_builder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include "core/error.h"

namespace tessera {

KdNode KdNode::inner(int axis, float split, uint32_t aboveChild) {
    KdNode n;
    std::memcpy(&n.word0, &split, 4);
    n.word1 = aboveChild << 2 | uint32_t(axis);
    return n;
}

KdNode KdNode::leaf(uint32_t first, uint32_t payload) {
    KdNode n;
    n.word0 = first;
    n.word1 = payload << 2 | 3u;
    return n;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Events. One 64-bit integer each, so that sorting, merging and comparing are integer operations:
//   bits 62..63 axis | bits 30..61 position (order-preserving bits of the float) | bits 28..29 type
//   | bits 0..27 primitive.
// Sorting by the whole key orders events by axis, then position, then type end < planar < start
// (the order the sweep needs, W&H Section 4.2), then primitive (determinism). One sorted list per
// node holds the three axes one after another.
// ---------------------------------------------------------------------------------------------
using Event = uint64_t;
constexpr int kPrimBits = 28;
constexpr uint32_t kPrimMask = (1u << kPrimBits) - 1u;
enum EventType : uint32_t { kEnd = 0, kPlanar = 1, kStart = 2 };

inline uint32_t sortableBits(float f) {
    if (f == 0.f) f = 0.f;  // −0.0 and +0.0 are one plane: float and key comparisons must agree
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
inline float fromSortableBits(uint32_t s) {
    uint32_t u = (s & 0x80000000u) ? (s & 0x7fffffffu) : ~s;
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}
inline Event makeEvent(int axis, float pos, EventType type, uint32_t prim) {
    return uint64_t(axis) << 62 | uint64_t(sortableBits(pos)) << 30 | uint64_t(type) << kPrimBits | prim;
}
inline int eventAxis(Event e) { return int(e >> 62); }
inline float eventPos(Event e) { return fromSortableBits(uint32_t(e >> 30)); }
inline uint32_t eventType(Event e) { return uint32_t(e >> kPrimBits) & 3u; }
inline uint32_t eventPrim(Event e) { return uint32_t(e) & kPrimMask; }
/// Axis and position: equal for all events of one candidate plane.
inline uint64_t eventPlane(Event e) { return e >> 30; }

/// The events of one primitive box on one axis: start and end, or one planar event where it is flat.
inline void appendAxisEvents(const Bounds3f& b, int a, uint32_t prim, std::vector<Event>& out) {
    if (b.lower[a] == b.upper[a]) {
        out.push_back(makeEvent(a, b.lower[a], kPlanar, prim));
    } else {
        out.push_back(makeEvent(a, b.lower[a], kStart, prim));
        out.push_back(makeEvent(a, b.upper[a], kEnd, prim));
    }
}

/// The events of one primitive box on all three axes.
inline void appendEvents(const Bounds3f& b, uint32_t prim, std::vector<Event>& out) {
    for (int a = 0; a < 3; ++a) appendAxisEvents(b, a, prim, out);
}

/// Stable LSD radix sort on the key bits above the primitive (axis, position, type): 3 passes of
/// 12 bits, from `src` to `dst` and back (`src` is scratch; the result lies in `dst`). Events are
/// generated in primitive order, so the result is sorted by the whole key.
void radixSortEventsInto(Event* src, Event* dst, size_t n) {
    constexpr int kBits = 12;
    constexpr size_t kBuckets = size_t(1) << kBits;
    std::vector<size_t> count(kBuckets);
    Event* from = src;
    Event* to = dst;
    for (int shift = kPrimBits; shift < 64; shift += kBits) {
        std::fill(count.begin(), count.end(), 0);
        for (size_t i = 0; i < n; ++i) ++count[(from[i] >> shift) & (kBuckets - 1)];
        size_t sum = 0;
        for (size_t& c : count) {
            size_t k = c;
            c = sum;
            sum += k;
        }
        for (size_t i = 0; i < n; ++i) to[count[(from[i] >> shift) & (kBuckets - 1)]++] = from[i];
        std::swap(from, to);
    }
    static_assert((64 - kPrimBits) / kBits % 2 == 1, "an odd number of passes leaves the result in dst");
}

/// A node's sorted events. Not a std::vector: children's lists are written once by a merge, and
/// value-initialising them first would cost a pass over every event of every level.
struct EventList {
    std::unique_ptr<Event[]> data;
    size_t size = 0;
    void allocate(size_t n) {
        data.reset(n ? new Event[n] : nullptr);
        size = n;
    }
    void release() {
        data.reset();
        size = 0;
    }
    const Event* begin() const { return data.get(); }
    const Event* end() const { return data.get() + size; }
    Event operator[](size_t i) const { return data[i]; }
};

enum Side : uint8_t { kBoth = 0, kLeftOnly = 1, kRightOnly = 2 };

struct SplitCandidate {
    float cost = std::numeric_limits<float>::infinity();
    int axis = -1;
    float pos = 0.f;
    bool planarLeft = false;
};

/// The SAH of the candidate planes on one axis of a cell (KdConfig: W&H Section 3 with the
/// empty-space bonus): one cost model for the binned and the swept levels.
struct AxisSah {
    float lo = 0.f, hi = 0.f;              ///< the cell's extent on the axis
    float crossArea = 0.f, perimeter = 0.f;  ///< d_b·d_c and d_b + d_c of the other two axes
    float invArea = 0.f, minEmpty = 0.f;

    AxisSah() = default;
    AxisSah(const Bounds3f& cell, const Vec3f& d, float invCellArea, int a, float emptyCutMinFraction)
        : lo(cell.lower[a]), hi(cell.upper[a]), invArea(invCellArea) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        crossArea = d[b] * d[c];
        perimeter = d[b] + d[c];
        minEmpty = emptyCutMinFraction * (hi - lo);
    }
    /// Children's areas relative to the cell's, 2·(len·(d_b + d_c) + d_b·d_c) / A (flat cells,
    /// d = 0, are fine).
    float leftFraction(float p) const { return 2.f * ((p - lo) * perimeter + crossArea) * invArea; }
    float rightFraction(float p) const { return 2.f * ((hi - p) * perimeter + crossArea) * invArea; }
    /// λ(p)·(C_trav + C_isect·(P_L·B(N_L) + P_R·B(N_R))) for blocks bl = B(N_L), br = B(N_R).
    float cost(float p, uint32_t cl, uint32_t cr, float bl, float br, const KdConfig& config) const {
        float c = config.traversalCost + config.intersectionCost * (leftFraction(p) * bl + rightFraction(p) * br);
        bool emptySide = (cl == 0 && p - lo >= minEmpty) || (cr == 0 && hi - p >= minEmpty);
        return emptySide ? (1.f - config.emptyBonus) * c : c;
    }
};

class KdBuilder {
public:
    /// `parallel`: build sibling subtrees of more than config.parallelAbove references as TBB tasks.
    KdBuilder(std::span<const Bounds3f> bounds, const KdClipFunction& clip, const KdConfig& config, int depthLimit, bool parallel)
        : bounds_(bounds), clip_(clip), config_(config), depthLimit_(depthLimit), parallel_(parallel),
          scratch_([n = bounds.size()] { return Scratch(n); }) {
        invBlockSize_ = 1.f / float(std::max(1, config.sahBlockSize));
    }

    /// Builds the two children of the inner node `nodeIndex` (just appended to `out`) with
    /// buildLeft(tree) and buildRight(tree), sets the node, and returns the children's costs.
    /// Serially, the left subtree is appended to `out` and then the right one. In parallel, the
    /// right subtree is built into a tree of its own while the left one grows `out`, and is then
    /// appended with its node and reference indices moved: the nodes, leaves and statistics come out
    /// exactly as in the serial order, whatever the number of threads (a subtree's build reads
    /// nothing but its own input; the scratch buffers are per thread and hold nothing across the
    /// recursion).
    template <class BuildLeft, class BuildRight>
    std::pair<double, double> buildChildren(KdTree& out, uint32_t nodeIndex, const SplitCandidate& split, size_t work,
                                            BuildLeft&& buildLeft, BuildRight&& buildRight) {
        double costL = 0.0, costR = 0.0;
        uint32_t above;
        if (parallel_ && work > config_.parallelAbove) {
            KdTree right;
            tbb::parallel_invoke([&] { costL = buildLeft(out); }, [&] { costR = buildRight(right); });
            above = uint32_t(out.nodes.size());
            appendSubtree(out, right);
        } else {
            costL = buildLeft(out);
            above = uint32_t(out.nodes.size());
            costR = buildRight(out);
        }
        out.nodes[nodeIndex] = KdNode::inner(split.axis, split.pos, above);
        return {costL, costR};
    }

    /// Builds the subtree of `cell` from its sorted events (consumed); returns its expected cost
    /// relative to the cell's area (leaf: C_isect·B(N); inner: C_trav + P_L·C_L + P_R·C_R).
    double build(EventList& events, uint32_t count, const Bounds3f& cell, int depth, int badRefines, KdTree& out) {
        out.stats.maxDepth = std::max(out.stats.maxDepth, depth);
        const float leafCost = config_.intersectionCost * blocks(count);
        if (count == 0) return makeLeaf(events, out);
        if (depth >= depthLimit_) {
            ++out.stats.depthLimitHits;
            return makeLeaf(events, out);
        }
        size_t segment[4];
        out.stats.eventsSwept += events.size;
        SplitCandidate best = findSplit(events, count, cell, segment);
        // pbrt-v3's termination: a split worse than a leaf is allowed a few times along a path.
        bool bad = best.cost >= leafCost;
        if (bad) ++badRefines;
        if (best.axis < 0 || (bad && (badRefines > config_.maxBadRefines || (best.cost > 4.f * leafCost && count < 16))))
            return makeLeaf(events, out);

        // A bad refinement may be retracted: keep its primitives until the subtree is known.
        std::vector<uint32_t> retractPrims;
        if (bad) retractPrims = primsOf(events);

        Bounds3f leftCell = cell, rightCell = cell;
        leftCell.upper[best.axis] = best.pos;
        rightCell.lower[best.axis] = best.pos;
        EventList left, right;
        uint32_t leftCount = 0, rightCount = 0;
        split(events, segment, best, leftCell, rightCell, left, right, leftCount, rightCount);

        uint32_t nodeIndex = uint32_t(out.nodes.size());
        size_t primMark = out.primIndices.size();
        size_t leavesMark = out.stats.leaves, emptyMark = out.stats.emptyLeaves, refMark = out.stats.references;
        size_t innerMark = out.stats.innerNodes;
        out.nodes.emplace_back();
        ++out.stats.innerNodes;
        auto [costL, costR] = buildChildren(
            out, nodeIndex, best, size_t(leftCount) + rightCount,
            [&](KdTree& o) { return build(left, leftCount, leftCell, depth + 1, badRefines, o); },
            [&](KdTree& o) { return build(right, rightCount, rightCell, depth + 1, badRefines, o); });

        double area = cell.surfaceArea();
        double cost = config_.traversalCost +
                      (leftCell.surfaceArea() * costL + rightCell.surfaceArea() * costR) / area;
        if (bad && cost >= leafCost) {
            // The refinement did not pay: retract the whole subtree into one leaf.
            out.nodes.resize(nodeIndex);
            out.primIndices.resize(primMark);
            out.stats.leaves = leavesMark, out.stats.emptyLeaves = emptyMark, out.stats.references = refMark;
            out.stats.innerNodes = innerMark;
            ++out.stats.retractions;
            return emitLeaf(retractPrims, out);
        }
        return cost;
    }

    /// A reference of the binned levels: a primitive and its box clipped to the current cell.
    struct Ref {
        Bounds3f box;
        uint32_t prim;
    };

    /// Builds the subtree of `cell` over `refs` (consumed; sorted by primitive): binned SAH while
    /// the node holds more than `binnedAbove` references, then the exact event build. Returns the
    /// subtree's cost as build() does.
    double buildBinned(std::vector<Ref>& refs, const Bounds3f& cell, int depth, int badRefines, KdTree& out) {
        const uint32_t count = uint32_t(refs.size());
        SplitCandidate best;
        if (count > config_.binnedAbove && depth < depthLimit_) best = findBinnedSplit(refs, cell);
        if (best.axis < 0 || best.cost >= config_.intersectionCost * blocks(count)) {
            // Small enough, at the depth limit, or no binned plane pays: the exact sweep decides
            // (including whether this becomes a leaf, with the bad-refinement rules).
            EventList events;
            eventsOf(refs, events);
            std::vector<Ref>().swap(refs);
            return build(events, count, cell, depth, badRefines, out);
        }
        out.stats.maxDepth = std::max(out.stats.maxDepth, depth);
        out.stats.refsBinned += count;
        Bounds3f leftCell = cell, rightCell = cell;
        leftCell.upper[best.axis] = best.pos;
        rightCell.lower[best.axis] = best.pos;
        std::vector<Ref> left, right;
        left.reserve(count / 2 + count / 8), right.reserve(count / 2 + count / 8);
        const int a = best.axis;
        // In primitive order, so both lists stay sorted by primitive. A box ending at the plane
        // (planar ones in it included) goes left, one starting there right: the sweep's rules.
        for (const Ref& r : refs) {
            if (r.box.upper[a] <= best.pos) left.push_back(r);
            else if (r.box.lower[a] >= best.pos) right.push_back(r);
            else {
                // Straddling: perfect split, clipped to each child (within its current box).
                Bounds3f bl = clipped(r.prim, leftCell).intersection(r.box), br = clipped(r.prim, rightCell).intersection(r.box);
                if (!bl.empty()) left.push_back({bl, r.prim});
                if (!br.empty()) right.push_back({br, r.prim});
            }
        }
        std::vector<Ref>().swap(refs);
        uint32_t nodeIndex = uint32_t(out.nodes.size());
        out.nodes.emplace_back();
        ++out.stats.innerNodes;
        auto [costL, costR] = buildChildren(
            out, nodeIndex, best, left.size() + right.size(),
            [&](KdTree& o) { return buildBinned(left, leftCell, depth + 1, badRefines, o); },
            [&](KdTree& o) { return buildBinned(right, rightCell, depth + 1, badRefines, o); });
        return config_.traversalCost + (leftCell.surfaceArea() * costL + rightCell.surfaceArea() * costR) / cell.surfaceArea();
    }

private:
    /// Binned SAH (min–max binning): per axis, count the references whose box starts in each bin
    /// and those whose box ends in each bin; at the boundary after bin k, N_L = starts in bins ≤ k
    /// and N_R = ends in bins > k. Bin indices round like the plane positions only approximately,
    /// so the counts are estimates; the partition itself compares exactly. Same cost model as the
    /// sweep (empty-space bonus included).
    SplitCandidate findBinnedSplit(const std::vector<Ref>& refs, const Bounds3f& cell) {
        SplitCandidate best;
        const int nb = std::clamp(config_.binCount, 2, 256);
        const Vec3f d = cell.diagonal();
        const float area = cell.surfaceArea();
        if (!(area > 0.f)) return best;
        const float invArea = 1.f / area;
        const uint32_t count = uint32_t(refs.size());
        std::vector<uint32_t>& binStart = scratch_.local().binStart;
        std::vector<uint32_t>& binEnd = scratch_.local().binEnd;
        binStart.assign(size_t(3 * nb), 0u);
        binEnd.assign(size_t(3 * nb), 0u);
        Vec3f scale;
        for (int a = 0; a < 3; ++a) scale[a] = d[a] > 0.f ? float(nb) / d[a] : 0.f;
        auto binOf = [&](float x, int a) { return std::clamp(int((x - cell.lower[a]) * scale[a]), 0, nb - 1); };
        for (const Ref& r : refs)
            for (int a = 0; a < 3; ++a) {
                ++binStart[size_t(a * nb + binOf(r.box.lower[a], a))];
                ++binEnd[size_t(a * nb + binOf(r.box.upper[a], a))];
            }
        for (int a = 0; a < 3; ++a) {
            if (!(d[a] > 0.f)) continue;
            const AxisSah sah(cell, d, invArea, a, config_.emptyCutMinFraction);
            uint32_t nl = 0, nr = count;
            for (int k = 0; k + 1 < nb; ++k) {
                nl += binStart[size_t(a * nb + k)];
                nr -= binEnd[size_t(a * nb + k)];
                const float p = sah.lo + d[a] * float(k + 1) / float(nb);
                if (!(p > sah.lo && p < sah.hi)) continue;
                float cost = sah.cost(p, nl, nr, blocks(nl), blocks(nr), config_);
                if (cost < best.cost) best = {cost, a, p, true};
            }
        }
        return best;
    }

    /// The sorted events of `refs` (sorted by primitive, so the stable radix sort on the upper key
    /// bits sorts by the whole key), generated into the thread's scratch and sorted into the list.
    void eventsOf(const std::vector<Ref>& refs, EventList& events) {
        std::vector<Event>& list = scratch_.local().unsorted;
        list.clear();
        for (int a = 0; a < 3; ++a)
            for (const Ref& r : refs) appendAxisEvents(r.box, a, r.prim, list);
        events.allocate(list.size());
        radixSortEventsInto(list.data(), events.data.get(), list.size());
    }

    /// B(n) = max(1, n / sahBlockSize) for n > 0: a leaf test costs one SIMD block at least, and
    /// grows linearly beyond. (⌈n / sahBlockSize⌉ jumps at multiples of the block size, and then a
    /// split that duplicates almost every reference, 9 → 8 + 8, looks cheaper than a leaf.)
    float blocks(uint32_t n) const { return n == 0 ? 0.f : std::max(1.f, float(n) * invBlockSize_); }

    /// One sweep over the sorted events of all three axes (W&H Algorithm 4, "FindPlane"): at each
    /// plane, N_L counts primitives entirely or partly before it, N_P those lying in it, N_R those
    /// after it; each candidate is evaluated with the planar primitives on either side.
    SplitCandidate findSplit(const EventList& events, uint32_t count, const Bounds3f& cell, size_t segment[4]) const {
        SplitCandidate best;
        const Vec3f d = cell.diagonal();
        const float area = cell.surfaceArea();
        segment[0] = 0;
        segment[1] = segment[2] = segment[3] = events.size;
        if (!(area > 0.f)) return best;  // a cell flat on two axes: no area to split
        const float invArea = 1.f / area;
        int axis = -1;
        uint32_t nl = 0, nr = 0;
        AxisSah sah;
        const size_t n = events.size;
        size_t i = 0;
        while (i < n) {
            Event e = events[i];
            int a = eventAxis(e);
            if (a != axis) {
                for (int s = axis + 1; s <= a; ++s) segment[s] = i;
                axis = a;
                nl = 0, nr = count;
                sah = AxisSah(cell, d, invArea, a, config_.emptyCutMinFraction);
            }
            uint64_t plane = eventPlane(e);
            // Counts in registers: an array indexed by the type made every event a load-add-store
            // whose store the next event's load waited for (a sixth of the build's time).
            uint32_t ends = 0, planars = 0, starts = 0;
            for (; i < n && eventPlane(events[i]) == plane; ++i) {
                const uint32_t type = eventType(events[i]);
                ends += type == kEnd, planars += type == kPlanar, starts += type == kStart;
            }
            const uint32_t typeCount[3] = {ends, planars, starts};
            uint32_t np = typeCount[kPlanar];
            nr -= typeCount[kPlanar] + typeCount[kEnd];
            float p = eventPos(e);
            if (p > sah.lo && p < sah.hi) {
                float costLeft = sah.cost(p, nl + np, nr, blocks(nl + np), blocks(nr), config_);
                float costRight = sah.cost(p, nl, nr + np, blocks(nl), blocks(nr + np), config_);
                // Planar primitives go to the cheaper side (W&H Section 3.3).
                if (costLeft < best.cost) best = {costLeft, a, p, true};
                if (costRight < best.cost) best = {costRight, a, p, false};
            }
            nl += typeCount[kStart] + typeCount[kPlanar];
        }
        for (int s = axis + 1; s <= 3; ++s) segment[s] = n;
        return best;
    }

    /// Classifies the primitives (W&H Algorithm 5), splits the sorted event list stably into the
    /// children's lists and merges in the freshly sorted events of the straddling primitives,
    /// clipped to each child cell (W&H Section 4.3). Consumes `events`.
    void split(EventList& events, const size_t segment[4], const SplitCandidate& s, const Bounds3f& leftCell,
               const Bounds3f& rightCell, EventList& left, EventList& right, uint32_t& leftCount,
               uint32_t& rightCount) {
        Scratch& sc = scratch_.local();
        const size_t begin = segment[s.axis], end = segment[s.axis + 1];
        // One pass over the split axis's events, in position order (W&H Algorithm 5 folded): a start
        // before the plane marks its primitive as straddling until its end event, if also at or
        // before the plane, marks it left; a start at or after the plane marks it right; planar
        // events go by position, those in the plane by the SAH's choice. Ends after the plane leave
        // the mark alone (their primitive straddles or was marked right by its start).
        const uint32_t splitKey = sortableBits(s.pos);
        uint8_t* side = sc.side.data();
        const uint8_t planarInPlane = s.planarLeft ? kLeftOnly : kRightOnly;
        for (size_t i = begin; i < end; ++i) {
            Event e = events[i];
            uint32_t posKey = uint32_t(e >> 30), type = eventType(e), prim = eventPrim(e);
            uint8_t mark;
            if (posKey < splitKey) mark = type == kStart ? kBoth : kLeftOnly;
            else if (posKey == splitKey) mark = type == kEnd ? uint8_t(kLeftOnly) : type == kStart ? uint8_t(kRightOnly) : planarInPlane;
            else mark = type == kEnd ? side[prim] : uint8_t(kRightOnly);
            side[prim] = mark;
        }
        sc.straddlers.clear();
        leftCount = rightCount = 0;
        for (size_t i = begin; i < end; ++i) {
            Event e = events[i];
            if (eventType(e) == kEnd) continue;
            uint32_t prim = eventPrim(e);
            Side side = Side(sc.side[prim]);
            if (side == kLeftOnly) ++leftCount;
            else if (side == kRightOnly) ++rightCount;
            else sc.straddlers.push_back(prim);
        }
        // Stable partition without branches: every event is written to both lists, and only the
        // cursor of its side advances (straddlers advance neither: their events are regenerated).
        if (sc.keptLeft.size() < events.size) sc.keptLeft.resize(events.size), sc.keptRight.resize(events.size);
        size_t nLeft = 0, nRight = 0;
        Event* keptL = sc.keptLeft.data();
        Event* keptR = sc.keptRight.data();
        for (Event e : events) {
            uint8_t sd = side[eventPrim(e)];
            keptL[nLeft] = e;
            keptR[nRight] = e;
            nLeft += sd == kLeftOnly;
            nRight += sd == kRightOnly;
        }
        events.release();  // the parent's list is no longer needed

        sc.newLeft.clear(), sc.newRight.clear();
        for (uint32_t prim : sc.straddlers) {
            Bounds3f bl = clipped(prim, leftCell), br = clipped(prim, rightCell);
            if (!bl.empty()) appendEvents(bl, prim, sc.newLeft), ++leftCount;
            if (!br.empty()) appendEvents(br, prim, sc.newRight), ++rightCount;
        }
        std::sort(sc.newLeft.begin(), sc.newLeft.end());
        std::sort(sc.newRight.begin(), sc.newRight.end());
        left.allocate(nLeft + sc.newLeft.size());
        std::merge(keptL, keptL + nLeft, sc.newLeft.begin(), sc.newLeft.end(), left.data.get());
        right.allocate(nRight + sc.newRight.size());
        std::merge(keptR, keptR + nRight, sc.newRight.begin(), sc.newRight.end(), right.data.get());
    }

    /// The primitive clipped to the cell (perfect split), always within the cell.
    Bounds3f clipped(uint32_t prim, const Bounds3f& cell) const {
        Bounds3f b = (config_.perfectSplits && clip_) ? clip_(prim, cell) : bounds_[prim];
        return b.intersection(cell);
    }

    std::vector<uint32_t> primsOf(const EventList& events) const {
        std::vector<uint32_t> prims;
        for (Event e : events) {
            if (eventAxis(e) != 0) break;
            if (eventType(e) != kEnd) prims.push_back(eventPrim(e));
        }
        return prims;
    }

    double makeLeaf(EventList& events, KdTree& out) {
        std::vector<uint32_t> prims = primsOf(events);
        events.release();
        return emitLeaf(prims, out);
    }

    double emitLeaf(std::vector<uint32_t>& prims, KdTree& out) {
        // Primitive order inside a leaf: ascending ids, so leaf blocks do not depend on event order.
        std::sort(prims.begin(), prims.end());
        out.nodes.push_back(KdNode::leaf(uint32_t(out.primIndices.size()), uint32_t(prims.size())));
        out.primIndices.insert(out.primIndices.end(), prims.begin(), prims.end());
        ++out.stats.leaves;
        out.stats.references += prims.size();
        if (prims.empty()) ++out.stats.emptyLeaves;
        return config_.intersectionCost * blocks(uint32_t(prims.size()));
    }

    /// Appends a subtree built on its own (node 0 its root) to `out`, moving its child and
    /// reference indices by the nodes and references already in `out`.
    static void appendSubtree(KdTree& out, const KdTree& sub) {
        const uint32_t nodeBase = uint32_t(out.nodes.size()), primBase = uint32_t(out.primIndices.size());
        out.nodes.reserve(out.nodes.size() + sub.nodes.size());
        for (KdNode n : sub.nodes) {
            if (n.isLeaf()) n.word0 += primBase;
            else n.word1 += nodeBase << 2;
            out.nodes.push_back(n);
        }
        out.primIndices.insert(out.primIndices.end(), sub.primIndices.begin(), sub.primIndices.end());
        KdBuildStats& s = out.stats;
        const KdBuildStats& t = sub.stats;
        s.innerNodes += t.innerNodes, s.leaves += t.leaves, s.emptyLeaves += t.emptyLeaves, s.references += t.references;
        s.depthLimitHits += t.depthLimitHits, s.retractions += t.retractions;
        s.eventsSwept += t.eventsSwept, s.refsBinned += t.refsBinned;
        s.maxDepth = std::max(s.maxDepth, t.maxDepth);
    }

    /// Per-thread buffers of one node's step (split(), findBinnedSplit()): nothing in them lives
    /// across a recursive call, so a thread may switch to another subtree while it waits.
    struct Scratch {
        explicit Scratch(size_t primitives) : side(primitives, kBoth) {}
        std::vector<uint8_t> side;  ///< per primitive: its side of the plane being split
        std::vector<uint32_t> straddlers;
        std::vector<Event> keptLeft, keptRight, newLeft, newRight, unsorted;
        std::vector<uint32_t> binStart, binEnd;
    };

    std::span<const Bounds3f> bounds_;
    const KdClipFunction& clip_;
    KdConfig config_;
    int depthLimit_ = 0;
    bool parallel_ = false;
    float invBlockSize_ = 1.f;
    tbb::enumerable_thread_specific<Scratch> scratch_;
};

}  // namespace

KdTree buildKdTree(std::span<const Bounds3f> primBounds, const KdClipFunction& clip, const KdConfig& config) {
    KdTree tree;
    if (primBounds.size() > kPrimMask)
        throw InputError("k-d tree: " + std::to_string(primBounds.size()) + " primitives exceed the limit of " +
                         std::to_string(kPrimMask));
    for (const Bounds3f& b : primBounds) tree.bounds.extend(b);
    size_t n = primBounds.size();
    int limit = config.maxDepth > 0 ? config.maxDepth
                                    : int(std::lround(8.0 + 1.3 * std::log2(double(std::max<size_t>(n, 1)))));
    tree.stats.depthLimit = std::clamp(limit, 0, kKdMaxDepth);
    if (n == 0) return tree;

    // Subtrees are built as TBB tasks when the caller's arena has more than one thread (the tree is
    // the same either way, KdBuilder::buildChildren).
    const bool parallel = config.parallelAbove > 0 && tbb::this_task_arena::max_concurrency() > 1;
    KdBuilder builder(primBounds, clip, config, tree.stats.depthLimit, parallel);
    if (config.binnedAbove > 0 && n > config.binnedAbove) {
        std::vector<KdBuilder::Ref> refs(n);
        for (uint32_t i = 0; i < n; ++i) refs[i] = {primBounds[i], i};
        tree.stats.sahCost = builder.buildBinned(refs, tree.bounds, 0, 0, tree);
    } else {
        std::vector<Event> events;
        events.reserve(6 * n);
        // Per axis, in primitive order: the radix sort is stable, so equal keys stay by primitive.
        for (int a = 0; a < 3; ++a)
            for (uint32_t i = 0; i < n; ++i) appendAxisEvents(primBounds[i], a, i, events);
        EventList root;
        root.allocate(events.size());
        radixSortEventsInto(events.data(), root.data.get(), events.size());
        std::vector<Event>().swap(events);
        tree.stats.sahCost = builder.build(root, uint32_t(n), tree.bounds, 0, 0, tree);
    }
    tree.nodes.shrink_to_fit();
    tree.primIndices.shrink_to_fit();
    return tree;
}

}  // namespace tessera
