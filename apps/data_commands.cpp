// `generate` and `dataset-info` (docs/dataset.md).
#include <unistd.h>

#include <iostream>

#include "commands.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "team.hpp"

namespace lanechange::app {

namespace {

struct GenerateArgs {
  long long count = 0;
  std::uint64_t seed = 0;
  std::string behavior;
  std::string target_lane_cars;
  std::string out_dir;
  int jobs = 0;
  std::string solver = "fast";
  int steps = 0;
  long long shard_size = 200;
  double time_limit = 60.0;
  bool gap_labels = false;
};

data::GenerateOptions to_options(const GenerateArgs& a, const ConfigSource& global_config) {
  data::GenerateOptions o;
  o.count = a.count;
  o.seed = a.seed;
  o.behavior = behavior_option(a.behavior);
  o.out_dir = a.out_dir;
  o.solver = a.solver;
  o.shard_size = a.shard_size;
  o.time_limit_s = a.time_limit;
  o.gap_labels = a.gap_labels;
  o.config = global_config();
  if (a.steps > 0) o.config.expert.steps = a.steps;
  return o;
}

void report_done(const data::GenerateReport& r, const run::Team& team, const std::string& dir) {
  if (team.rank() != 0) return;
  if (r.already_complete) {
    std::cerr << dir << " is already complete; nothing to do\n";
    return;
  }
  std::cerr << "wrote " << r.shards_written << " of " << r.shards_total << " shards ("
            << r.scenarios_planned << " scenarios";
  if (team.size() > 1) std::cerr << " on rank 0 of " << team.size();
  std::cerr << ", " << r.shards_skipped << " finished before) to " << dir << " in " << r.wall_s
            << " s\n";
}

void run_generate(const GenerateArgs& args, const ConfigSource& config) {
  const data::GenerateOptions options = to_options(args, config);
  const auto team = make_team();
  data::RunOptions run;
  run.jobs = args.jobs;
  run.team = team.get();
  if (team->rank() == 0) {
    run.progress = &std::cerr;
    run.progress_on_terminal = ::isatty(STDERR_FILENO) != 0;
  }
  run_on_team(*team, [&] { report_done(data::generate(options, run), *team, options.out_dir); });
}

}  // namespace

void add_generate(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "generate", "Plan N sampled scenarios with the expert and write a data set (resumable)");
  auto a = make_args<GenerateArgs>();
  cmd->add_option("--count", a->count, "How many scenarios")->required();
  cmd->add_option("--seed", a->seed, "Sampler seed")->required();
  cmd->add_option("--out", a->out_dir, "Data set directory (created; resumed if it exists)")
      ->required();
  add_behavior_option(*cmd, a->behavior);
  add_traffic_option(*cmd, a->target_lane_cars);
  cmd->add_option("--jobs", a->jobs, "Worker threads per process (default: all cores)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--solver", a->solver, "MIQP back-end: fast (ours) or reference (Bonmin)");
  cmd->add_option("--steps", a->steps, "Override N, the plan's steps (cheaper data)")
      ->check(CLI::Range(2, 10000));
  cmd->add_option("--shard-size", a->shard_size, "Scenarios per shard file");
  cmd->add_option("--time-limit", a->time_limit, "Seconds per plan");
  cmd->add_flag("--gap-labels", a->gap_labels,
                "Also label each gap around the ego, planned alone (a plan per gap)");
  cmd->callback([a, config] {
    run_generate(*a, [&] { return with_target_lane_cars(config(), a->target_lane_cars); });
  });
}

void add_dataset_info(CLI::App& app) {
  auto* cmd = app.add_subcommand("dataset-info", "Counts and solve times of a data set");
  auto dir = make_args<std::string>();
  cmd->add_option("--data", *dir, "Data set directory")->required();
  cmd->callback([dir] { data::print_summary(data::summarize_dataset(*dir), std::cout); });
}

}  // namespace lanechange::app
