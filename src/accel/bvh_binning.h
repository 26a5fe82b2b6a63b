#pragma once
/// \file bvh_binning.h
/// Binned SAH object splits (Wald 2007, "On fast Construction of SAH-based Bounding Volume
/// Hierarchies"): primitives binned by centroid along each axis, then one sweep per axis prices the
/// plane before every bin. The one binning of both BVH builders: the object-split build
/// (bvh_builder.cpp) and the object splits of the spatial-split build (bvh_spatial.cpp).
#include <algorithm>
#include <cstdint>
#include <cstring>

#include "accel/accel_simd.h"
#include "core/bounds.h"

namespace tessera {

using simd::Vf4;
using simd::Vi4;

/// The most bins per axis a node uses.
inline constexpr int kMaxBins = 32;

/// Leaf blocks of n primitives, ⌈n / blockSize⌉, as Embree counts them: a leaf tests `blockSize`
/// primitives at once, so 1 and 4 primitives cost the same.
inline float sahBlocks(uint32_t n, int blockSize) { return float((n + uint32_t(blockSize) - 1) / uint32_t(blockSize)); }

TESSERA_INLINE Vf4 vmin(Vf4 a, Vf4 b) { return a < b ? a : b; }
TESSERA_INLINE Vf4 vmax(Vf4 a, Vf4 b) { return a > b ? a : b; }

/// An axis-aligned box in SIMD form (lanes x, y, z; lane 3 ignored).
struct Box {
    Vf4 lo = simd::splat4(kInfinity), hi = simd::splat4(-kInfinity);
    TESSERA_INLINE void extend(Vf4 l, Vf4 h) { lo = vmin(lo, l), hi = vmax(hi, h); }
    TESSERA_INLINE void extend(const Box& b) { extend(b.lo, b.hi); }
    bool empty() const { return lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]; }
    /// Half the surface area: SAH only compares ratios, and empty boxes count as 0.
    float halfArea() const {
        if (empty()) return 0.f;
        Vf4 d = hi - lo;
        return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
    }
    Bounds3f bounds() const {
        Bounds3f b;
        b.lower = Vec3f(lo[0], lo[1], lo[2]);
        b.upper = Vec3f(hi[0], hi[1], hi[2]);
        return b;
    }
};

/// The x, y, z lanes of v, lane 3 zeroed (the builders keep a primitive index in lane 3 of a box
/// corner; arithmetic on those bits, denormal floats, may be slow).
TESSERA_INLINE Vf4 xyz(Vf4 v) {
    const Vi4 keep = {-1, -1, -1, 0};
    return reinterpret_cast<Vf4>(reinterpret_cast<Vi4>(v) & keep);
}

/// Per-axis bins of one node: box and count of the primitives whose centroid falls in each bin.
struct Binning {
    // Plain SIMD arrays (trivially constructible), initialised for the bins in use only: small
    // nodes are the majority and clearing 3 × kMaxBins boxes each time dominated the build.
    Vf4 lo[3][kMaxBins], hi[3][kMaxBins];
    /// counts[bin][axis] (lane 3 unused): the sweep reads one bin's three counts as one vector.
    alignas(16) uint32_t counts[kMaxBins][4];

    explicit Binning(int binCount = kMaxBins) {
        for (int i = 0; i < binCount; ++i) {
            for (int a = 0; a < 3; ++a) lo[a][i] = simd::splat4(kInfinity), hi[a][i] = simd::splat4(-kInfinity);
            for (int a = 0; a < 4; ++a) counts[i][a] = 0;
        }
    }
    TESSERA_INLINE void add(int axis, int bin, Vf4 l, Vf4 h) {
        lo[axis][bin] = vmin(lo[axis][bin], l);
        hi[axis][bin] = vmax(hi[axis][bin], h);
        ++counts[bin][axis];
    }
    TESSERA_INLINE Vi4 binCounts(int bin) const {
        Vi4 c;
        std::memcpy(&c, counts[bin], sizeof c);
        return c;
    }
    void merge(const Binning& o, int binCount) {
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < binCount; ++i) {
                lo[a][i] = vmin(lo[a][i], o.lo[a][i]);
                hi[a][i] = vmax(hi[a][i], o.hi[a][i]);
                counts[i][a] += o.counts[i][a];
            }
    }
};

/// Maps a centroid to its bin on each axis: k · (c − min) / extent, clamped (Wald 2007, eq. 1). The
/// same function bins and partitions, so a chosen split can never leave a side empty.
struct BinMapping {
    Vf4 lower, scale;
    int binCount;
    BinMapping(const Box& centroidBox, int bins) : lower(centroidBox.lo), binCount(bins) {
        Vf4 extent = centroidBox.hi - centroidBox.lo;
        for (int a = 0; a < 4; ++a) scale[a] = (a < 3 && extent[a] > 0.f) ? float(bins) * (1.f - 1e-6f) / extent[a] : 0.f;
    }
    TESSERA_INLINE Vi4 bins(Vf4 c) const {
        Vi4 i = __builtin_convertvector((c - lower) * scale, Vi4);
        Vi4 zero{}, top = Vi4{} + (binCount - 1);
        i = i < zero ? zero : i;
        return i > top ? top : i;
    }
    TESSERA_INLINE int bin(Vf4 c, int axis) const {
        return std::clamp(int((c[axis] - lower[axis]) * scale[axis]), 0, binCount - 1);
    }
    /// bin(c, axis) < b for a centroid inside the mapped box (c ≥ lower) and 1 ≤ b < binCount,
    /// without the conversion: (c − lower)·scale ≥ 0 truncates below b exactly when it is below b.
    TESSERA_INLINE bool below(Vf4 c, int axis, float b) const { return (c[axis] - lower[axis]) * scale[axis] < b; }
};

/// The cheapest object split of a node: planes before bin `bin` of axis `axis` (−1: none).
struct ObjectSplit {
    int axis = -1, bin = 0;
    float cost = kInfinity;  ///< Σ halfArea · blocks over both children
    Box left, right;         ///< the children's boxes (unions of their bins)
    uint32_t leftCount = 0, rightCount = 0;
};

/// Half the surface areas of three boxes at once (lanes 0–2; lane 3 junk): the 3 × 3 extents
/// transposed, so that one multiply-add chain serves all three axes' candidate boxes.
TESSERA_INLINE Vf4 halfAreas3(const Box& a, const Box& b, const Box& c) {
    Vf4 da = a.hi - a.lo, db = b.hi - b.lo, dc = c.hi - c.lo;
    Vf4 t0 = __builtin_shufflevector(da, db, 0, 4, 1, 5);  // ax bx ay by
    Vf4 t1 = __builtin_shufflevector(da, db, 2, 6, 2, 6);  // az bz az bz
    Vf4 x = __builtin_shufflevector(t0, dc, 0, 1, 4, 4);
    Vf4 y = __builtin_shufflevector(t0, dc, 2, 3, 5, 5);
    Vf4 z = __builtin_shufflevector(t1, dc, 0, 1, 6, 6);
    return x * y + y * z + z * x;
}

/// Leaf blocks ⌈n / blockSize⌉ of three counts at once (lanes 0–2), as floats. `blockShift` is
/// log2(blockSize) when blockSize is a power of two, else −1.
TESSERA_INLINE Vf4 sahBlocks3(Vi4 n, int blockSize, int blockShift) {
    if (blockShift >= 0) return __builtin_convertvector((n + (blockSize - 1)) >> blockShift, Vf4);
    Vf4 r;
    for (int a = 0; a < 4; ++a) r[a] = sahBlocks(uint32_t(n[a]), blockSize);
    return r;
}

/// Sweeps the bins of all three axes at once from both ends (the layout of Embree's binning: lanes
/// are axes) and returns the cheapest plane (in units of half-area × blocks; the node's constant
/// terms are added by the caller) with both child boxes. `k` bins in use, `blockSize` primitives
/// per leaf block (sahBlocks). An empty side has no area (an inverted box, area +inf) and no blocks:
/// 0 · inf is NaN, which never compares below the best cost, so such planes are never chosen. Ties
/// go to the lowest axis, then the lowest bin.
inline ObjectSplit findObjectSplit(const Binning& bins, int k, int blockSize) {
    int blockShift = (blockSize & (blockSize - 1)) == 0 ? __builtin_ctz(uint32_t(blockSize)) : -1;
    Vf4 rightArea[kMaxBins];
    Vi4 rightCount[kMaxBins];
    Box bx, by, bz;
    Vi4 count{};
    for (int i = k - 1; i > 0; --i) {
        count += bins.binCounts(i);
        bx.extend(bins.lo[0][i], bins.hi[0][i]);
        by.extend(bins.lo[1][i], bins.hi[1][i]);
        bz.extend(bins.lo[2][i], bins.hi[2][i]);
        rightArea[i] = halfAreas3(bx, by, bz);
        rightCount[i] = count;
    }
    bx = by = bz = Box();
    count = Vi4{};
    Vf4 bestCost = simd::splat4(kInfinity);
    Vi4 bestBin{};
    for (int i = 1; i < k; ++i) {
        count += bins.binCounts(i - 1);
        bx.extend(bins.lo[0][i - 1], bins.hi[0][i - 1]);
        by.extend(bins.lo[1][i - 1], bins.hi[1][i - 1]);
        bz.extend(bins.lo[2][i - 1], bins.hi[2][i - 1]);
        Vf4 cost = halfAreas3(bx, by, bz) * sahBlocks3(count, blockSize, blockShift) +
                   rightArea[i] * sahBlocks3(rightCount[i], blockSize, blockShift);
        Vi4 better = cost < bestCost;  // strict: the lowest bin wins ties
        bestCost = better ? cost : bestCost;
        bestBin = better ? Vi4{} + i : bestBin;
    }
    ObjectSplit best;
    for (int a = 0; a < 3; ++a)
        if (bestCost[a] < best.cost) best.axis = a, best.bin = bestBin[a], best.cost = bestCost[a];
    if (best.axis < 0) return best;
    for (int i = 0; i < k; ++i) {
        uint32_t c = bins.counts[i][best.axis];
        if (i < best.bin) best.left.extend(bins.lo[best.axis][i], bins.hi[best.axis][i]), best.leftCount += c;
        else best.right.extend(bins.lo[best.axis][i], bins.hi[best.axis][i]), best.rightCount += c;
    }
    return best;
}

/// A point in SIMD form (lane 3 zero).
inline Vf4 toVf4(const Vec3f& v) { return Vf4{v.x, v.y, v.z, 0.f}; }

/// A box in SIMD form from a Bounds3f (lane 3 zero).
inline Box toBox(const Bounds3f& b) {
    Box r;
    r.lo = Vf4{b.lower.x, b.lower.y, b.lower.z, 0.f};
    r.hi = Vf4{b.upper.x, b.upper.y, b.upper.z, 0.f};
    return r;
}

}  // namespace tessera
