#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <exception>
#include <mutex>
#include <thread>

#include "data/manifest.hpp"
#include "data/shard.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "lanechange/run/progress.hpp"

namespace lanechange::data {

using nlohmann::json;

namespace {

using Clock = std::chrono::steady_clock;

void require(bool ok, const std::string& field, const std::string& problem) {
  if (!ok) throw InputError(field, problem);
}

void validate_options(const GenerateOptions& o) {
  require(o.count >= 1 && o.count <= 1'000'000'000LL, "--count", "must be in [1, 1e9]");
  require(o.shard_size >= 1 && o.shard_size <= 10'000'000LL, "--shard-size", "must be in [1, 1e7]");
  require(std::isfinite(o.time_limit_s) && o.time_limit_s > 0.0, "--time-limit",
          "must be a positive number of seconds");
  require(!o.out_dir.empty(), "--out", "must name a directory");
  require(o.solver == "fast" || o.solver == "reference", "--solver",
          "unknown solver \"" + o.solver + "\" (expected fast or reference)");
  o.config.validate();
}

// Rank 0 alone touches the directory; the others learn the outcome, so that
// every rank stops (or goes on) together. Codes: the DirectoryState, or -2
// for bad input and -1 for any other error.
DirectoryState agree_on_directory(const std::string& dir, const json& parameters, run::Team& team) {
  return static_cast<DirectoryState>(run::decide_on_rank_zero(team, "--out", [&] {
    const DirectoryState state = prepare_directory(dir, parameters);
    if (state == DirectoryState::Resumable) remove_stale_temporaries(dir);
    return static_cast<int>(state);
  }));
}

std::vector<ShardRange> unfinished_shards(const GenerateOptions& o, const run::Team& team,
                                          GenerateReport& report) {
  std::vector<ShardRange> todo;
  for (long long s = team.rank(); s < report.shards_total; s += team.size()) {
    const ShardRange range = shard_range(s, o.count, o.shard_size);
    if (shard_finished(range, o.out_dir)) {
      ++report.shards_skipped;
    } else {
      todo.push_back(range);
    }
  }
  return todo;
}

// Workers pull shard indices from one counter, so a slow shard does not hold
// up the others. The first error stops the pool and is rethrown.
void run_workers(const ShardMaker& maker, const std::vector<ShardRange>& todo,
                 const std::string& dir, int jobs, run::Progress& progress) {
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  auto work = [&] {
    while (!stop) {
      const std::size_t i = next++;
      if (i >= todo.size()) return;
      try {
        make_shard(maker, todo[i], dir, [&] { progress.add(1); });
      } catch (...) {
        const std::lock_guard lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        stop = true;
      }
    }
  };
  {
    std::vector<std::jthread> workers;
    const auto n = std::min<std::size_t>(static_cast<std::size_t>(jobs), todo.size());
    for (std::size_t j = 0; j < n; ++j) workers.emplace_back(work);
  }
  if (first_error) std::rethrow_exception(first_error);
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

json run_block(const run::Team& team, int jobs, double wall_s) {
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  return {{"host", host},
          {"ranks", team.size()},
          {"jobs_per_rank", jobs},
          {"finished_utc", utc_now()},
          {"wall_s_last_run", wall_s}};
}

long long scenarios_in(const std::vector<ShardRange>& shards) {
  long long n = 0;
  for (const ShardRange& r : shards) n += r.count;
  return n;
}

}  // namespace

json dataset_parameters(const GenerateOptions& o) {
  const json config = o.config;
  return {{"version", LANECHANGE_VERSION},
          {"count", o.count},
          {"seed", o.seed},
          {"behavior", o.behavior ? std::string(to_string(*o.behavior)) : std::string("all")},
          {"shard_size", o.shard_size},
          {"solver", o.solver},
          {"time_limit_s", o.time_limit_s},
          {"gap_labels", o.gap_labels},
          {"config", config}};
}

GenerateReport generate(const GenerateOptions& options, const RunOptions& run) {
  run::Team& team = run::team_or_alone(run.team);
  const auto start = Clock::now();
  validate_options(options);
  const json parameters = dataset_parameters(options);
  GenerateReport report;
  report.shards_total = shard_count(options.count, options.shard_size);
  if (agree_on_directory(options.out_dir, parameters, team) == DirectoryState::Complete) {
    report.already_complete = true;
    return report;
  }
  const std::vector<ShardRange> todo = unfinished_shards(options, team, report);
  const int jobs =
      run.jobs > 0 ? run.jobs : static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  const auto solver = run.solver_override ? run.solver_override
                                          : expert::make_lane_change_solver(
                                                options.solver, options.config.expert.big_m);
  const ScenarioSampler sampler(options.config, options.seed);
  const expert::ExpertPlanner planner(options.config, solver);
  const ShardMaker maker{
      sampler, planner, options.behavior, options.seed, options.time_limit_s, options.gap_labels};
  run::Progress progress(run.progress, run.progress_on_terminal, scenarios_in(todo));
  run_workers(maker, todo, options.out_dir, jobs, progress);
  progress.finish();
  report.shards_written = static_cast<long long>(todo.size());
  report.scenarios_planned = scenarios_in(todo);
  // The manifest is written once every rank has finished its shards.
  team.barrier();
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  if (team.rank() == 0) {
    write_final_manifest(options.out_dir, parameters, run_block(team, jobs, wall_s));
  }
  report.wall_s = wall_s;
  return report;
}

}  // namespace lanechange::data
