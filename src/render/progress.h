#pragma once
/// \file progress.h
/// Progress on stderr: a bar redrawn at most ~8 times a second on a terminal, plain log lines
/// (every 10% or 30 s) when stderr is a file or pipe, nothing at all when quiet. Thread-safe.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace tessera {

class ProgressReporter {
public:
    /// `total` units of work (samples), or 0 with `timeLimitSeconds` > 0 for a time-bounded render.
    ProgressReporter(std::string label, uint64_t total, double timeLimitSeconds, bool quiet);
    /// Called by workers after each tile.
    void advance(uint64_t units);
    /// Final line (always printed unless quiet).
    void done(const std::string& summary);
    double elapsedSeconds() const;

private:
    void print(bool final);

    std::string label_;
    uint64_t total_;
    double timeLimit_;
    bool quiet_, tty_;
    std::atomic<uint64_t> doneUnits_{0};
    std::chrono::steady_clock::time_point start_, lastPrint_;
    int lastDecile_ = -1;
    std::mutex mutex_;
};

/// Formats seconds as "1h02m03s" / "2m05s" / "4.2s".
std::string formatDuration(double seconds);

}  // namespace tessera
