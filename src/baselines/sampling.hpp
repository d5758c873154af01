#pragma once
// What the sampling baselines (dwa, lattice) share: the cars predicted from an
// observation, and the checks a sampled ego path must pass against them.
#include <span>

#include "lanechange/config.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::baselines {

/// Whether the lane change is still on: within the scene's horizon (the time
/// the scene asks the change to happen in, as the expert's t_f), or once the
/// ego's body has entered the target lane. A change begun later could not
/// finish before the run is judged.
[[nodiscard]] bool lane_change_on(const planner::Observation& observation);

/// The cars as their behavior predicts them from their current states, over
/// `steps` steps of the scene's dt. The ego is taken to hold its lane and
/// speed (predict_traffic): one prediction serves every candidate, so an IDM
/// follower is not expected to brake for a candidate that cuts in.
[[nodiscard]] TrafficPrediction predict_from(const planner::Observation& observation,
                                             const Config& config, int steps);

/// The smallest separation over the path's nodes between the ego's box and
/// the cars' boxes at the same nodes (m; a lower bound on the gap, negative
/// in contact). Separations above `cap` are reported as `cap`: far cars are
/// not measured, which keeps the check cheap.
[[nodiscard]] double min_separation(std::span<const EgoState> path, const TrafficPrediction& cars,
                                    const Scenario& scene, double cap);

/// Eq. 1's safe distances (scene.safe_distance) to every car of the target
/// lane at every node (from node 1: the present cannot change) where the
/// ego's body reaches into that lane: ahead, standstill + headway x ego
/// speed; behind, standstill + headway x that car's speed; centre to centre.
/// Either side of each car will do, as the expert's gap choice allows.
[[nodiscard]] bool keeps_target_lane_distances(std::span<const EgoState> path,
                                               const TrafficPrediction& cars,
                                               const Scenario& scene);

}  // namespace lanechange::baselines
