#pragma once
/// \file bench_clock.h
/// What the benchmark commands (bench-accel, bench-photons) time with and report: CPU clocks, so
/// that time spent descheduled on a shared machine does not count, and medians of repeats.
#include <time.h>

#include <algorithm>
#include <vector>

namespace tessera::app {

/// Seconds of CPU time of `clock` (CLOCK_THREAD_CPUTIME_ID, CLOCK_PROCESS_CPUTIME_ID).
inline double cpuSeconds(clockid_t clock) {
    timespec ts{};
    clock_gettime(clock, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// The median of `v` (0 for an empty list).
inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

}  // namespace tessera::app
