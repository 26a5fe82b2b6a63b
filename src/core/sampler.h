#pragma once
/// \file sampler.h
/// The random numbers of one camera sample. A draw is a pure function of (pixel, sample index,
/// seed, dimension), never of the thread or tile that renders it, so images are bit-identical for
/// any thread count, across checkpoint/resume and across sample-range splits.
///
/// Two kinds (`--sampler`):
///  * `sobol` (default): Owen-scrambled, shuffled Sobol' points, padded per dimension (Burley 2020,
///    "Practical Hash-based Owen Scrambling", JCGT 9(4), §3-4). Every 2D draw is the first two Sobol'
///    dimensions, a (0,2)-sequence, so each pair (pixel jitter, light position, BSDF direction, ...)
///    is stratified on its own; each draw's sample index is shuffled by a nested uniform scramble and
///    its coordinates Owen-scrambled, with seeds hashed from (pixel, seed, dimension), so different
///    dimensions and pixels are decorrelated. The camera block (pixel jitter, lens) is one 4D Sobol'
///    point (dimensions 1-4 of Joe & Kuo 2008). Dimensions are allocated by purpose: the caller opens
///    a block per path vertex (startBounce, startLightPath, startConnection) and draws in a fixed
///    order inside it. Paths deeper than kSobolDepth, and blocks with more draws than kBlockSlots,
///    use a hashed fallback (independent numbers per dimension), still a pure function of the key.
///  * `independent`: one PCG32 stream per (pixel, sample index, seed); the start* calls are no-ops.
#include <algorithm>
#include <cstdint>

#include "core/math.h"
#include "core/rng.h"
#include "core/sampler_kind.h"
#include "core/sobol_matrices.h"

namespace tessera {

/// Bit reversal: byte swap, then the bits within each byte (three masked swaps).
inline uint32_t reverseBits32(uint32_t v) {
    v = __builtin_bswap32(v);
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    return ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
}

/// Laine & Karras's (2011) permutation, each output bit depending only on the input bits at or below
/// it, with their constants as Burley 2020 (§3) uses it. Its seed is added, so the leading bits see
/// one fixed permutation and a shift; Vegdahl's 2021 variant (a seed multiply, new constants) is
/// closer to a true Owen scramble, and would change every sobol image.
inline uint32_t laineKarrasPermutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

/// Owen scrambling of a 32-bit fraction (Burley 2020, §3, "nested uniform scramble"): bit k from the
/// top is flipped by a hash of the bits above it. Applied to a sample index it shuffles the order
/// while mapping every aligned block of 2^m indices onto an aligned block of 2^m indices, so each
/// prefix of a power-of-two count keeps the net property (§4).
inline uint32_t owenScramble(uint32_t v, uint32_t seed) { return reverseBits32(laineKarrasPermutation(reverseBits32(v), seed)); }

/// Unscrambled Sobol' point `index`, dimension `dim` (< kSobolDimensions), as a 32-bit fraction.
inline uint32_t sobolBits(uint32_t index, int dim) {
    if (dim == 0) return reverseBits32(index);
    uint32_t v = 0;
    for (const uint32_t* col = kSobolMatrices[dim]; index; index >>= 1, ++col)
        if (index & 1u) v ^= *col;
    return v;
}

/// The Sobol' matrices with bit-reversed columns, as 4 byte-indexed tables per dimension, indexed
/// by the bit-reversed sample index: sobolReversedBitsOfReversed(reverseBits32(i), d) =
/// reverseBits32(sobolBits(i, d)) in 4 look-ups instead of a loop over the index's bits (a shuffled
/// index has all 32 bits set at random). The shuffle (owenScramble) ends in a bit reversal, so a
/// draw takes its reversed index straight from the permutation and spares that reversal.
struct SobolReversedTables {
    uint32_t byteTable[kSobolDimensions][4][256];
};
constexpr SobolReversedTables makeSobolReversedTables() {
    SobolReversedTables t{};
    for (int d = 0; d < kSobolDimensions; ++d)
        for (int b = 0; b < 4; ++b)
            for (uint32_t v = 0; v < 256; ++v) {
                uint32_t x = 0;
                for (int j = 0; j < 8; ++j)
                    if (v & (1u << j)) {
                        // Bit 8b + j of the reversed index is bit 31 − 8b − j of the index: the
                        // reversed column of that bit.
                        uint32_t c = kSobolMatrices[d][31 - (8 * b + j)], r = 0;
                        for (int k = 0; k < 32; ++k) r |= ((c >> k) & 1u) << (31 - k);
                        x ^= r;
                    }
                t.byteTable[d][b][v] = x;
            }
    return t;
}
inline constexpr SobolReversedTables kSobolReversedTables = makeSobolReversedTables();

inline uint32_t sobolReversedBitsOfReversed(uint32_t r, int dim) {
    const auto& t = kSobolReversedTables.byteTable[dim];
    return t[0][r & 0xffu] ^ t[1][(r >> 8) & 0xffu] ^ t[2][(r >> 16) & 0xffu] ^ t[3][r >> 24];
}

/// [0, 1) float from the top 24 bits of a 32-bit fraction (never rounds up to 1).
inline float bitsToUnitFloat(uint32_t v) { return float(v >> 8) * 0x1p-24f; }

class Sampler {
public:
    /// Draw slots per block: a bounce uses light choice, light position, BSDF lobe, BSDF direction
    /// and Russian roulette (5); more draws in one block fall back to hashed numbers.
    static constexpr uint32_t kBlockSlots = 8;
    /// Vertices (bounces) deeper than this draw hashed numbers: long paths add little and gain
    /// nothing from stratification.
    static constexpr int kSobolDepth = 16;

    Sampler(Vec2i pixel, uint32_t sampleIndex, uint64_t seed, SamplerKind kind = kDefaultSampler) : index_(sampleIndex), kind_(kind) {
        uint64_t pixelKey = (uint64_t(uint32_t(pixel.y)) << 32) | uint32_t(pixel.x);
        pixelSeed_ = hashCombine(pixelKey, seed);
        if (kind == SamplerKind::Independent) rng_.seed(pixelSeed_, mixBits(sampleIndex));
        else reversedIndex_ = reverseBits32(sampleIndex);
    }

    SamplerKind kind() const { return kind_; }
    /// The sample index the sampler was made for (a photon-mapping pass's iteration).
    uint32_t sampleIndex() const { return index_; }

    /// The camera block, open at construction: slot 0 is the pixel jitter, slot 1 the lens.
    void startCamera() { open(kCameraBlock, true); }
    /// Skips to the lens slot of the camera block (for an integrator that traces its camera ray
    /// after other draws).
    void startLens() {
        open(kCameraBlock, true);
        slot_ = 1;
    }
    /// Vertex `depth` (0 = the first surface hit) of the camera sub-path.
    void startBounce(int depth) { open(kBounceBlock | clampId(depth), depth < kSobolDepth); }
    /// The emission of a light sub-path: light choice, position, direction.
    void startLightPath() { open(kLightBlock, true); }
    /// Vertex `depth` (0 = the first surface hit after the light) of the light sub-path.
    void startLightBounce(int depth) { open(kLightBlock | clampId(depth + 1), depth < kSobolDepth); }
    /// The draws of connection strategy (s, t): the resampled light point or lens point.
    void startConnection(int s, int t) { open(kConnectBlock | (clampId(s, 4095) << 12) | clampId(t, 4095), s + t < kSobolDepth); }

    // Both draws compute owenScramble(sobolBits(idx, d), seed) as
    // reverseBits32(laineKarrasPermutation(reverseBits32(sobolBits(idx, d)), seed)), with the shuffled
    // index idx = owenScramble(index, seed') = reverseBits32(laineKarrasPermutation(reversed index, seed')).
    float get1D() {
        if (kind_ == SamplerKind::Independent) return rng_.nextFloat();
        uint32_t slot = slot_++;
        if (!sobol_ || slot >= kBlockSlots) return fallback(slot).x;
        uint64_t h = dimensionHash(slot);
        uint32_t idx = reverseBits32(laineKarrasPermutation(reversedIndex_, uint32_t(h)));
        return bitsToUnitFloat(reverseBits32(laineKarrasPermutation(idx, uint32_t(h >> 32))));
    }

    /// Consumes the next 2D draw without computing it, leaving every later draw exactly as get2D
    /// would have: for a draw whose value is not needed (a pinhole camera's lens point).
    void skip2D() {
        if (kind_ == SamplerKind::Independent) rng_.next2D();
        else ++slot_;
    }
    /// The same for a 1D draw.
    void skip1D() {
        if (kind_ == SamplerKind::Independent) rng_.nextFloat();
        else ++slot_;
    }

    Vec2f get2D() {
        if (kind_ == SamplerKind::Independent) return rng_.next2D();
        uint32_t slot = slot_++;
        if (!sobol_ || slot >= kBlockSlots || (block_ == kCameraBlock && slot >= 2)) return fallback(slot);
        // The camera block shares one shuffled index: jitter and lens are dimensions (0,1), (2,3) of
        // one 4D point. Elsewhere each draw is padded: dimensions (0,1) with its own shuffle.
        bool camera = block_ == kCameraBlock;
        uint64_t h = dimensionHash(camera ? 0 : slot);
        uint32_t idxReversed = laineKarrasPermutation(reversedIndex_, uint32_t(h));
        int d0 = camera ? int(2 * slot) : 0;
        // Per-coordinate scramble seeds: the hash's high half and a multiplicative remix of it.
        uint64_t hs = (h >> 32) * 0x9e3779b97f4a7c15ULL + (camera ? slot : 0u) * 0xd1b54a32d192ed03ULL;
        uint32_t sx = uint32_t(hs >> 32), sy = uint32_t(mixBits(hs));
        return {bitsToUnitFloat(reverseBits32(laineKarrasPermutation(sobolReversedBitsOfReversed(idxReversed, d0), sx))),
                bitsToUnitFloat(reverseBits32(laineKarrasPermutation(sobolReversedBitsOfReversed(idxReversed, d0 + 1), sy)))};
    }

private:
    static constexpr uint32_t kCameraBlock = 0, kBounceBlock = 1u << 24, kLightBlock = 2u << 24, kConnectBlock = 3u << 24;
    /// Block ids: a bounce's depth has 24 bits, a connection's s and t 12 bits each.
    static uint32_t clampId(int v, int maxId = (1 << 24) - 1) { return uint32_t(std::clamp(v, 0, maxId)); }

    void open(uint32_t block, bool sobol) {
        block_ = block;
        slot_ = 0;
        sobol_ = sobol;
    }
    /// One mix of the pixel's seed and the dimension key (block, slot): keys are distinct per draw.
    uint64_t dimensionHash(uint32_t slot) const { return mixBits(pixelSeed_ ^ (((uint64_t(block_) << 8) | slot) * 0x9e3779b97f4a7c15ULL)); }
    /// Independent numbers keyed by (pixel, seed, sample index, block, slot).
    Vec2f fallback(uint32_t slot) const {
        uint64_t v = mixBits(hashCombine(dimensionHash(slot), index_) ^ 0x5851f42d4c957f2dULL);
        return {bitsToUnitFloat(uint32_t(v)), bitsToUnitFloat(uint32_t(v >> 32))};
    }

    uint64_t pixelSeed_ = 0;
    uint32_t index_ = 0, reversedIndex_ = 0;
    SamplerKind kind_;
    uint32_t block_ = kCameraBlock, slot_ = 0;
    bool sobol_ = true;
    Pcg32 rng_;
};

}  // namespace tessera
