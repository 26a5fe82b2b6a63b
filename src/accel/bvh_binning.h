#pragma once
/// \file bvh_binning.h
/// Binned SAH object splits (Wald 2007, "On fast Construction of SAH-based Bounding Volume
/// Hierarchies"): primitives binned by centroid along each axis, then one sweep per axis prices the
/// plane before every bin. The one binning of both BVH builders: the object-split build
/// (bvh_builder.cpp) and the object splits of the spatial-split build (bvh_spatial.cpp).
#include <algorithm>
#include <cstdint>

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

/// Per-axis bins of one node: box and count of the primitives whose centroid falls in each bin.
struct Binning {
    // Plain SIMD arrays (trivially constructible), initialised for the bins in use only: small
    // nodes are the majority and clearing 3 × kMaxBins boxes each time dominated the build.
    Vf4 lo[3][kMaxBins], hi[3][kMaxBins];
    uint32_t counts[3][kMaxBins];

    explicit Binning(int binCount = kMaxBins) {
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < binCount; ++i) lo[a][i] = simd::splat4(kInfinity), hi[a][i] = simd::splat4(-kInfinity), counts[a][i] = 0;
    }
    TESSERA_INLINE void add(int axis, int bin, Vf4 l, Vf4 h) {
        lo[axis][bin] = vmin(lo[axis][bin], l);
        hi[axis][bin] = vmax(hi[axis][bin], h);
        ++counts[axis][bin];
    }
    void merge(const Binning& o, int binCount) {
        for (int a = 0; a < 3; ++a)
            for (int i = 0; i < binCount; ++i) {
                lo[a][i] = vmin(lo[a][i], o.lo[a][i]);
                hi[a][i] = vmax(hi[a][i], o.hi[a][i]);
                counts[a][i] += o.counts[a][i];
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
};

/// The cheapest object split of a node: planes before bin `bin` of axis `axis` (−1: none).
struct ObjectSplit {
    int axis = -1, bin = 0;
    float cost = kInfinity;  ///< Σ halfArea · blocks over both children
    Box left, right;         ///< the children's boxes (unions of their bins)
    uint32_t leftCount = 0, rightCount = 0;
};

/// Sweeps the bins of each axis from both ends and returns the cheapest plane (in units of
/// half-area × blocks; the node's constant terms are added by the caller) with both child boxes.
/// `k` bins in use, `blockSize` primitives per leaf block (sahBlocks).
inline ObjectSplit findObjectSplit(const Binning& bins, int k, int blockSize) {
    ObjectSplit best;
    for (int a = 0; a < 3; ++a) {
        // Plain arrays, written only for the k bins in use: default-constructing 32 boxes per
        // axis per node cost more than the sweep itself on the many small nodes.
        float rightCost[kMaxBins];
        Vf4 rightLo[kMaxBins], rightHi[kMaxBins];
        Box acc;
        uint32_t count = 0;
        for (int i = k - 1; i > 0; --i) {
            acc.extend(bins.lo[a][i], bins.hi[a][i]);
            count += bins.counts[a][i];
            rightCost[i] = acc.halfArea() * sahBlocks(count, blockSize);
            rightLo[i] = acc.lo, rightHi[i] = acc.hi;
        }
        acc = Box();
        count = 0;
        uint32_t total = 0;
        for (int i = 0; i < k; ++i) total += bins.counts[a][i];
        for (int i = 1; i < k; ++i) {
            acc.extend(bins.lo[a][i - 1], bins.hi[a][i - 1]);
            count += bins.counts[a][i - 1];
            if (count == 0 || count == total) continue;
            float cost = acc.halfArea() * sahBlocks(count, blockSize) + rightCost[i];
            if (cost < best.cost) {  // strict: lowest axis, then bin, wins ties
                best.axis = a, best.bin = i, best.cost = cost;
                best.left = acc, best.right.lo = rightLo[i], best.right.hi = rightHi[i];
                best.leftCount = count, best.rightCount = total - count;
            }
        }
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
