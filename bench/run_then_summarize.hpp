#pragma once
// The main of a benchmark program that prints a summary of its own after
// Google Benchmark's table (medians and ratios measured in the same run).
#include <benchmark/benchmark.h>

inline int run_then_summarize(int argc, char** argv, void (*summarize)()) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  summarize();
  return 0;
}
