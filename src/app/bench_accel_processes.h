#pragma once
/// \file bench_accel_processes.h
/// `bench-accel --processes N`: the benchmark repeated in N fresh processes, each figure reported as
/// the median over the processes with its spread (bench_accel_processes.cpp).
#include <string>
#include <vector>

namespace tessera::app {

/// Runs this program N times with `childArgs` (a bench-accel command line that prints JSON) and
/// prints the median, range and spread of every figure; `agreeWithin`: the spread every ratio to
/// Embree should stay within (reported, not enforced).
int runBenchProcesses(const std::vector<std::string>& childArgs, int processes, double agreeWithin, bool json);

}  // namespace tessera::app
