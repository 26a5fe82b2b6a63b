#pragma once
/// \file interrupt.h
/// Ctrl-C / SIGTERM handling for long renders: the first signal asks the scheduler to stop at the
/// next tile boundary (the render then writes what it has); a second one exits at once with 130.
/// Outputs are written atomically, so even that leaves no half-written file.
#include <atomic>
#include <string>

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

/// Names a temporary file that a second signal's immediate exit should delete (unlink() is
/// async-signal-safe), for its lifetime. One at a time; longer paths are not registered.
class TemporaryFileForSignal {
public:
    explicit TemporaryFileForSignal(const std::string& path);
    ~TemporaryFileForSignal();
    TemporaryFileForSignal(const TemporaryFileForSignal&) = delete;
    TemporaryFileForSignal& operator=(const TemporaryFileForSignal&) = delete;

private:
    bool registered_ = false;
};

}  // namespace tessera
