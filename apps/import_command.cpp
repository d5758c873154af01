// import-commonroad: lane-change scenes cut out of CommonRoad recordings.
#include <charconv>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "lanechange/commonroad/import.hpp"
#include "lanechange/error.hpp"

namespace lanechange::app {

namespace {

struct ImportArgs {
  std::vector<std::string> files;
  std::string out_dir;
  std::string ego = "planning";
  double every = 2.0;
  double range = 100.0;
  bool right = false;
  std::string behavior = "replay";
  bool reactive_behind = false;
};

// "planning", "recorded", or obstacle ids "12,40".
void read_ego_option(const std::string& ego, commonroad::ImportSettings& settings) {
  if (ego == "planning") return;
  settings.egos = commonroad::EgoChoice::RecordedCars;
  if (ego == "recorded") return;
  std::string_view rest = ego;
  while (!rest.empty()) {
    const std::string_view item = rest.substr(0, rest.find(','));
    int id = 0;
    const auto [end, error] = std::from_chars(item.data(), item.data() + item.size(), id);
    if (error != std::errc() || end != item.data() + item.size()) {
      throw InputError("--ego",
                       "\"" + ego + "\" is not planning, recorded or a list of obstacle ids");
    }
    settings.cars.push_back(id);
    rest = item.size() < rest.size() ? rest.substr(item.size() + 1) : std::string_view{};
  }
}

void import_files(const ImportArgs& a, const Config& config) {
  commonroad::ImportSettings settings;
  read_ego_option(a.ego, settings);
  settings.every = a.every;
  settings.range = a.range;
  settings.right = a.right;
  settings.behavior = behavior_from_string(a.behavior, "--behavior");
  settings.reactive_behind = a.reactive_behind;
  // Every file is read and cut before anything is written, so a bad file
  // leaves the output folder as it was.
  std::vector<commonroad::ImportReport> reports;
  for (const std::string& file : a.files)
    reports.push_back(
        commonroad::import_scenes(commonroad::read_recording(file), config, settings));
  std::filesystem::create_directories(a.out_dir);
  for (std::size_t i = 0; i < a.files.size(); ++i) {
    int changes = 0;
    for (const commonroad::ImportedScene& s : reports[i].scenes) {
      save_scenario(s.scene, (std::filesystem::path(a.out_dir) / (s.name + ".json")).string());
      changes += s.scene.origin && s.scene.origin->human_change ? 1 : 0;
    }
    std::cerr << a.files[i] << ": " << reports[i].scenes.size() << " scenes";
    if (settings.egos == commonroad::EgoChoice::RecordedCars)
      std::cerr << " (in " << changes << " the driver changed into the target lane)";
    for (const auto& [reason, count] : reports[i].skipped)
      std::cerr << "; skipped " << count << ": " << reason;
    std::cerr << "\n";
  }
}

}  // namespace

void add_import_commonroad(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand("import-commonroad",
                                 "Cut lane-change scenes out of CommonRoad 2020a recordings");
  auto a = make_args<ImportArgs>();
  cmd->add_option("files", a->files, "CommonRoad XML files")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", a->out_dir, "Output directory for the scene files")->required();
  cmd->add_option("--ego", a->ego,
                  "Whose scenes: planning (each planning problem), recorded (every recorded car) "
                  "or obstacle ids 12,40")
      ->capture_default_str();
  cmd->add_option("--every", a->every, "Seconds between one recorded car's scenes")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--range", a->range, "Metres ahead and behind the ego within which cars are kept")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--right", a->right, "Also cut scenes with the target lane to the right");
  cmd->add_option("--behavior", a->behavior,
                  "How the cars move: replay (as recorded), constant_speed, constant_accel or idm")
      ->capture_default_str();
  cmd->add_flag("--reactive-behind", a->reactive_behind,
                "Cars behind the ego follow IDM instead, so that they answer a cut-in");
  cmd->callback([a, config] { import_files(*a, config()); });
}

}  // namespace lanechange::app
