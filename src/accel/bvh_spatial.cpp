#include "accel/bvh_spatial.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "accel/bvh_binning.h"

namespace tessera {
namespace {

/// Bins per axis, for object and spatial splits alike.
constexpr int kBins = kMaxBins;

/// A reference: one primitive, or the part of it inside a box after spatial splits.
struct SRef {
    Bounds3f box;
    uint32_t prim;
    Vec3f centroid() const { return box.center(); }
};

Bounds3f unite(Bounds3f a, const Bounds3f& b) {
    a.extend(b);
    return a;
}

struct Choice {
    enum Kind { kNone, kObject, kSpatial } kind = kNone;
    int axis = -1, bin = 0;
    float cost = kInfinity;  ///< Σ halfArea · blocks over both children
    Bounds3f left, right;    ///< children's boxes as the sweep saw them
    uint32_t leftCount = 0, rightCount = 0;
};

/// Bounds of triangle v[0..2] between the planes x[axis] = lo and x[axis] = hi: the vertices inside
/// and the edges' crossings of both planes. Only prices candidate planes (the split clips exactly).
Bounds3f triangleSlabBounds(const Vec3f* v, int axis, float lo, float hi) {
    Bounds3f r;
    for (int i = 0; i < 3; ++i) {
        const Vec3f& p = v[i];
        const Vec3f& q = v[(i + 1) % 3];
        if (p[axis] >= lo && p[axis] <= hi) r.extend(p);
        for (float plane : {lo, hi}) {
            float dp = p[axis] - plane, dq = q[axis] - plane;
            if ((dp < 0.f && dq > 0.f) || (dp > 0.f && dq < 0.f)) {
                Vec3f x = p + (q - p) * (dp / (dp - dq));
                x[axis] = plane;
                r.extend(x);
            }
        }
    }
    return r;
}

class SpatialBuilder {
public:
    SpatialBuilder(std::span<const Bounds3f> b, std::span<const Vec3f> tris, const ClipToBox& clip, const BvhConfig& cfg,
                   BinaryBvh& out)
        : primBounds_(b), triangles_(tris), clip_(clip), config_(cfg), out_(out) {
        config_.maxLeafSize = std::clamp(config_.maxLeafSize, 1, 15);  // 4 bits in BVH8 leaf refs
        config_.sahBlockSize = std::max(config_.sahBlockSize, 1);
    }

    void run() {
        size_t n = primBounds_.size();
        if (n == 0) return;
        std::vector<SRef> refs(n);
        Bounds3f bounds;
        for (size_t i = 0; i < n; ++i) refs[i] = {primBounds_[i], uint32_t(i)}, bounds.extend(primBounds_[i]);
        budget_ = size_t(double(n) * std::max(0.f, config_.spatialSplitBudget));
        rootHalfArea_ = bounds.halfArea();
        // Every split adds two nodes and at most one reference: 2 · (n + budget) − 1 slots suffice.
        out_.nodes.allocate(2 * (n + budget_) - 1);
        out_.primIndices.reserve(n + budget_);
        build(refs, bounds, 0);
        out_.maxDepth = maxDepth_;
    }

private:
    std::span<const Bounds3f> primBounds_;
    std::span<const Vec3f> triangles_;
    const ClipToBox& clip_;
    BvhConfig config_;
    BinaryBvh& out_;
    size_t budget_ = 0;  ///< extra references still allowed
    float rootHalfArea_ = 0.f;
    uint32_t nextSlot_ = 0, maxDepth_ = 0;

    float blocks(uint32_t n) const { return sahBlocks(n, config_.sahBlockSize); }

    uint32_t makeLeaf(const std::vector<SRef>& refs, const Bounds3f& bounds, uint32_t depth) {
        uint32_t slot = nextSlot_++;
        BvhBuildNode& node = out_.nodes[slot];
        node.bounds = bounds;
        node.count = uint32_t(refs.size());
        node.left = uint32_t(out_.primIndices.size());
        for (const SRef& r : refs) out_.primIndices.push_back(r.prim);
        maxDepth_ = std::max(maxDepth_, depth);
        return slot;
    }

    /// Prices the plane before every bin of one axis from both ends (the references counted left
    /// where they enter, right where they exit: the same bin for object splits) and keeps the
    /// cheapest in `best`.
    void sweep(const Bounds3f* box, const uint32_t* enter, const uint32_t* exit, Choice::Kind kind, int axis,
               Choice& best) const {
        Bounds3f rightBox[kBins];
        uint32_t rightCount[kBins];
        Bounds3f acc;
        uint32_t cnt = 0;
        for (int i = kBins - 1; i > 0; --i) acc.extend(box[i]), cnt += exit[i], rightBox[i] = acc, rightCount[i] = cnt;
        acc = Bounds3f();
        cnt = 0;
        for (int i = 1; i < kBins; ++i) {
            acc.extend(box[i - 1]);
            cnt += enter[i - 1];
            if (cnt == 0 || rightCount[i] == 0) continue;
            float cost = acc.halfArea() * blocks(cnt) + rightBox[i].halfArea() * blocks(rightCount[i]);
            if (cost < best.cost) best = {kind, axis, i, cost, acc, rightBox[i], cnt, rightCount[i]};
        }
    }

    /// The binned object split on reference centroids (bvh_binning.h, as in the object-split build).
    Choice objectSplit(const std::vector<SRef>& refs, const BinMapping& map) const {
        Binning bins(kBins);
        for (const SRef& r : refs) {
            Box box = toBox(r.box);
            Vi4 b = map.bins(toVf4(r.centroid()));
            for (int a = 0; a < 3; ++a) bins.add(a, b[a], box.lo, box.hi);
        }
        ObjectSplit s = findObjectSplit(bins, kBins, config_.sahBlockSize);
        if (s.axis < 0) return {};
        return {Choice::kObject, s.axis, s.bin, s.cost, s.left.bounds(), s.right.bounds(), s.leftCount, s.rightCount};
    }

    float planePosition(const Bounds3f& bounds, int axis, int i) const {
        return bounds.lower[axis] + (bounds.upper[axis] - bounds.lower[axis]) * (float(i) / float(kBins));
    }
    int spatialBin(const Bounds3f& bounds, int axis, float x) const {
        float extent = bounds.upper[axis] - bounds.lower[axis];
        return std::clamp(int((x - bounds.lower[axis]) * (float(kBins) / extent)), 0, kBins - 1);
    }
    /// The slab of the node between planes i and j (whole node beyond the outermost planes).
    Bounds3f slab(const Bounds3f& bounds, int axis, int i, int j) const {
        Bounds3f s = bounds;
        if (i > 0) s.lower[axis] = planePosition(bounds, axis, i);
        if (j < kBins) s.upper[axis] = planePosition(bounds, axis, j);
        return s;
    }
    Bounds3f clipRef(const SRef& r, const Bounds3f& box) const {
        return clip_(r.prim, box.intersection(r.box)).intersection(r.box);
    }

    /// Chopped binning of the references into uniform slabs of the node (paper, Section 4.2): each
    /// reference adds its part to every slab it overlaps, enters in the first, exits in the last; a
    /// sweep prices every plane.
    Choice spatialSplit(const std::vector<SRef>& refs, const Bounds3f& bounds) const {
        Choice best;
        for (int a = 0; a < 3; ++a) {
            if (!(bounds.upper[a] > bounds.lower[a])) continue;
            Bounds3f box[kBins];
            uint32_t enter[kBins] = {}, exit[kBins] = {};
            for (const SRef& r : refs) {
                int b0 = spatialBin(bounds, a, r.box.lower[a]), b1 = spatialBin(bounds, a, r.box.upper[a]);
                if (b0 == b1) box[b0].extend(r.box);
                else
                    // The triangle cut by each slab (a cheap estimate; exact clipping of every slab
                    // of every straddling reference made the build ten times slower), within the
                    // reference's box. Non-triangles: the box cut by the slab.
                    for (int b = b0; b <= b1; ++b) {
                        Bounds3f s = slab(bounds, a, b, b + 1);
                        const Vec3f* v = &triangles_[3 * size_t(r.prim)];
                        if (!std::isnan(v[0].x)) s = triangleSlabBounds(v, a, s.lower[a], s.upper[a]);
                        box[b].extend(r.box.intersection(s));
                    }
                ++enter[b0];
                ++exit[b1];
            }
            sweep(box, enter, exit, Choice::kSpatial, a, best);
        }
        return best;
    }

    /// Performs a spatial split; straddling references are split in two or, where that is cheaper,
    /// moved whole to one side ("reference unsplitting", paper Section 4.3). False when one side
    /// would be empty (the caller falls back to an object split).
    bool partitionSpatial(const std::vector<SRef>& refs, const Bounds3f& bounds, const Choice& c,
                          std::vector<SRef>& left, std::vector<SRef>& right) {
        int a = c.axis;
        Bounds3f leftSlab = slab(bounds, a, 0, c.bin), rightSlab = slab(bounds, a, c.bin, kBins);
        Bounds3f leftBox = c.left, rightBox = c.right;
        float nl = float(c.leftCount), nr = float(c.rightCount);
        for (const SRef& r : refs) {
            int b0 = spatialBin(bounds, a, r.box.lower[a]), b1 = spatialBin(bounds, a, r.box.upper[a]);
            if (b1 < c.bin) left.push_back(r);
            else if (b0 >= c.bin) right.push_back(r);
            else {
                Bounds3f l = clipRef(r, leftSlab), rt = clipRef(r, rightSlab);
                if (l.empty() || rt.empty()) {  // rounding left nothing on one side: keep it whole
                    (l.empty() ? right : left).push_back(r);
                    (l.empty() ? rightBox : leftBox).extend(r.box);
                    (l.empty() ? nl : nr) -= 1.f;
                    continue;
                }
                float costSplit = budget_ > 0 ? leftBox.halfArea() * nl + rightBox.halfArea() * nr : kInfinity;
                float costLeft = unite(leftBox, r.box).halfArea() * nl + rightBox.halfArea() * (nr - 1.f);
                float costRight = leftBox.halfArea() * (nl - 1.f) + unite(rightBox, r.box).halfArea() * nr;
                if (costSplit <= costLeft && costSplit <= costRight) {
                    left.push_back({l, r.prim});
                    right.push_back({rt, r.prim});
                    --budget_;
                } else if (costLeft <= costRight) {
                    left.push_back(r), leftBox.extend(r.box), nr -= 1.f;
                } else {
                    right.push_back(r), rightBox.extend(r.box), nl -= 1.f;
                }
            }
        }
        return !left.empty() && !right.empty();
    }

    uint32_t build(std::vector<SRef>& refs, const Bounds3f& bounds, uint32_t depth) {
        uint32_t n = uint32_t(refs.size());
        // A leaf that no split can beat (a split costs at least traversalCost): neither split is
        // priced. Such nodes are the most numerous, and their references span most spatial bins.
        if (n <= uint32_t(config_.maxLeafSize) && config_.intersectionCost * blocks(n) <= config_.traversalCost)
            return makeLeaf(refs, bounds, depth);
        Bounds3f centroidBox;
        for (const SRef& r : refs) centroidBox.extend(r.centroid());

        Choice choice;
        const BinMapping map(toBox(centroidBox), kBins);
        if (int(depth) < config_.maxSahDepth) {
            choice = objectSplit(refs, map);
            // Spatial splits only where the object split's children overlap (paper, Section 4.5).
            if (budget_ > 0 && rootHalfArea_ > 0.f && choice.kind != Choice::kNone) {
                float overlap = choice.left.intersection(choice.right).halfArea();
                if (overlap > config_.spatialSplitAlpha * rootHalfArea_) {
                    Choice spatial = spatialSplit(refs, bounds);
                    if (spatial.cost < choice.cost) choice = spatial;
                }
            } else if (budget_ > 0 && choice.kind == Choice::kNone) {
                choice = spatialSplit(refs, bounds);  // identical centroids: only a spatial split can help
            }
            float area = bounds.halfArea();
            float leafCost = config_.intersectionCost * blocks(n);
            float splitCost = area > 0.f && choice.kind != Choice::kNone
                                  ? config_.traversalCost + config_.intersectionCost * choice.cost / area
                                  : kInfinity;
            if (n <= uint32_t(config_.maxLeafSize) && leafCost <= splitCost) return makeLeaf(refs, bounds, depth);
        } else if (n <= uint32_t(config_.maxLeafSize)) {
            return makeLeaf(refs, bounds, depth);
        }

        std::vector<SRef> left, right;
        bool done = false;
        if (choice.kind == Choice::kSpatial) done = partitionSpatial(refs, bounds, choice, left, right);
        if (!done && choice.kind == Choice::kObject) {
            left.clear(), right.clear();
            for (const SRef& r : refs)
                (map.bin(toVf4(r.centroid()), choice.axis) < choice.bin ? left : right).push_back(r);
            done = !left.empty() && !right.empty();
        }
        if (!done) {
            // No usable split (identical centroids, or too deep): object median along the widest
            // centroid axis, ties broken by primitive index so the order is fully determined.
            left.clear(), right.clear();
            Vec3f e = centroidBox.upper - centroidBox.lower;
            int a = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
            std::sort(refs.begin(), refs.end(), [&](const SRef& p, const SRef& q) {
                float cp = p.centroid()[a], cq = q.centroid()[a];
                return cp < cq || (cp == cq && p.prim < q.prim);
            });
            left.assign(refs.begin(), refs.begin() + n / 2);
            right.assign(refs.begin() + n / 2, refs.end());
        }
        std::vector<SRef>().swap(refs);  // the parent's list is no longer needed: keep peak memory down

        Bounds3f leftBounds, rightBounds;
        for (const SRef& r : left) leftBounds.extend(r.box);
        for (const SRef& r : right) rightBounds.extend(r.box);
        uint32_t slot = nextSlot_++;
        uint32_t l = build(left, leftBounds, depth + 1);
        uint32_t r = build(right, rightBounds, depth + 1);
        BvhBuildNode& node = out_.nodes[slot];
        node.bounds = bounds;
        node.count = 0;
        node.left = l;
        node.right = r;
        return slot;
    }
};

}  // namespace

BinaryBvh buildSpatialSplitBvh(std::span<const Bounds3f> primBounds, std::span<const Vec3f> triangles,
                               const ClipToBox& clip, const BvhConfig& config) {
    BinaryBvh out;
    SpatialBuilder(primBounds, triangles, clip, config, out).run();
    return out;
}

}  // namespace tessera
