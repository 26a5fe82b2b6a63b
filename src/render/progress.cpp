#include "render/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace tessera {

std::string formatDuration(double s) {
    char buf[64];
    if (!std::isfinite(s) || s < 0) return "?";
    if (s < 60) {
        std::snprintf(buf, sizeof buf, "%.1fs", s);
    } else if (s < 3600) {
        std::snprintf(buf, sizeof buf, "%dm%02ds", int(s) / 60, int(s) % 60);
    } else {
        std::snprintf(buf, sizeof buf, "%dh%02dm%02ds", int(s) / 3600, (int(s) / 60) % 60, int(s) % 60);
    }
    return buf;
}

ProgressReporter::ProgressReporter(std::string label, uint64_t total, double timeLimitSeconds, bool quiet)
    : label_(std::move(label)), total_(total), timeLimit_(timeLimitSeconds), quiet_(quiet),
      tty_(isatty(STDERR_FILENO) != 0), start_(std::chrono::steady_clock::now()), lastPrint_(start_) {}

double ProgressReporter::elapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressReporter::advance(uint64_t units) {
    doneUnits_.fetch_add(units, std::memory_order_relaxed);
    if (quiet_) return;
    // Only one thread prints; the others never wait for it.
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    print(false);
}

void ProgressReporter::print(bool final) {
    auto now = std::chrono::steady_clock::now();
    double elapsed = std::chrono::duration<double>(now - start_).count();
    double fraction = total_ > 0 ? double(doneUnits_.load()) / double(total_)
                                 : (timeLimit_ > 0 ? std::min(1.0, elapsed / timeLimit_) : 0.0);
    fraction = std::min(1.0, fraction);
    double sinceLast = std::chrono::duration<double>(now - lastPrint_).count();
    int decile = int(fraction * 10.0);
    if (!final) {
        if (tty_ && sinceLast < 0.125) return;
        if (!tty_ && decile == lastDecile_ && sinceLast < 30.0) return;
    }
    lastPrint_ = now;
    lastDecile_ = decile;
    double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : NAN;
    if (total_ == 0 && timeLimit_ > 0) eta = std::max(0.0, timeLimit_ - elapsed);
    if (tty_) {
        constexpr int kWidth = 30;
        int filled = int(fraction * kWidth);
        std::string bar(size_t(filled), '=');
        bar += std::string(size_t(kWidth - filled), ' ');
        std::fprintf(stderr, "\r%s [%s] %5.1f%%  %s elapsed, %s left ", label_.c_str(), bar.c_str(), 100.0 * fraction,
                     formatDuration(elapsed).c_str(), formatDuration(eta).c_str());
    } else {
        std::fprintf(stderr, "%s: %5.1f%% after %s (eta %s)\n", label_.c_str(), 100.0 * fraction,
                     formatDuration(elapsed).c_str(), formatDuration(eta).c_str());
    }
    std::fflush(stderr);
}

void ProgressReporter::done(const std::string& summary) {
    if (quiet_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (tty_) std::fprintf(stderr, "\r\033[K");
    std::fprintf(stderr, "%s: %s\n", label_.c_str(), summary.c_str());
    std::fflush(stderr);
}

}  // namespace tessera
