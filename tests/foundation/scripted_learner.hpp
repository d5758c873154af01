#pragma once
// mlp-miqp with its learned parts scripted: the tests of the hierarchy and of
// DAgger drive it with a known "network" and a forced scene class.
#include <functional>
#include <memory>
#include <utility>

#include "lanechange/expert/lane_change_solver.hpp"
#include "planner/mlp_miqp_planner.hpp"

namespace lanechange::testing {

/// A "network" that drives by the observation alone.
using ScriptedDrive = std::function<EgoControl(const planner::Observation&)>;

/// The classifier answers `label` for every scene and names the paper's gap
/// (between the follower and the target, where the scene has them).
/// `reads_roles`: the network reads the paper's three cars, else any gap.
inline planner::MlpMiqpPlanner scripted_learner(
    const Config& config, Label label, ScriptedDrive drive,
    std::shared_ptr<const expert::LaneChangeSolver> solver =
        std::make_shared<expert::FastLaneChangeSolver>(),
    bool reads_roles = true) {
  const auto classify = [label](const Scenario& s) {
    planner::MlpMiqpPlanner::SceneChoice choice{label != Label::Failure, {}};
    if (s.has_every_role()) choice.gap = {s.index_of(Role::Follower), s.index_of(Role::Target)};
    return choice;
  };
  auto network = [drive = std::move(drive)](const planner::Observation& o,
                                            const expert::GapFrame& /*gap*/) { return drive(o); };
  return {config, classify, std::move(network), std::move(solver), "mlp-miqp", reads_roles};
}

}  // namespace lanechange::testing
