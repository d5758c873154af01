// Cutting scenes out of a CommonRoad recording: reading the XML, then
// import_scenes with every recorded car as the ego (--ego recorded --right),
// on the largest NGSIM US-101 recording beside the repository (40 cars), or
// the file LANECHANGE_BENCH_COMMONROAD names. Reports the median and the
// slowest of the repetitions (Google Benchmark's aggregates).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "lanechange/commonroad/import.hpp"

namespace lc = lanechange;

namespace {

std::string recording_path() {
  if (const char* path = std::getenv("LANECHANGE_BENCH_COMMONROAD")) return path;
  return std::string(LANECHANGE_SOURCE_DIR) +
         "/../shared/commonroad/recorded/USA_US101-2_1_T-1.xml";
}

lc::commonroad::ImportSettings every_car_both_sides() {
  lc::commonroad::ImportSettings s;
  s.egos = lc::commonroad::EgoChoice::RecordedCars;
  s.right = true;
  return s;
}

void BM_ReadRecording(benchmark::State& state) {
  const std::string path = recording_path();
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("no recording at " + path).c_str());
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(lc::commonroad::read_recording(path));
}

void BM_ReadAndImport(benchmark::State& state) {
  const std::string path = recording_path();
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("no recording at " + path).c_str());
    return;
  }
  const lc::Config config;
  std::size_t scenes = 0;
  for (auto _ : state) {
    const auto report = lc::commonroad::import_scenes(lc::commonroad::read_recording(path), config,
                                                      every_car_both_sides());
    scenes = report.scenes.size();
    benchmark::DoNotOptimize(report);
  }
  state.counters["scenes"] = static_cast<double>(scenes);
}

double slowest(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

}  // namespace

BENCHMARK(BM_ReadRecording)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(10)
    ->ComputeStatistics("max", slowest)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_ReadAndImport)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(10)
    ->ComputeStatistics("max", slowest)
    ->ReportAggregatesOnly(true);
BENCHMARK_MAIN();
