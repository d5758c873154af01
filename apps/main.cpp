// The lanechange command line. Bad input (a malformed scenario, config or
// option) exits with code 2 and a message that names the problem; any other
// error exits with 1.
#include <CLI/CLI.hpp>
#include <iostream>

#include "commands.hpp"
#include "lanechange/config.hpp"
#include "lanechange/error.hpp"

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

void add_commands(CLI::App& app, const GlobalOptions& global) {
  const lc::app::ConfigSource config = [&global] { return global.config(); };
  namespace cmd = lc::app;
  cmd::add_validate(app, config);
  cmd::add_sample(app, config);
  cmd::add_config(app, config);
  cmd::add_plan(app, config);
  cmd::add_plot(app, config);
  cmd::add_import_commonroad(app, config);
  cmd::add_generate(app, config);
  cmd::add_dataset_info(app);
  cmd::add_train(app);
  cmd::add_dagger(app, config);
  cmd::add_model_info(app);
  cmd::add_simulate(app, config);
  cmd::add_evaluate(app, config);
  cmd::add_experiments(app, config);
  cmd::add_sumo(app, config);
  cmd::add_crosscheck(app, config);
  cmd::add_label_study(app, config);
  cmd::add_strategy_study(app, config);
  cmd::add_authors_study(app, config);
}

int run(int argc, char** argv) {
  CLI::App app{"lanechange: motion planning for automated lane changes"};
  app.require_subcommand(1);
  // --config and --preset may also follow the subcommand's name.
  app.fallthrough();
  GlobalOptions global;
  app.add_option("--config", global.config_path, "Config JSON file (overrides --preset)");
  app.add_option("--preset", global.preset, "Config preset: paper or authors")
      ->check(CLI::IsMember(lc::preset_names()));
  add_commands(app, global);
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
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  } catch (...) {
    std::cerr << "error: unknown exception\n";
    return 1;
  }
}
