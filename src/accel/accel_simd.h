#pragma once
/// \file accel_simd.h
/// The few SIMD operations the BVH and k-d tree traversals (and the BVH builder's binning) need,
/// written with GCC/Clang vector extensions so the same code compiles to SSE2 in the default build
/// and to AVX2 inside functions marked `__attribute__((target("avx2")))` (each traversal is
/// instantiated once per instruction set and chosen at run time, kernel_isa.h, so the default build
/// never needs -march=native).
#include <array>
#include <cstdint>
#include <cstring>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define TESSERA_X86 1
#endif

// Passing 32-byte vectors by value in an SSE2 function changes the ABI; every helper below is
// always inlined, so no such call ever exists.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace tessera::simd {

typedef float Vf8 __attribute__((vector_size(32)));
typedef int32_t Vi8 __attribute__((vector_size(32)));
typedef float Vf4 __attribute__((vector_size(16)));
typedef int32_t Vi4 __attribute__((vector_size(16)));

#define TESSERA_INLINE inline __attribute__((always_inline))

TESSERA_INLINE Vf8 load8(const float* p) {
    Vf8 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
TESSERA_INLINE Vf4 load4(const float* p) {
    Vf4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
TESSERA_INLINE Vf8 splat8(float x) { return Vf8{} + x; }
TESSERA_INLINE Vf4 splat4(float x) { return Vf4{} + x; }

/// max/min that return `b` when `a` is NaN (the order of maxps/minps): a slab whose t is NaN
/// (ray origin exactly on a plane of a zero direction component) then leaves the interval alone.
TESSERA_INLINE Vf8 maxNanB(Vf8 a, Vf8 b) { return a > b ? a : b; }
TESSERA_INLINE Vf8 minNanB(Vf8 a, Vf8 b) { return a < b ? a : b; }

/// Bit i set when lane i of the mask is true (all bits set). Built from two 4-wide movemasks:
/// an AVX intrinsic here could not be inlined into the shared (default-target) traversal template,
/// and inside AVX2 code the halves cost one extract.
TESSERA_INLINE uint32_t moveMask8(Vi8 m) {
#if defined(TESSERA_X86)
    __m128 lo, hi;
    std::memcpy(&lo, &m, 16);
    std::memcpy(&hi, reinterpret_cast<const char*>(&m) + 16, 16);
    return uint32_t(_mm_movemask_ps(lo)) | (uint32_t(_mm_movemask_ps(hi)) << 4);
#else
    uint32_t bits = 0;
    for (int i = 0; i < 8; ++i) bits |= uint32_t(m[i] < 0) << i;
    return bits;
#endif
}

/// moveMask8 for code that knows its instruction set at compile time: inside the AVX2 traversal
/// one vmovmskps on the whole 8-lane register (its latency sits between every box test and the
/// next node's address), elsewhere the two halves. Inline assembly, because the intrinsic cannot
/// be inlined into the traversal template, whose default-target body is shared by both builds.
template <bool kAvx>
TESSERA_INLINE uint32_t moveMask8Isa(Vi8 m) {
#if defined(TESSERA_X86)
    if constexpr (kAvx) {
        uint32_t bits;
        asm("vmovmskps %1, %0" : "=r"(bits) : "x"(m));
        return bits;
    }
#endif
    return moveMask8(m);
}

TESSERA_INLINE uint32_t moveMask4(Vi4 m) {
#if defined(TESSERA_X86)
    return uint32_t(_mm_movemask_ps(reinterpret_cast<__m128>(m)));
#else
    uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits |= uint32_t(m[i] < 0) << i;
    return bits;
#endif
}

/// Lane i of the result takes lane idx[i] mod 8 of v (vpermps / vpermd inside AVX2 code; GCC
/// lowers it lane by lane elsewhere, with the same result).
template <class V>
TESSERA_INLINE V permute8(V v, Vi8 idx) {
#if defined(__clang__)
    V r;
    for (int i = 0; i < 8; ++i) r[i] = v[idx[i] & 7];
    return r;
#else
    return __builtin_shuffle(v, idx);
#endif
}

/// For each 8-bit lane mask, its set lanes packed from the low nibble up (4 bits each).
constexpr std::array<uint32_t, 256> kCompactLanes = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t m = 0; m < 256; ++m) {
        uint32_t packed = 0, n = 0;
        for (uint32_t i = 0; i < 8; ++i)
            if (m >> i & 1) packed |= i << (4 * n++);
        t[m] = packed;
    }
    return t;
}();

/// permute8 indices that move the set lanes of `mask` to the front, in lane order (stream
/// compaction of one node's hit children: one permute and one store push them all). Lanes past the
/// count hold junk; permute8 reads only the low three bits of each index.
TESSERA_INLINE Vi8 compactIndices(uint32_t mask) {
    const Vi8 nibbleShift = {0, 4, 8, 12, 16, 20, 24, 28};
    return (Vi8{} + int32_t(kCompactLanes[mask])) >> nibbleShift;
}

}  // namespace tessera::simd
