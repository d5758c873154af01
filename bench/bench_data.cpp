// Data generation throughput: the whole `generate` pipeline (sample, plan,
// label, write shards, final manifest) on 1 and 2 worker threads, in
// scenarios per second of wall time, and the scaling efficiency of 2 workers
// (rate with 2 / (2 x rate with 1)). Environment: LANECHANGE_BENCH_DATA_COUNT
// scenarios per run (default 60), LANECHANGE_BENCH_DATA_STEPS (default 50).
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "lanechange/data/dataset.hpp"
#include "run_then_summarize.hpp"

namespace lc = lanechange;

namespace {

constexpr std::uint64_t kSeed = 2026;
double g_rate_one_worker = 0.0;

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atoi(v) : fallback;
}

lc::data::GenerateOptions options(const std::filesystem::path& dir) {
  lc::data::GenerateOptions o;
  o.count = env_int("LANECHANGE_BENCH_DATA_COUNT", 60);
  o.seed = kSeed;
  o.out_dir = dir.string();
  o.shard_size = 10;
  o.config = lc::make_preset("paper");
  o.config.expert.steps = env_int("LANECHANGE_BENCH_DATA_STEPS", 50);
  return o;
}

void BM_Generate(benchmark::State& state) {
  const int jobs = static_cast<int>(state.range(0));
  const auto dir = std::filesystem::temp_directory_path() /
                   ("lanechange_bench_data_" + std::to_string(::getpid()));
  const lc::data::GenerateOptions o = options(dir);
  lc::data::RunOptions run;
  run.jobs = jobs;
  double seconds = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    std::filesystem::remove_all(dir);
    state.ResumeTiming();
    const auto report = lc::data::generate(o, run);
    seconds += report.wall_s;
  }
  std::filesystem::remove_all(dir);
  const double rate = static_cast<double>(o.count * state.iterations()) / seconds;
  state.counters["scenarios_per_s"] = rate;
  state.counters["workers"] = jobs;
  if (jobs == 1) g_rate_one_worker = rate;
  if (jobs > 1 && g_rate_one_worker > 0.0) {
    state.counters["scaling_efficiency"] = rate / (jobs * g_rate_one_worker);
  }
}

BENCHMARK(BM_Generate)->Arg(1)->Arg(2)->Iterations(3)->UseRealTime()->Unit(benchmark::kMillisecond);

void print_context() {
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  struct rusage usage {};
  ::getrusage(RUSAGE_SELF, &usage);
  const auto o = options("");
  std::printf(
      "== data benchmark ==\nseed %llu, %lld scenarios per run (N = %d, shard size %lld), "
      "host %s, cores %u, peak RSS %ld KiB\n",
      static_cast<unsigned long long>(kSeed), o.count, o.config.expert.steps, o.shard_size, host,
      std::thread::hardware_concurrency(), usage.ru_maxrss);
}

}  // namespace

int main(int argc, char** argv) { return run_then_summarize(argc, argv, print_context); }
