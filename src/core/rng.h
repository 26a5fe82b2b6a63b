#pragma once
/// \file rng.h
/// PCG32 random numbers (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient Statistically
/// Good Algorithms for Random Number Generation") and the hashing that seeds the samplers
/// (core/sampler.h).
#include <cstdint>

#include "core/math.h"

namespace tessera {

/// 64-bit finaliser of MurmurHash3 (Appleby); mixes all input bits into all output bits.
inline uint64_t mixBits(uint64_t v) {
    v ^= v >> 33;
    v *= 0xff51afd7ed558ccdULL;
    v ^= v >> 33;
    v *= 0xc4ceb9fe1a85ec53ULL;
    v ^= v >> 33;
    return v;
}

inline uint64_t hashCombine(uint64_t a, uint64_t b) { return mixBits(a ^ (mixBits(b) + 0x9e3779b97f4a7c15ULL + (a << 6) + (a >> 2))); }

class Pcg32 {
public:
    Pcg32() { seed(0, 0); }
    Pcg32(uint64_t seqIndex, uint64_t offset) { seed(seqIndex, offset); }

    /// Selects stream `seqIndex` and advances to `offset` within it (PCG's reference seeding).
    void seed(uint64_t seqIndex, uint64_t offset) {
        state_ = 0u;
        inc_ = (seqIndex << 1u) | 1u;
        nextU32();
        state_ += offset;
        nextU32();
    }

    uint32_t nextU32() {
        uint64_t old = state_;
        state_ = old * 0x5851f42d4c957f2dULL + inc_;
        uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }

    /// Uniform float in [0, 1): 24 random mantissa bits, never rounds up to 1.
    float nextFloat() { return float(nextU32() >> 8) * 0x1p-24f; }
    Vec2f next2D() {
        float a = nextFloat();
        return {a, nextFloat()};
    }

private:
    uint64_t state_ = 0, inc_ = 1;
};

}  // namespace tessera
