// The lanechange command line. Bad input (a malformed scenario, config or
// option) exits with code 2 and a message that names the problem; any other
// error exits with 1.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "lanechange/config.hpp"
#include "lanechange/error.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/scenario.hpp"

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
  auto* cmd = app.add_subcommand("validate", "Check a scenario file and print it with all defaults");
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
  cmd->add_option("--count", count, "How many scenarios")->required()->check(CLI::Range(1LL, 100'000'000LL));
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
