#pragma once
/// \file fp_env.h
/// Floating-point environment of render threads.
namespace tessera {
/// Sets flush-to-zero and denormals-are-zero on the calling thread: denormal arithmetic costs ~100
/// cycles per operation on x86 and only ever appears in throughput products that are about to be
/// terminated by Russian roulette. Must be called in every worker thread (MXCSR is per thread).
void enableFlushToZero();
}  // namespace tessera
