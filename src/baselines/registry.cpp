#include <algorithm>
#include <array>

#include "baselines/dwa.hpp"
#include "baselines/lattice.hpp"
#include "baselines/mpc.hpp"
#include "lanechange/baselines/baselines.hpp"
#include "lanechange/error.hpp"

namespace lanechange::baselines {

namespace {

using Factory = std::shared_ptr<const planner::ClosedLoopPlanner> (*)(const Config&);

struct Entry {
  std::string_view name;
  Factory make;
};

// One line per baseline, in the order docs/baselines.md lists them.
constexpr std::array<Entry, 3> kBaselines{{
    {"mpc", make_mpc_planner},
    {"dwa", make_dwa_planner},
    {"lattice", make_lattice_planner},
}};

}  // namespace

std::vector<std::string> baseline_names() {
  std::vector<std::string> names;
  names.reserve(kBaselines.size());
  for (const auto& entry : kBaselines) names.emplace_back(entry.name);
  return names;
}

std::vector<std::string> planner_names() {
  auto names = planner::planner_names();
  for (auto& name : baseline_names()) names.push_back(std::move(name));
  return names;
}

std::shared_ptr<const planner::ClosedLoopPlanner> make_planner(std::string_view name,
                                                               const Config& config,
                                                               const std::string& model_dir) {
  for (const auto& entry : kBaselines) {
    if (entry.name == name) return entry.make(config);
  }
  const auto ours = planner::planner_names();
  if (std::find(ours.begin(), ours.end(), name) != ours.end()) {
    return planner::make_planner(name, config, model_dir);
  }
  std::string known;
  for (const auto& n : planner_names()) {
    if (!known.empty()) known += ", ";
    known += n;
  }
  std::string problem = "unknown planner \"";
  problem += name;
  problem += "\" (known: ";
  problem += known;
  problem += ")";
  throw InputError("--planner", problem);
}

}  // namespace lanechange::baselines
