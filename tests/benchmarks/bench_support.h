#pragma once
// Google Benchmark main with ratios: after the run, every benchmark's median real time is
// printed as a ratio to the baseline benchmark of the same family (the one whose name
// contains "baseline"), so noisy shared machines still give comparable figures.
// Use: SOLO_BENCHMARK_MAIN() instead of BENCHMARK_MAIN(), run with
// --benchmark_repetitions=5 (the default here) to get medians.

#include <benchmark/benchmark.h>

namespace solo::bench {
int runWithRatios(int argc, char** argv);
}

#define SOLO_BENCHMARK_MAIN() \
  int main(int argc, char** argv) { return ::solo::bench::runWithRatios(argc, argv); }
