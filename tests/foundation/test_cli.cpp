#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "test_helpers.hpp"

namespace lanechange {
namespace {

using testing::run_cli;
using testing::TempDir;

// Writes `json_text` to a scenario file and runs `validate` on it.
testing::CommandResult validate_text(const TempDir& dir, const std::string& json_text) {
  testing::write_text(dir.file("s.json"), json_text);
  return run_cli("validate --scenario " + dir.file("s.json"));
}

std::string example_with(const std::string& pointer, const nlohmann::json& value) {
  nlohmann::json j = testing::example_scenario_json();
  j[nlohmann::json::json_pointer(pointer)] = value;
  return j.dump();
}

TEST(Cli, HelpWorksOnEveryLevel) {
  for (const char* args : {"--help", "validate --help", "sample --help", "config --help"}) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("Usage"), std::string::npos) << args;
  }
}

TEST(Cli, ValidatePrintsTheScenarioWithDefaults) {
  TempDir dir;
  const auto r = validate_text(dir, testing::example_scenario_json().dump());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto printed = nlohmann::json::parse(r.output);
  EXPECT_EQ(printed["steps"], 50);
  EXPECT_EQ(printed["lane_width"], 3.5);
  EXPECT_TRUE(printed.contains("limits"));
}

TEST(Cli, EveryBadInputClassExitsWithTwoAndNamesTheProblem) {
  TempDir dir;
  nlohmann::json missing = testing::example_scenario_json();
  missing["leader"].erase("x");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{not json", "not valid JSON"},
      {missing.dump(), "leader.x"},
      {example_with("/behavior", "warp"), "behavior"},
      {example_with("/target/v", "NaN"), "target.v"},
      {R"({"lane_width": 3.5, "behavior": "idm", "ego": {"x": 0, "y": 0, "v": 8, "theta": 0},
           "leader": {"x": 1e999, "v": 7}, "follower": {"x": -12, "v": 9},
           "target": {"x": 20, "v": 9}})",
       "leader.x"},
      {example_with("/follower/v", -2.0), "follower.v"},
      {example_with("/lane_width", -3.5), "lane_width"},
      {example_with("/leader/x", 2.0), "overlaps"},
  };
  for (const auto& [text, expected] : cases) {
    const auto r = validate_text(dir, text);
    EXPECT_EQ(r.exit_code, 2) << text << "\n" << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos)
        << "expected '" << expected << "' in: " << r.output;
  }
  const auto no_file = run_cli("validate --scenario " + dir.file("absent.json"));
  EXPECT_EQ(no_file.exit_code, 2);
  EXPECT_NE(no_file.output.find("absent.json"), std::string::npos);
}

TEST(Cli, BadOptionsExitWithTwo) {
  EXPECT_EQ(run_cli("").exit_code, 2);
  EXPECT_EQ(run_cli("frobnicate").exit_code, 2);
  EXPECT_EQ(run_cli("sample --count 3 --out /tmp/x").exit_code, 2);  // no seed
  EXPECT_EQ(run_cli("sample --count -1 --seed 1 --out /tmp/x").exit_code, 2);
  EXPECT_EQ(run_cli("--preset nobody config").exit_code, 2);
}

TEST(Cli, SampleWritesReproducibleValidFiles) {
  TempDir dir;
  const std::string a = (dir.path() / "a").string();
  const std::string b = (dir.path() / "b").string();
  ASSERT_EQ(run_cli("sample --count 5 --seed 11 --out " + a).exit_code, 0);
  ASSERT_EQ(run_cli("sample --count 5 --seed 11 --out " + b).exit_code, 0);
  for (int i = 0; i < 5; ++i) {
    std::string name = "/scenario_00000";
    name += std::to_string(i);
    name += ".json";
    const std::string file = a + name;
    EXPECT_EQ(testing::read_text(file), testing::read_text(b + name));
    std::string validate = "validate --scenario ";
    validate += file;
    EXPECT_EQ(run_cli(validate).exit_code, 0);
  }
}

TEST(Cli, BadConfigLeavesWrittenFilesIntact) {
  TempDir dir;
  const std::string saved = dir.file("config.json");
  ASSERT_EQ(run_cli("--preset authors config --out " + saved).exit_code, 0);
  const std::string before = testing::read_text(saved);
  ASSERT_FALSE(before.empty());
  testing::write_text(dir.file("bad.json"), R"({"expert": {"steps": -4}})");
  const auto r = run_cli("--config " + dir.file("bad.json") + " config --out " + saved);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("expert.steps"), std::string::npos) << r.output;
  EXPECT_EQ(testing::read_text(saved), before);
  const std::string out_dir = (dir.path() / "none").string();
  EXPECT_EQ(
      run_cli("--config " + dir.file("bad.json") + " sample --count 2 --seed 1 --out " + out_dir)
          .exit_code,
      2);
  EXPECT_FALSE(std::filesystem::exists(out_dir));
}

}  // namespace
}  // namespace lanechange

namespace lanechange {
namespace {

// The subcommands `lanechange --help` lists, read from its "Subcommands:" block.
std::vector<std::string> listed_subcommands() {
  const auto help = testing::run_cli("--help");
  std::vector<std::string> names;
  std::istringstream in(help.output);
  bool in_block = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("Subcommands:", 0) == 0) {
      in_block = true;
    } else if (in_block && line.size() > 2 && line[0] == ' ' && line[2] != ' ') {
      names.push_back(line.substr(2, line.find(' ', 2) - 2));
    }
  }
  return names;
}

TEST(Cli, EverySubcommandHasHelp) {
  const std::vector<std::string> names = listed_subcommands();
  for (const char* expected :
       {"validate", "sample", "config", "plan", "plot", "generate", "dataset-info", "train",
        "dagger", "model-info", "simulate", "evaluate", "experiments", "crosscheck", "label-study",
        "strategy-study", "authors-study"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  }
  for (const std::string& name : names) {
    const auto help = testing::run_cli(name + " --help");
    EXPECT_EQ(help.exit_code, 0) << name << ": " << help.output;
    EXPECT_NE(help.output.find("Usage:"), std::string::npos) << name << ": " << help.output;
  }
}

// One spelling for one thing: every subcommand that draws scenes takes
// --behavior with the default "all", and every one that runs planners --planner.
TEST(Cli, SharedOptionsHaveOneNameAndDefault) {
  for (const char* name : {"sample", "generate", "evaluate", "strategy-study"}) {
    const auto help = testing::run_cli(std::string(name) + " --help");
    EXPECT_NE(help.output.find("--behavior TEXT=all"), std::string::npos) << name;
  }
  for (const char* name : {"simulate", "evaluate", "experiments"}) {
    const auto help = testing::run_cli(std::string(name) + " --help");
    EXPECT_NE(help.output.find("--planner"), std::string::npos) << name;
    EXPECT_EQ(help.output.find("--planners"), std::string::npos) << name;
  }
  EXPECT_EQ(testing::run_cli("train --help").output.find("--dagger"), std::string::npos);
}

// The global options may follow the subcommand too: the same config either way.
TEST(Cli, GlobalOptionsGoBeforeOrAfterTheSubcommand) {
  const auto before = testing::run_cli("--preset authors config");
  const auto after = testing::run_cli("config --preset authors");
  ASSERT_EQ(before.exit_code, 0) << before.output;
  ASSERT_EQ(after.exit_code, 0) << after.output;
  EXPECT_EQ(before.output, after.output);
  EXPECT_NE(before.output, testing::run_cli("config").output);
}

}  // namespace
}  // namespace lanechange
