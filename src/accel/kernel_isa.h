#pragma once
/// \file kernel_isa.h
/// Which compiled traversal kernels a structure runs. The BVH and the k-d tree compile each kernel
/// twice from one template (accel_simd.h): once for the default target (SSE2 on x86, the portable
/// vector code elsewhere) and, on x86, once inside `target("avx2")` functions. The choice is made at
/// run time from the CPU, so the default build needs no -march=native; tests force the portable
/// kernels to compare the two bit for bit.
#include <string_view>

namespace tessera {

class KernelIsa {
public:
    KernelIsa() { useBest(); }
    /// True when the AVX2 kernels run (x86 CPUs that have AVX2 only).
    bool avx2() const { return avx2_; }
    /// "avx2" or "sse2/portable".
    std::string_view name() const { return avx2_ ? "avx2" : "sse2/portable"; }
    /// Runs the default-target kernels even where AVX2 is available.
    void forcePortable() { avx2_ = false; }
    /// The best kernels this CPU runs (the default).
    void useBest() {
#if defined(__x86_64__) || defined(__i386__)
        avx2_ = __builtin_cpu_supports("avx2");
#endif
    }

private:
    bool avx2_ = false;
};

}  // namespace tessera
