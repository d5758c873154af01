// SUMO episodes in worker processes: libsumo's state is global, so threads
// cannot share it, and a forked worker inherits the planners already built.
#include "lanechange/sumo/evaluate.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>

#include "common/json_fields.hpp"
#include "lanechange/error.hpp"
#include "lanechange/run/progress.hpp"
#include "lanechange/run/team.hpp"
#include "sim/evaluation_files.hpp"

namespace lanechange::sumo {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Planners = std::vector<std::shared_ptr<const planner::ClosedLoopPlanner>>;

// One episode: a highway of a density and seed, or an interactive folder.
struct EpisodeSpec {
  std::string group;
  HighwaySettings highway;
  std::string folder;  ///< empty: the highway
};

// The subfolders holding a NAME.cr.xml, by name; the others are not scenarios.
std::vector<std::string> interactive_folders(const std::string& dir) {
  if (!fs::is_directory(dir)) throw InputError("--sumo-commonroad", dir + " is not a folder");
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() && fs::is_regular_file(entry.path() / (name + ".cr.xml"))) {
      out.push_back(name);
    }
  }
  std::sort(out.begin(), out.end());
  if (out.empty()) {
    throw InputError("--sumo-commonroad", dir + " holds no interactive scenario folder");
  }
  return out;
}

std::vector<EpisodeSpec> episodes_of(const EvaluateOptions& o) {
  std::vector<EpisodeSpec> out;
  if (!o.commonroad_dir.empty()) {
    for (const std::string& name : interactive_folders(o.commonroad_dir)) {
      out.push_back({"commonroad", o.highway, (fs::path(o.commonroad_dir) / name).string()});
    }
    return out;
  }
  for (const double density : o.densities) {
    for (long long i = 0; i < o.count; ++i) {
      EpisodeSpec e{highway_group(density), o.highway, ""};
      e.highway.density = density;
      e.highway.seed = o.seed + static_cast<int>(i);
      out.push_back(std::move(e));
    }
  }
  return out;
}

void validate_options(const EvaluateOptions& o) {
  if (o.densities.empty() == o.commonroad_dir.empty()) {
    throw InputError("--sumo-highway", "name the traffic: densities or --sumo-commonroad, one");
  }
  for (const double d : o.densities) {
    HighwaySettings h = o.highway;
    h.density = d;
    validate(h);
  }
  if (o.commonroad_dir.empty() && o.count < 1) throw InputError("--count", "must be at least 1");
  if (o.shard_size < 1) throw InputError("--shard-size", "must be at least 1");
  if (o.planners.empty()) throw InputError("--planner", "names no planner");
  if (o.out_dir.empty()) throw InputError("--out", "must name a directory");
  CoSimSettings loop = o.loop;
  loop.work_dir = o.out_dir;
  validate(loop);
  o.config.validate();
}

json parameters_of(const EvaluateOptions& o, const std::vector<EpisodeSpec>& episodes) {
  const HighwaySettings& h = o.highway;
  const CoSimSettings& c = o.loop;
  json folders = json::array();
  for (const EpisodeSpec& e : episodes) {
    if (!e.folder.empty()) folders.push_back(fs::path(e.folder).filename().string());
  }
  return {{"sumo_highway", o.densities},
          {"sumo_commonroad", folders},
          {"count", o.count},
          {"seed", o.seed},
          {"planners", o.planners},
          {"model", o.model_dir},
          {"shard_size", o.shard_size},
          {"highway",
           {{"lanes", h.lanes},
            {"ego_lane", h.ego_lane},
            {"length", h.length},
            {"speed_limit", h.speed_limit},
            {"settle_time", h.settle_time},
            {"ego_position", h.ego_position}}},
          {"loop",
           {{"range", c.range},
            {"request_after", c.request_after},
            {"duration", c.duration},
            {"prediction", std::string(to_string(c.prediction))},
            {"signal_change", c.signal_change}}},
          {"config", o.config}};
}

// The planners of a CommonRoad folder whose cars SUMO drives by a vehicle
// type of its own, made for it once (the built-in highway's are SUMO's
// defaults, the planners evaluate() made).
class FolderPlanners {
 public:
  FolderPlanners(const EvaluateOptions& o, const Planners& defaults) : o_(o), defaults_(defaults) {}

  // The config and planners for `folder`.
  std::pair<const Config*, const Planners*> of(const std::string& folder) {
    const SumoCarModel cars = commonroad_car_model(folder);
    if (cars == SumoCarModel{}) return {&o_.config, &defaults_};
    if (model_ != cars) {
      model_ = cars;
      config_ = as_sumo_drives(o_.config, cars);
      planners_.clear();
      for (const auto& name : o_.planners)
        planners_.push_back(o_.make_planner(name, config_, o_.model_dir));
    }
    return {&config_, &planners_};
  }

 private:
  const EvaluateOptions& o_;
  const Planners& defaults_;
  std::optional<SumoCarModel> model_;
  Config config_;
  Planners planners_;
};

// Runs the shards `shards` (one process), writing each shard file whole.
void run_shards(const EvaluateOptions& o, const Planners& planners,
                const std::vector<EpisodeSpec>& episodes, const std::vector<long long>& shards,
                const std::string& work_dir) {
  const auto total = static_cast<long long>(episodes.size());
  CoSimSettings loop = o.loop;
  loop.work_dir = work_dir;
  FolderPlanners folder_planners(o, planners);
  for (const long long shard : shards) {
    std::string rows = sim::detail::csv_header(sim::rollout_columns());
    const long long first = shard * o.shard_size;
    for (long long index = first; index < std::min(total, first + o.shard_size); ++index) {
      const EpisodeSpec& e = episodes[static_cast<std::size_t>(index)];
      const auto [config, episode_planners] =
          e.folder.empty() ? std::pair{&o.config, &planners} : folder_planners.of(e.folder);
      for (std::size_t p = 0; p < episode_planners->size(); ++p) {
        const planner::ClosedLoopPlanner& planner = *(*episode_planners)[p];
        const CoSimResult r = e.folder.empty() ? run_highway(planner, *config, e.highway, loop)
                                               : run_commonroad(planner, *config, e.folder, loop);
        rows += sim::detail::rollout_row(index, e.group, o.planners[p], r.rollout);
      }
    }
    lanechange::detail::write_file_atomically(
        (fs::path(o.out_dir) / sim::detail::shard_file(shard)).string(), rows);
  }
}

// Forks one worker per share of `todo` and waits for them all, counting the
// shard files they finish as progress. A worker's error is written to a file
// and rethrown here.
void run_in_workers(const EvaluateOptions& o, const Planners& planners,
                    const std::vector<EpisodeSpec>& episodes, const std::vector<long long>& todo,
                    int jobs, run::Progress& progress) {
  const fs::path work = fs::path(o.out_dir) / "sumo";
  std::vector<pid_t> workers;
  for (int j = 0; j < jobs && j < static_cast<int>(todo.size()); ++j) {
    std::vector<long long> mine;
    for (std::size_t i = static_cast<std::size_t>(j); i < todo.size();
         i += static_cast<std::size_t>(jobs)) {
      mine.push_back(todo[i]);
    }
    const fs::path dir = work / ("worker-" + std::to_string(j));
    fs::create_directories(dir);
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error("cannot start a SUMO worker process");
    if (pid == 0) {
      int code = 0;
      try {
        run_shards(o, planners, episodes, mine, dir.string());
      } catch (const std::exception& e) {
        std::ofstream(dir / "error.txt") << e.what() << "\n";
        code = 1;
      }
      ::_exit(code);  // the parent's exit handlers (and MPI's) are not the worker's
    }
    workers.push_back(pid);
  }
  std::string failure;
  std::size_t running = workers.size();
  long long reported = 0;
  while (running > 0) {
    for (pid_t& pid : workers) {
      if (pid <= 0) continue;
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) != pid) continue;
      const std::size_t j = static_cast<std::size_t>(&pid - workers.data());
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::ifstream in(work / ("worker-" + std::to_string(j)) / "error.txt");
        std::stringstream why;
        why << in.rdbuf();
        if (failure.empty()) failure = "SUMO worker " + std::to_string(j) + " failed: " + why.str();
      }
      pid = 0;
      --running;
    }
    long long finished = 0;
    for (const long long s : todo) {
      finished += fs::exists(fs::path(o.out_dir) / sim::detail::shard_file(s)) ? 1 : 0;
    }
    progress.add(finished - reported);
    reported = finished;
    if (running > 0) std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (!failure.empty()) throw std::runtime_error(failure);
}

}  // namespace

std::string highway_group(double density) {
  std::ostringstream name;
  name << "highway_" << density;
  return name.str();
}

sim::EvaluateReport evaluate(const EvaluateOptions& given, const sim::EvaluateRun& run) {
  // Whoever calls (the CLI, the experiments), the planners plan by SUMO's rules.
  EvaluateOptions o = given;
  o.config = as_sumo_drives(given.config);
  validate_options(o);
  // Built (and a model loaded) once, before the directory is touched.
  Planners planners;
  for (const auto& name : o.planners)
    planners.push_back(o.make_planner(name, o.config, o.model_dir));
  const auto start = std::chrono::steady_clock::now();
  const std::vector<EpisodeSpec> episodes = episodes_of(o);
  const json parameters = parameters_of(o, episodes);
  sim::EvaluateReport report;
  const auto total = static_cast<long long>(episodes.size());
  report.shards_total = (total + o.shard_size - 1) / o.shard_size;
  run::Team& team = run::team_or_alone(run.team);
  if (run::decide_on_rank_zero(team, "--out", [&] {
        return sim::detail::prepare_directory(o.out_dir, parameters) ? 1 : 0;
      }) == 1) {
    report.shards_skipped = report.shards_total;
    return report;
  }
  std::vector<long long> todo;
  for (long long s = team.rank(); s < report.shards_total; s += team.size()) {
    if (fs::exists(fs::path(o.out_dir) / sim::detail::shard_file(s))) {
      ++report.shards_skipped;
    } else {
      todo.push_back(s);
    }
  }
  run::Progress progress(run.progress, run.progress_on_terminal,
                         static_cast<long long>(todo.size()), -1.0, "evaluate", "shards");
  const int jobs =
      run.jobs > 0 ? run.jobs : static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  if (jobs == 1) {
    // One worker: this process, one shard after another.
    const std::string dir = (fs::path(o.out_dir) / "sumo" / "worker-0").string();
    fs::create_directories(dir);
    for (const long long s : todo) {
      run_shards(o, planners, episodes, {s}, dir);
      progress.add(1);
    }
  } else {
    run_in_workers(o, planners, episodes, todo, jobs, progress);
  }
  progress.finish();
  team.barrier();
  if (team.rank() == 0) {
    sim::detail::write_results(o.out_dir, report.shards_total);
    sim::detail::mark_complete(o.out_dir, parameters);
  }
  for (const long long s : todo) {
    report.rollouts +=
        std::min(o.shard_size, total - s * o.shard_size) * static_cast<long long>(planners.size());
  }
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace lanechange::sumo
