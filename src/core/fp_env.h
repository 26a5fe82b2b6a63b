#pragma once
/// \file fp_env.h
/// Floating-point environment of render threads.
namespace tessera {
/// Sets flush-to-zero and denormals-are-zero on the calling thread: denormal arithmetic costs ~100
/// cycles per operation on x86 and only ever appears in throughput products that are about to be
/// terminated by Russian roulette. Must be called in every worker thread (MXCSR is per thread).
void enableFlushToZero();

/// FTZ/DAZ for a scope, restoring the thread's previous mode at its end. Render code uses this, not
/// enableFlushToZero(), because the threads that render (the caller's included: TBB runs tasks in
/// the calling thread too) go on to do other work — with DAZ left on, reading a half-float EXR
/// afterwards turned its denormal values into zeros.
class ScopedFlushToZero {
public:
    ScopedFlushToZero();
    ~ScopedFlushToZero();
    ScopedFlushToZero(const ScopedFlushToZero&) = delete;
    ScopedFlushToZero& operator=(const ScopedFlushToZero&) = delete;

private:
    unsigned saved_ = 0;
};
}  // namespace tessera
