#include "lanechange/sim/evaluate.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "common/json_fields.hpp"
#include "data/rows.hpp"
#include "lanechange/error.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/run/progress.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/simulator.hpp"
#include "run/checksum.hpp"
#include "run/csv.hpp"
#include "sim/evaluation_files.hpp"

namespace lanechange::sim {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::string_view kEvaluationFormat = "lanechange.evaluation/5";
constexpr const char* kManifest = "evaluation.json";

// The scene files of a folder, in the order of their names, each loaded
// (and so checked) before anything is written.
struct SceneFiles {
  std::vector<std::string> names;
  std::vector<Scenario> scenes;
};

SceneFiles load_scene_files(const EvaluateOptions& o) {
  SceneFiles files;
  if (o.scenarios_dir.empty()) return files;
  if (!fs::is_directory(o.scenarios_dir)) {
    throw InputError("--scenarios", o.scenarios_dir + " is not a directory");
  }
  for (const auto& entry : fs::directory_iterator(o.scenarios_dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".json") {
      files.names.push_back(entry.path().filename().string());
    }
  }
  if (files.names.empty()) {
    throw InputError("--scenarios", o.scenarios_dir + " holds no scene file (*.json)");
  }
  std::sort(files.names.begin(), files.names.end());
  for (const std::string& name : files.names) {
    files.scenes.push_back(load_scenario((fs::path(o.scenarios_dir) / name).string(), o.config));
  }
  return files;
}

// A resume must roll out the very same files: their names and checksums are
// part of the parameters.
json scene_files_block(const EvaluateOptions& o, const SceneFiles& files) {
  json block = json::array();
  for (const std::string& name : files.names) {
    block.push_back(
        {{"file", name}, {"crc32", run::file_crc32((fs::path(o.scenarios_dir) / name).string())}});
  }
  return block;
}

json parameters_of(const EvaluateOptions& o, const SceneFiles& files) {
  if (!files.names.empty()) {
    return {{"scenarios", scene_files_block(o, files)},
            {"planners", o.planners},
            {"model", o.model_dir},
            {"shard_size", o.shard_size},
            {"duration", o.duration},
            {"config", o.config}};
  }
  return {{"count", o.count},
          {"seed", o.seed},
          {"behavior", o.behavior ? std::string(to_string(*o.behavior)) : "all"},
          {"planners", o.planners},
          {"model", o.model_dir},
          {"shard_size", o.shard_size},
          {"duration", o.duration},
          {"config", o.config}};
}

void validate(const EvaluateOptions& o) {
  auto require = [](bool ok, const char* field, const std::string& problem) {
    if (!ok) throw InputError(field, problem);
  };
  if (o.scenarios_dir.empty()) {
    require(o.count >= 1 && o.count <= 100'000'000LL, "--count", "must be in [1, 1e8]");
  } else {
    require(o.count == 0, "--count", "does not go with --scenarios (every file is rolled out)");
    require(!o.behavior, "--behavior", "does not go with --scenarios (each file has its own)");
  }
  require(o.shard_size >= 1, "--shard-size", "must be at least 1");
  require(!o.planners.empty(), "--planner", "names no planner");
  require(!o.out_dir.empty(), "--out", "must name a directory");
  require(std::isfinite(o.duration) && o.duration >= 0, "--duration", "must be >= 0");
  o.config.validate();
}

void write_scene_index(const std::string& out_dir, const SceneFiles& files) {
  std::string text = "index,file\n";
  for (std::size_t i = 0; i < files.names.size(); ++i) {
    text += std::to_string(i) + "," + run::csv_field(files.names[i]) + "\n";
  }
  lanechange::detail::write_file_atomically((fs::path(out_dir) / "scenes.csv").string(), text);
}

}  // namespace

std::vector<std::string> rollout_columns() {
  return {"index",
          "behavior",
          "planner",
          "outcome",
          "collision",
          "collision_at_fault",
          "unsafe_cut_in",
          "cars_collide",
          "takeovers",
          "fallbacks",
          "overruns",
          "failures",
          "clipped",
          "time_to_target_lane",
          "min_gap",
          "min_ttc",
          "max_abs_accel",
          "rms_jerk",
          "max_abs_omega",
          "median_step_ms",
          "p99_step_ms",
          "max_step_ms",
          "first_takeover_t",
          "forced_decel",
          "max_car_decel",
          "time_to_lane_line",
          "target_lane_slot",
          "gap_behind",
          "gap_ahead",
          "reason"};
}

namespace detail {

namespace {

// Rollout rows are read back for the summary: ten digits keep them exact
// enough that a resumed run summarises as an uninterrupted one.
constexpr int kRolloutDigits = 10;

// The id of the target-lane car behind or ahead of the ego at the end, or ""
// where it did not end in the target lane or that side was empty.
std::string gap_car(const Rollout& r, const char* side) {
  const auto gap = r.trajectory.details.find("gap");
  if (gap == r.trajectory.details.end() || !gap->contains(side) || !(*gap)[side].is_string()) {
    return "";
  }
  return (*gap)[side].get<std::string>();
}

}  // namespace

std::string rollout_row(long long index, std::string_view group, const std::string& planner,
                        const Rollout& r) {
  const RolloutMetrics& m = r.metrics;
  std::string row = std::to_string(index) + "," + std::string(group) + "," + planner + "," +
                    std::string(to_string(r.outcome)) + "," + (r.trajectory.collision ? "1" : "0") +
                    "," + (r.collision_at_fault ? "1" : "0") + "," + (m.unsafe_cut_in ? "1" : "0") +
                    "," + (m.cars_collide ? "1" : "0");
  for (int v : {m.takeovers, m.fallbacks, m.overruns, m.failures, m.clipped}) {
    row += ',';
    row += std::to_string(v);
  }
  for (double v :
       {m.time_to_target_lane >= 0 ? m.time_to_target_lane : NAN, m.min_gap, m.min_ttc,
        m.max_abs_accel, m.rms_jerk, m.max_abs_omega, m.median_step_ms, m.p99_step_ms,
        m.max_step_ms, m.first_takeover_t >= 0 ? m.first_takeover_t : NAN, m.forced_decel,
        m.max_car_decel, m.time_to_lane_line >= 0 ? m.time_to_lane_line : NAN}) {
    row += ',';
    row += run::csv_number(v, kRolloutDigits);
  }
  return row + "," + m.target_lane_slot + "," + gap_car(r, "behind") + "," + gap_car(r, "ahead") +
         "," + run::csv_field(r.reason) + "\n";
}

// Creates the directory and its manifest, or checks that the manifest there
// is of this very evaluation. Returns true when it is already complete.
bool prepare_directory(const std::string& out_dir, const json& parameters) {
  const fs::path dir(out_dir);
  const fs::path manifest = dir / kManifest;
  if (fs::exists(manifest)) {
    json old;
    try {
      old = json::parse(std::ifstream(manifest));
    } catch (const json::exception&) {
      throw InputError("--out", manifest.string() + " is not an evaluation manifest");
    }
    if (old.value("format", std::string()) != kEvaluationFormat ||
        old.value("parameters", json()) != parameters) {
      throw InputError("--out", out_dir +
                                    " holds an evaluation with other parameters; use another "
                                    "directory or the same command");
    }
    return old.value("status", std::string()) == "complete";
  }
  std::error_code error;
  fs::create_directories(dir, error);
  if (!fs::is_directory(dir)) throw InputError("--out", "cannot create " + out_dir);
  if (!fs::is_empty(dir)) {
    throw InputError("--out", out_dir + " is not empty and holds no evaluation");
  }
  lanechange::detail::write_file_atomically(
      manifest.string(),
      json{{"format", kEvaluationFormat}, {"status", "incomplete"}, {"parameters", parameters}}
              .dump(2) +
          "\n");
  return false;
}

void mark_complete(const std::string& out_dir, const json& parameters) {
  const json manifest = {
      {"format", kEvaluationFormat}, {"status", "complete"}, {"parameters", parameters}};
  lanechange::detail::write_file_atomically((fs::path(out_dir) / kManifest).string(),
                                            manifest.dump(2) + "\n");
}

}  // namespace detail

EvaluateReport evaluate(const EvaluateOptions& o, const EvaluateRun& run) {
  validate(o);
  // Built (and a model loaded) once, before the directory is touched, so an
  // unknown planner or a bad model leaves it as it was.
  std::vector<std::shared_ptr<const planner::ClosedLoopPlanner>> planners;
  for (const auto& name : o.planners) {
    planners.push_back(o.make_planner(name, o.config, o.model_dir));
  }
  const SceneFiles files = load_scene_files(o);
  const long long count =
      files.names.empty() ? o.count : static_cast<long long>(files.names.size());
  const auto start = std::chrono::steady_clock::now();
  const json parameters = parameters_of(o, files);
  EvaluateReport report;
  report.shards_total = (count + o.shard_size - 1) / o.shard_size;
  run::Team& team = run::team_or_alone(run.team);
  if (run::decide_on_rank_zero(team, "--out", [&] {
        return detail::prepare_directory(o.out_dir, parameters) ? 1 : 0;
      }) == 1) {
    report.shards_skipped = report.shards_total;
    return report;
  }
  std::vector<long long> todo;
  for (long long s = team.rank(); s < report.shards_total; s += team.size()) {
    if (fs::exists(fs::path(o.out_dir) / detail::shard_file(s))) {
      ++report.shards_skipped;
    } else {
      todo.push_back(s);
    }
  }
  const ScenarioSampler sampler(o.config, o.seed);
  const auto per_shard = static_cast<long long>(planners.size());
  long long total = 0;
  for (long long s : todo) total += std::min(o.shard_size, count - s * o.shard_size) * per_shard;
  run::Progress progress(run.progress, run.progress_on_terminal, total, -1.0, "evaluate",
                         "rollouts");
  std::atomic<std::size_t> next{0};
  std::atomic<long long> done{0};
  std::mutex error_mutex;
  std::exception_ptr error;
  auto worker = [&] {
    try {
      for (std::size_t i = next++; i < todo.size(); i = next++) {
        const long long shard = todo[i];
        std::string rows = detail::csv_header(rollout_columns());
        const long long first = shard * o.shard_size;
        for (long long index = first; index < std::min(count, first + o.shard_size); ++index) {
          const Scenario s = files.scenes.empty()
                                 ? sampler.sample(static_cast<std::uint64_t>(index), o.behavior)
                                 : files.scenes[static_cast<std::size_t>(index)];
          for (std::size_t p = 0; p < planners.size(); ++p) {
            const Rollout r = simulate(s, *planners[p], o.config, {o.duration});
            rows += detail::rollout_row(index, to_string(s.behavior), o.planners[p], r);
            progress.add(1);
            ++done;
          }
        }
        lanechange::detail::write_file_atomically(
            (fs::path(o.out_dir) / detail::shard_file(shard)).string(), rows);
      }
    } catch (...) {
      const std::lock_guard lock(error_mutex);
      if (!error) error = std::current_exception();
      next = todo.size();
    }
  };
  const unsigned jobs = run.jobs > 0 ? static_cast<unsigned>(run.jobs)
                                     : std::max(1U, std::thread::hardware_concurrency());
  std::vector<std::thread> threads;
  threads.reserve(jobs);
  for (unsigned j = 0; j < jobs; ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  progress.finish();
  if (error) std::rethrow_exception(error);
  // The tables are written once every rank has finished its shards.
  team.barrier();
  if (team.rank() == 0) {
    detail::write_results(o.out_dir, report.shards_total);
    if (!files.names.empty()) write_scene_index(o.out_dir, files);
    const bool humans_changed =
        std::any_of(files.scenes.begin(), files.scenes.end(),
                    [](const Scenario& s) { return s.origin && s.origin->human_change; });
    if (humans_changed) {
      const std::vector<RolloutRow> rows =
          read_rollouts((fs::path(o.out_dir) / "rollouts.csv").string());
      detail::write_human_comparison(o.out_dir,
                                     compare_with_humans(files.scenes, rows, o.planners));
    }
    detail::mark_complete(o.out_dir, parameters);
  }
  report.rollouts = done;
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace lanechange::sim
