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
#include <optional>
#include <string_view>

#include "core/math.h"
#include "core/rng.h"
#include "core/sobol_matrices.h"

namespace tessera {

enum class SamplerKind : uint8_t { Sobol, Independent };

inline constexpr SamplerKind kDefaultSampler = SamplerKind::Sobol;

inline std::string_view samplerName(SamplerKind k) { return k == SamplerKind::Sobol ? "sobol" : "independent"; }
inline std::optional<SamplerKind> parseSamplerKind(std::string_view name) {
    if (name == "sobol") return SamplerKind::Sobol;
    if (name == "independent") return SamplerKind::Independent;
    return std::nullopt;
}

inline uint32_t reverseBits32(uint32_t v) {
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
    return (v >> 16) | (v << 16);
}

/// Laine-Karras style hash in which each output bit depends only on the input bits at or below it
/// (Burley 2020, §3, the improved constants of his Listing 3).
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

/// [0, 1) float from the top 24 bits of a 32-bit fraction (never rounds up to 1).
inline float bitsToUnitFloat(uint32_t v) { return float(v >> 8) * 0x1p-24f; }

inline uint32_t hash32(uint64_t v) { return uint32_t(mixBits(v)); }

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
    }

    SamplerKind kind() const { return kind_; }

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

    float get1D() {
        if (kind_ == SamplerKind::Independent) return rng_.nextFloat();
        uint32_t slot = slot_++;
        if (!sobol_ || slot >= kBlockSlots) return fallback(slot).x;
        uint64_t h = dimensionHash(slot);
        uint32_t idx = owenScramble(index_, uint32_t(h));
        return bitsToUnitFloat(owenScramble(sobolBits(idx, 0), uint32_t(h >> 32)));
    }

    Vec2f get2D() {
        if (kind_ == SamplerKind::Independent) return rng_.next2D();
        uint32_t slot = slot_++;
        if (!sobol_ || slot >= kBlockSlots || (block_ == kCameraBlock && slot >= 2)) return fallback(slot);
        // The camera block shares one shuffled index: jitter and lens are dimensions (0,1), (2,3) of
        // one 4D point. Elsewhere each draw is padded: dimensions (0,1) with its own shuffle.
        bool camera = block_ == kCameraBlock;
        uint64_t h = dimensionHash(camera ? 0 : slot);
        uint32_t idx = owenScramble(index_, uint32_t(h));
        int d0 = camera ? int(2 * slot) : 0;
        uint32_t sx = uint32_t(h >> 32) + (camera ? slot * 0x9e3779b9u : 0u);
        return {bitsToUnitFloat(owenScramble(sobolBits(idx, d0), hash32(uint64_t(sx) << 1))),
                bitsToUnitFloat(owenScramble(sobolBits(idx, d0 + 1), hash32((uint64_t(sx) << 1) | 1u)))};
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
    uint64_t dimensionHash(uint32_t slot) const { return hashCombine(pixelSeed_, (uint64_t(block_) << 8) | slot); }
    /// Independent numbers keyed by (pixel, seed, sample index, block, slot).
    Vec2f fallback(uint32_t slot) const {
        uint64_t v = mixBits(hashCombine(dimensionHash(slot), index_) ^ 0x5851f42d4c957f2dULL);
        return {bitsToUnitFloat(uint32_t(v)), bitsToUnitFloat(uint32_t(v >> 32))};
    }

    uint64_t pixelSeed_ = 0;
    uint32_t index_ = 0;
    SamplerKind kind_;
    uint32_t block_ = kCameraBlock, slot_ = 0;
    bool sobol_ = true;
    Pcg32 rng_;
};

}  // namespace tessera
