#pragma once
/// \file interrupt.h
/// Ctrl-C / SIGTERM handling for long renders: the first signal asks the scheduler to stop at the
/// next tile boundary (the render then writes what it has); a second one exits at once with 130.
/// Outputs are written atomically, so even that leaves no half-written file.
#include <atomic>

namespace tessera {

/// Installs the handlers for its lifetime and restores the previous ones afterwards.
class InterruptGuard {
public:
    InterruptGuard();
    ~InterruptGuard();
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;
};

/// The flag the first signal sets (lock-free, safe to set from a signal handler).
std::atomic<bool>& interruptFlag();

}  // namespace tessera
