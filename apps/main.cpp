// The lanechange command line. Bad input (a malformed scenario, config or
// option) exits with code 2 and a message that names the problem; any other
// error exits with 1.
#include <CLI/CLI.hpp>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "data_commands.hpp"
#include "experiments_command.hpp"
#include "lanechange/config.hpp"
#include "lanechange/error.hpp"
#include "lanechange/expert/crosscheck.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/plot.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/scenario.hpp"
#include "learn_commands.hpp"
#include "sim_commands.hpp"

namespace lc = lanechange;

namespace {

constexpr int kExitBadInput = 2;

struct GlobalOptions {
  std::string config_path;
  std::string preset = "paper";

  [[nodiscard]] lc::Config config() const {
    if (!config_path.empty()) return lc::load_config(config_path);
    return lc::make_preset(preset);
  }
};

void add_validate(CLI::App& app, const GlobalOptions& global) {
  auto* cmd =
      app.add_subcommand("validate", "Check a scenario file and print it with all defaults");
  static std::string scenario_path;
  cmd->add_option("--scenario", scenario_path, "Scenario JSON file")->required();
  cmd->callback([&global] {
    const lc::Scenario scenario = lc::load_scenario(scenario_path, global.config());
    std::cout << lc::scenario_to_json(scenario).dump(2) << "\n";
  });
}

void add_sample(CLI::App& app, const GlobalOptions& global) {
  auto* cmd = app.add_subcommand("sample", "Write N random scenario files (seeded)");
  static long long count = 0;
  static std::uint64_t seed = 0;
  static std::string out_dir;
  static std::string behavior;
  cmd->add_option("--count", count, "How many scenarios")
      ->required()
      ->check(CLI::Range(1LL, 100'000'000LL));
  cmd->add_option("--seed", seed, "Random seed")->required();
  cmd->add_option("--out", out_dir, "Output directory (created if missing)")->required();
  cmd->add_option("--behavior", behavior,
                  "constant_speed, constant_accel or idm (default: drawn per scenario)");
  cmd->callback([&global] {
    std::optional<lc::Behavior> fixed;
    if (!behavior.empty()) fixed = lc::behavior_from_string(behavior, "--behavior");
    const lc::ScenarioSampler sampler(global.config(), seed);
    std::filesystem::create_directories(out_dir);
    for (long long i = 0; i < count; ++i) {
      char name[64];
      std::snprintf(name, sizeof name, "scenario_%06lld.json", i);
      lc::save_scenario(sampler.sample(static_cast<std::uint64_t>(i), fixed),
                        (std::filesystem::path(out_dir) / name).string());
    }
    std::cerr << "wrote " << count << " scenarios to " << out_dir << "\n";
  });
}

void add_config(CLI::App& app, const GlobalOptions& global) {
  auto* cmd = app.add_subcommand("config", "Print the effective config as JSON (or save it)");
  static std::string out_path;
  cmd->add_option("--out", out_path, "Write to this file instead of standard output");
  cmd->callback([&global] {
    const lc::Config config = global.config();
    if (out_path.empty()) {
      nlohmann::json j = config;
      std::cout << j.dump(2) << "\n";
    } else {
      lc::save_config(config, out_path);
    }
  });
}

void add_plan(CLI::App& app, const GlobalOptions& global) {
  auto* cmd = app.add_subcommand("plan", "Plan once from the scenario's initial state");
  static std::string scenario_path;
  static std::string planner = "miqp";
  static std::string solver = "fast";
  static double time_limit = 60.0;
  static std::string out_path = "-";
  cmd->add_option("--scenario", scenario_path, "Scenario JSON file")->required();
  cmd->add_option("--planner", planner,
                  "Planner: miqp, the expert's open-loop plan (the closed-loop planners run with "
                  "simulate and evaluate)");
  cmd->add_option("--solver", solver, "MIQP back-end: fast (ours) or reference (Bonmin B-BB)");
  cmd->add_option("--time-limit", time_limit, "Seconds for the whole plan")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", out_path, "Trajectory JSON file, or - for standard output");
  cmd->callback([&global] {
    if (planner != "miqp") {
      std::string message = "plan makes the expert's open-loop plan (miqp); \"";
      message += planner;
      message += "\" acts in closed loop: use simulate --planner ";
      message += planner;
      throw lc::InputError("--planner", message);
    }
    const lc::Config config = global.config();
    const lc::Scenario scenario = lc::load_scenario(scenario_path, config);
    const lc::expert::ExpertPlanner expert(
        config, lc::expert::make_lane_change_solver(solver, config.expert.big_m));
    const auto result = expert.plan(scenario, {time_limit});
    const lc::Trajectory trajectory = expert.to_trajectory(result, scenario);
    lc::save_trajectory(trajectory, out_path);
    std::cerr << "label " << lc::to_string(trajectory.label) << ", "
              << lc::expert::to_string(result.status) << " after " << result.iterations()
              << " rounds, objective " << result.objective << ", " << result.total_ms << " ms"
              << (trajectory.reason.empty() ? "" : " (" + trajectory.reason + ")") << "\n";
  });
}

nlohmann::json crosscheck_row(const lc::expert::CrossCheckCase& c, std::uint64_t seed, int steps) {
  auto number_or_null = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
  };
  return {{"index", c.index},
          {"seed", seed},
          {"steps", steps},
          {"behavior", c.behavior},
          {"fast_status", lc::expert::to_string(c.fast_status)},
          {"reference_status", lc::expert::to_string(c.reference_status)},
          {"fast_objective", number_or_null(c.fast_objective)},
          {"reference_objective", number_or_null(c.reference_objective)},
          {"relative_difference", c.relative_difference},
          {"fast_ms", c.fast_ms},
          {"reference_ms", c.reference_ms},
          {"fast_nodes", c.fast_nodes},
          {"reference_nodes", c.reference_nodes},
          {"agree", c.agree}};
}

// A case of an earlier cross-check file: its scenario, the config it was made
// with, and the reference's verdict.
struct StoredCase {
  std::optional<nlohmann::json> scenario;
  lc::Config config;
  std::uint64_t index = 0;
  std::uint64_t seed = 0;
  int steps = 0;
  lc::expert::StoredReference reference;
};

StoredCase parse_stored_case(const std::string& line, long long line_number, std::uint64_t seed,
                             int steps) {
  const std::string where = "cross-check line " + std::to_string(line_number);
  try {
    const auto row = nlohmann::json::parse(line);
    StoredCase c;
    if (row.contains("scenario")) c.scenario = row.at("scenario");
    // A replay checks what the stored verdict was made for, whatever today's
    // defaults are: a case without its config cannot be replayed faithfully.
    if (!row.contains("config")) {
      throw lc::InputError(where, "carries no \"config\" (the config the case was made with)");
    }
    c.config = lc::config_from_json(row.at("config"));
    c.index = row.at("index").get<std::uint64_t>();
    c.seed = row.value("seed", seed);
    c.steps = row.value("steps", steps);
    c.reference.status =
        lc::expert::parse_miqp_status(row.at("reference_status").get<std::string>());
    const auto& objective = row.at("reference_objective");
    c.reference.objective = objective.is_null() ? lc::expert::kInfinity : objective.get<double>();
    c.reference.ms = row.value("reference_ms", 0.0);
    c.reference.nodes = row.value("reference_nodes", 0L);
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw lc::InputError(where, e.what());
  }
}

void add_crosscheck(CLI::App& app, const GlobalOptions& global) {
  auto* cmd = app.add_subcommand(
      "crosscheck", "Solve the same linearized MIQPs with the fast and the reference solver");
  static long long count = 20;
  static long long first = 0;
  static std::uint64_t seed = 1;
  static int steps = 0;
  static double tolerance = 1e-6;
  static std::string out_path;
  static std::string replay_path;
  cmd->add_option("--count", count, "How many sampled scenarios")->check(CLI::Range(1LL, 100000LL));
  cmd->add_option("--seed", seed, "Sampler seed");
  cmd->add_option("--first", first, "Index of the first scenario");
  cmd->add_option("--steps", steps, "Override N (fewer steps make the reference faster)");
  cmd->add_option("--tolerance", tolerance, "Largest relative objective difference");
  cmd->add_option("--out", out_path, "JSON lines file, one case per line");
  cmd->add_option("--replay", replay_path,
                  "Re-solve only the fast side of the cases in an earlier --out file and compare "
                  "with its stored reference results (seconds instead of hours); each case "
                  "uses the config stored with it, not --config or --preset")
      ->check(CLI::ExistingFile);
  cmd->callback([&global] {
    const lc::expert::FastLaneChangeSolver fast;
    std::ofstream out;
    if (!out_path.empty()) out.open(out_path);
    long long agreed = 0;
    long long total = 0;
    // A stored case carries its scenario, so that a replay does not depend on the sampler.
    auto run_case = [&](std::uint64_t index, std::uint64_t case_seed, int case_steps,
                        const lc::expert::StoredReference* stored,
                        const std::optional<nlohmann::json>& stored_scenario,
                        const lc::Config* stored_config) {
      lc::Config config = stored_config != nullptr ? *stored_config : global.config();
      if (case_steps > 0) config.expert.steps = case_steps;
      const lc::Scenario scenario = stored_scenario
                                        ? lc::scenario_from_json(*stored_scenario, config)
                                        : lc::ScenarioSampler(config, case_seed).sample(index);
      const auto qp = lc::expert::first_round_problem(scenario, config);
      lc::expert::CrossCheckCase c;
      if (stored != nullptr) {
        c = lc::expert::compare_with_reference(fast.solve(qp, {}), *stored, tolerance);
      } else {
        const lc::expert::ReferenceLaneChangeSolver reference(config.expert.big_m);
        c = lc::expert::cross_check(qp, fast, reference, {}, tolerance);
      }
      c.index = index;
      c.behavior = std::string(lc::to_string(scenario.behavior));
      // A reference that hit its limit decides nothing: count agreement on the rest.
      const bool decided = c.reference_status == lc::expert::MiqpStatus::Optimal ||
                           c.reference_status == lc::expert::MiqpStatus::Infeasible;
      total += decided || stored == nullptr ? 1 : 0;
      agreed += c.agree ? 1 : 0;
      nlohmann::json row = crosscheck_row(c, case_seed, case_steps);
      row["scenario"] = lc::scenario_to_json(scenario);
      row["config"] = config;
      if (out.is_open()) out << row.dump() << std::endl;
      std::cerr << row.dump() << "\n";
    };
    if (!replay_path.empty()) {
      std::ifstream in(replay_path);
      std::string line;
      long long line_number = 0;
      while (std::getline(in, line)) {
        ++line_number;
        if (line.empty()) continue;
        const StoredCase c = parse_stored_case(line, line_number, seed, steps);
        run_case(c.index, c.seed, c.steps, &c.reference, c.scenario, &c.config);
      }
    } else {
      for (long long i = first; i < first + count; ++i) {
        run_case(static_cast<std::uint64_t>(i), seed, steps, nullptr, std::nullopt, nullptr);
      }
    }
    std::cout << agreed << " of " << total << " agree\n";
    if (agreed != total) throw std::runtime_error("the solvers disagree");
  });
}

// Plans sampled scenarios once and labels each plan under several reversal
// tolerances and both readings of "y never decreases" (docs/expert.md).
void add_label_study(CLI::App& app, const GlobalOptions& global) {
  auto* cmd =
      app.add_subcommand("label-study", "Label shares of expert plans under several tolerances");
  static long long count = 100;
  static std::uint64_t seed = 1;
  cmd->add_option("--count", count, "How many sampled scenarios")
      ->check(CLI::Range(1LL, 1000000LL));
  cmd->add_option("--seed", seed, "Sampler seed");
  cmd->callback([&global] {
    const lc::Config config = global.config();
    const lc::ScenarioSampler sampler(config, seed);
    const lc::expert::ExpertPlanner planner(config,
                                            std::make_shared<lc::expert::FastLaneChangeSolver>());
    const std::vector<double> tolerances = {0.02, 0.05, 0.10, 0.20, 0.30};
    const std::vector<lc::ReversalReference> references = {lc::ReversalReference::TargetCenter,
                                                           lc::ReversalReference::RunningMax};
    std::vector<std::array<long long, 3>> counts(tolerances.size() * references.size());
    for (long long i = 0; i < count; ++i) {
      const lc::Scenario s = sampler.sample(static_cast<std::uint64_t>(i));
      const lc::Trajectory t = planner.to_trajectory(planner.plan(s), s);
      for (std::size_t r = 0; r < references.size(); ++r) {
        for (std::size_t j = 0; j < tolerances.size(); ++j) {
          lc::LabelTolerances tol = config.labels;
          tol.reversal = tolerances[j];
          tol.reference = references[r];
          // A failure (no solution, lane not reached, collision) stays one;
          // only the reversal test depends on the tolerance.
          const lc::Label label =
              t.label == lc::Label::Failure
                  ? lc::Label::Failure
                  : lc::label_trajectory(t.ys(), t.ego.back().theta, s.lane_width, tol).label;
          ++counts[r * tolerances.size() + j][static_cast<int>(label)];
        }
      }
    }
    std::cout
        << "| reading | tolerance | well-posed | ill-posed | failure |\n|---|---|---|---|---|\n";
    for (std::size_t r = 0; r < references.size(); ++r) {
      for (std::size_t j = 0; j < tolerances.size(); ++j) {
        const auto& c = counts[r * tolerances.size() + j];
        auto share = [&](int k) {
          return 100.0 * static_cast<double>(c[k]) / static_cast<double>(count);
        };
        char line[200];
        std::snprintf(
            line, sizeof line, "| %s | %.2f m | %.1f%% | %.1f%% | %.1f%% |\n",
            references[r] == lc::ReversalReference::TargetCenter ? "target_center" : "running_max",
            tolerances[j], share(0), share(1), share(2));
        std::cout << line;
      }
    }
  });
}

void add_plot(CLI::App& app, const GlobalOptions& global) {
  auto* cmd = app.add_subcommand(
      "plot", "Draw a trajectory file as a PNG (needs gnuplot), or --animate it as an SVG");
  static std::string trajectory_path;
  static std::string out_path;
  static int snapshots = 5;
  static bool animate = false;
  static double speedup = 1.0;
  cmd->add_option("--trajectory", trajectory_path, "Trajectory JSON file (plan or rollout)")
      ->required();
  cmd->add_option("--out", out_path, "PNG file to write (SVG with --animate)")->required();
  cmd->add_flag("--animate", animate,
                "Write an animated SVG (plays in a web browser; no gnuplot needed)");
  cmd->add_option("--speedup", speedup, "Playback speed of --animate against real time")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--snapshots", snapshots, "How many instants to draw the cars at")
      ->check(CLI::Range(1, 50));
  cmd->callback([&global] {
    if (animate) {
      lc::AnimationOptions options;
      options.vehicle = global.config().vehicle;
      options.speedup = speedup;
      lc::animate_trajectory(lc::load_trajectory(trajectory_path), out_path, options);
      std::cerr << "wrote " << out_path << "\n";
      return;
    }
    lc::PlotOptions options;
    options.vehicle = global.config().vehicle;  // the trajectory file does not store it
    options.snapshots = snapshots;
    lc::plot_trajectory(lc::load_trajectory(trajectory_path), out_path, options);
    std::cerr << "wrote " << out_path << "\n";
  });
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lanechange: motion planning for automated lane changes"};
  app.require_subcommand(1);
  GlobalOptions global;
  app.add_option("--config", global.config_path, "Config JSON file (overrides --preset)");
  app.add_option("--preset", global.preset, "Config preset: paper or authors")
      ->check(CLI::IsMember(lc::preset_names()));
  add_validate(app, global);
  add_sample(app, global);
  add_config(app, global);
  add_plan(app, global);
  add_crosscheck(app, global);
  add_label_study(app, global);
  add_plot(app, global);
  lc::app::add_generate(app, [&global] { return global.config(); });
  lc::app::add_dataset_info(app);
  lc::app::add_simulate(app, [&global] { return global.config(); });
  lc::app::add_evaluate(app, [&global] { return global.config(); });
  lc::app::add_strategy_study(app, [&global] { return global.config(); });
  lc::app::add_train(app, [&global] { return global.config(); });
  lc::app::add_experiments(app, [&global] { return global.config(); });
  lc::app::add_model_info(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  } catch (const lc::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
