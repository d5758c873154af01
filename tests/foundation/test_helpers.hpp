#pragma once
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "lanechange/config.hpp"
#include "lanechange/error.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange {
/// A car's index in a three-car (format-1) scene: the roles in their order.
constexpr CarIndex car_of(Role role) { return static_cast<CarIndex>(role); }
}  // namespace lanechange

namespace lanechange::testing {

/// The example scenario of formats.md.
inline nlohmann::json example_scenario_json() {
  return nlohmann::json::parse(R"({
    "format": "lanechange.scenario/1",
    "lane_width": 3.5,
    "behavior": "constant_speed",
    "ego":      {"x": 0.0,   "y": 0.0, "v": 8.0, "theta": 0.0, "a": 0.0},
    "leader":   {"x": 30.0,  "v": 7.0, "a": 0.0},
    "follower": {"x": -12.0, "v": 9.0, "a": 0.0},
    "target":   {"x": 20.0,  "v": 9.5, "a": 0.0}
  })");
}

/// The example of formats.md as a format-2 file: the same scene, each car
/// with its id, lane and role.
inline nlohmann::json example_cars_json() {
  return nlohmann::json::parse(R"({
    "format": "lanechange.scenario/2",
    "road": {"lane_width": 3.5, "target_lane": "left"},
    "behavior": "constant_speed",
    "ego": {"x": 0.0, "y": 0.0, "v": 8.0, "theta": 0.0, "a": 0.0},
    "cars": [
      {"id": "leader",   "lane": "ego",    "x": 30.0,  "v": 7.0, "role": "leader"},
      {"id": "follower", "lane": "target", "x": -12.0, "v": 9.0, "role": "follower"},
      {"id": "target",   "lane": "target", "x": 20.0,  "v": 9.5, "role": "target"}
    ]
  })");
}

/// Dense traffic: `target_cars` cars in the target lane every `spacing`
/// metres from `first` back to front, a leader 30 m ahead of the ego and a
/// car 25 m behind it, every car at `speed`. Roles are the nearest cars.
inline Scenario dense_scenario(int target_cars, double first = -60.0, double spacing = 16.0,
                               double speed = 9.0, Behavior behavior = Behavior::ConstantSpeed) {
  nlohmann::json j = example_cars_json();
  j["behavior"] = std::string(to_string(behavior));
  j["ego"]["v"] = speed;
  auto& cars = j["cars"];
  cars = nlohmann::json::array();
  cars.push_back({{"id", "lead"}, {"lane", "ego"}, {"x", 30.0}, {"v", speed}});
  cars.push_back({{"id", "rear"}, {"lane", "ego"}, {"x", -25.0}, {"v", speed}});
  for (int i = 0; i < target_cars; ++i) {
    std::string id = "t";  // appended: GCC 12 misreads "t" + to_string (-Wrestrict)
    id += std::to_string(i);
    cars.push_back({{"id", id}, {"lane", "target"}, {"x", first + spacing * i}, {"v", speed}});
  }
  return scenario_from_json(j, Config{});
}

/// Parses and expects an InputError whose field is `field` and whose message
/// names it and says `words`.
inline void expect_rejected(const nlohmann::json& j, const std::string& field,
                            const std::string& words = "") {
  try {
    (void)scenario_from_json(j, Config{});
    FAIL() << "accepted a bad scenario; expected an error naming " << field;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

/// A fresh directory under the system temp dir, removed at destruction.
class TempDir {
 public:
  TempDir() {
    path_ =
        std::filesystem::temp_directory_path() /
        ("lanechange_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  [[nodiscard]] std::string file(const std::string& name) const { return (path_ / name).string(); }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Runs make() to fill dir once, then reuses it: test processes that need
/// the same costly inputs (a generated data set, a trained model) wait on a
/// lock while the first makes them. CTest empties the parent before the run
/// (lanechange_add_test's SHARED_SUITES), so a run never reuses an older build's.
template <class Make>
void made_once(const std::filesystem::path& dir, Make&& make) {
  std::filesystem::create_directories(dir.parent_path());
  const std::string lock_path = dir.string() + ".lock";
  const int lock = ::open(lock_path.c_str(), O_CREAT | O_RDWR, 0644);
  if (lock < 0) {
    ADD_FAILURE() << "cannot open " << lock_path;
    return;
  }
  if (::flock(lock, LOCK_EX) != 0) {
    ::close(lock);
    ADD_FAILURE() << "cannot lock " << lock_path;
    return;
  }
  const auto done = dir / ".made";
  if (!std::filesystem::exists(done)) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    make();
    if (!::testing::Test::HasFatalFailure()) std::ofstream(done) << "made\n";
  }
  ::close(lock);  // also releases the lock
}

inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct CommandResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
};

/// Runs a shell command line, with its standard error.
inline CommandResult run_cli_command(const std::string& command_line) {
  const std::string command = command_line + " 2>&1";
  CommandResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) result.output += buffer;
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

/// Runs the lanechange CLI with `args` (already shell-quoted).
inline CommandResult run_cli(const std::string& args) {
  // Appended, not concatenated: GCC 12 warns falsely on `string + " " + string` here.
  std::string command = LANECHANGE_CLI;
  command += ' ';
  command += args;
  return run_cli_command(command);
}

/// Runs the lanechange CLI on `ranks` MPI ranks (mpirun must be on PATH).
/// ASan's leak check would report MPI's own allocations at exit, and as root
/// mpirun wants to be told that is meant.
inline CommandResult run_cli_on_ranks(int ranks, const std::string& args) {
  return run_cli_command(
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ASAN_OPTIONS=detect_leaks=0 "
      "mpirun -np " +
      std::to_string(ranks) + " --oversubscribe " + std::string(LANECHANGE_CLI) + " " + args);
}

inline bool mpirun_available() { return std::system("command -v mpirun > /dev/null 2>&1") == 0; }

/// The default config with no step budget at all: neither the wall clock
/// (under the sanitizers a re-plan can take longer than the 100 ms control
/// period) nor the expert's budget of work binds.
inline Config untimed_config() {
  Config c;
  c.closed_loop.deadline = Deadline::WallClock;
  c.closed_loop.step_budget_ms = 1e9;
  return c;
}

/// untimed_config() as a file for the CLI, in `dir`; returns its path.
inline std::string untimed_config_file(const TempDir& dir) {
  const std::string path = dir.file("untimed.json");
  write_text(path, R"({"closed_loop": {"deadline": "wall_clock", "step_budget_ms": 1e9}})");
  return path;
}

/// Every car far away: a wide-open gap in the target lane.
// The paper's expert: Eq. 1's gap between the follower and the target only.
inline Config fixed_gap_config(Config config = {}) {
  config.expert.gap = GapChoice::Fixed;
  return config;
}

/// For no_gap_scenario(): Eq. 1's gap alone, between cars that keep their
/// speed whatever the ego does, so that it never opens. A follower that
/// reacts makes room for an ego that waits at the line long enough.
inline Config no_gap_config(Config config = {}) {
  config = fixed_gap_config(std::move(config));
  config.traffic.followers_react = false;
  return config;
}

/// The paper's whole set-up: Eq. 1's gap alone and distances, in the paper's traffic
/// (cars that ignore everything, IDM without a braking limit).
inline Config paper_config(Config config = {}) { return paper_formulation(std::move(config)); }

inline Scenario open_road_scenario(Behavior behavior = Behavior::ConstantSpeed) {
  Scenario s = three_car_scenario(Config{});
  s.set_behavior(behavior);
  s.ego = {0.0, 0.0, 8.0, 0.0, 0.0};
  s.leader() = {40.0, 8.0, 0.0};
  s.follower() = {-60.0, 8.0, 0.0};
  s.target() = {70.0, 8.0, 0.0};
  validate_scenario(s);
  return s;
}

// The follower and target bumper to bumper beside the ego: Eq. 1's gap is
// closed. The gaps behind the follower and ahead of the target stay open, so
// a test of "no gap" plans with fixed_gap_config().
inline Scenario no_gap_scenario() {
  Scenario s = open_road_scenario();
  s.follower() = {-2.0, 8.0, 0.0};
  s.target() = {3.0, 8.0, 0.0};
  validate_scenario(s);
  return s;
}

// The follower and target too close together to take the ego between them,
// both slower than it: only the gap ahead of the target is open.
inline Scenario only_the_gap_ahead_of_the_target() {
  Scenario s = open_road_scenario();
  s.ego.v = 10.0;
  s.leader() = {40.0, 10.0, 0.0};
  s.follower() = {-24.0, 8.0, 0.0};
  s.target() = {-10.0, 8.0, 0.0};
  validate_scenario(s);
  return s;
}

// The follower and the target both faster than the ego and too close together
// for it: only the gap behind the follower is open, and the ego waits in its
// lane for both to pass.
inline Scenario only_the_gap_behind_the_follower() {
  Scenario s = open_road_scenario();
  s.ego.v = 10.0;
  s.leader() = {50.0, 10.0, 0.0};
  s.follower() = {5.0, 14.0, 0.0};  // at Krauss's safe gap: neither brakes
  s.target() = {25.0, 14.0, 0.0};
  validate_scenario(s);
  return s;
}

}  // namespace lanechange::testing
