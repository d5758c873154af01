#pragma once
// Co-simulation with SUMO (docs/sumo.md): SUMO drives every other car with
// its own car-following and lane-change models, reacting to the ego; a
// planner drives the ego through our ego model. Each 0.1 s step the planner
// sees the cars within a range on the ego lane and the target lane, as it
// does in our own simulator, and the rollout is judged by our judge.
//
// libsumo holds one simulation per process: run episodes one after another,
// or in separate processes.
#include <set>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/sim/simulator.hpp"

namespace lanechange::sumo {

/// A straight road whose network and traffic the code writes for SUMO.
struct HighwaySettings {
  int lanes = 2;              ///< the ego starts in `ego_lane` and changes to the lane on its left
  int ego_lane = 0;           ///< SUMO's lane index, 0 the rightmost
  double length = 2000.0;     ///< m: room for the traffic to settle ahead of and behind the ego
  double density = 20.0;      ///< cars per lane and km at the start; the inflow keeps it
  double speed_limit = 13.9;  ///< m/s (50 km/h): within the ego's speed limits of the paper
  int seed = 1;               ///< places the cars and seeds SUMO's driver imperfection
  double settle_time = 60.0;  ///< s of traffic before the ego enters: queues form and dissolve
  /// m along the road: the SUMO car of the ego lane nearest this point hands
  /// its place and speed to the ego, so the ego enters settled traffic.
  double ego_position = 600.0;
};

/// How the closed loop meets SUMO.
struct CoSimSettings {
  double range = 150.0;  ///< m from the ego along the road: the cars the planner sees
  /// s the lane keeper drives the ego in its lane before the change is
  /// asked: the cars around it react to it first.
  double request_after = 2.0;
  double duration = 0.0;  ///< s of rollout from the request; 0: horizon + closed_loop.settle_time
  /// The model planners predict SUMO's cars by: their speed kept, and Krauss
  /// following (traffic.followers_react), the model SUMO drives them by.
  Behavior prediction = Behavior::ConstantSpeed;
  /// When the change is asked, the ego also asks SUMO for it
  /// (Vehicle::changeLaneRelative), as a driver signals: SUMO's cars then
  /// cooperate with it as with one of their own that wants to change (SL2015:
  /// a car blocking the change slows to open the gap). SUMO never moves the
  /// ego; our ego model does. Off, SUMO's cars do not know of the change
  /// until the ego's body reaches their lane.
  bool signal_change = true;
  std::string work_dir;  ///< SUMO's input files and its own outputs go here
};

struct CoSimResult {
  sim::Rollout rollout;  ///< t = 0 at the request; our rollout format
  /// The rollout's cars: one per stay of a SUMO car in the ego or target lane
  /// within the range (a car that changes lanes has one track per lane).
  Scenario scene;
  int sumo_collisions = 0;  ///< SUMO's own collision reports naming the ego
  int scenes = 0;           ///< times the planner was handed a new scene (the cars around changed)
  std::vector<double> sumo_step_ms;  ///< per step: SUMO's share (moving the ego and stepping)
  double max_pose_error = 0.0;       ///< m: the largest distance between SUMO's ego and ours
  /// SUMO's cars that followed the ego (SUMO named it their leader) at some step.
  std::set<std::string> followers;
  /// m/s^2: the hardest braking of a car of `followers` while the ego led it,
  /// for any cause. The rollout's forced_decel counts only what the car's
  /// following of the ego demanded (docs/sumo.md).
  double follower_braking = 0.0;
};

/// Krauss's parameters of SUMO's cars, as a vehicle type sets them: SUMO's
/// passenger car unless a scenario gives its own.
struct SumoCarModel {
  double decel = 4.5;    ///< m/s^2: the braking its safe speed plans with (decel)
  double min_gap = 2.5;  ///< m: bumper to bumper on top of the safe-speed gap (minGap)
  double tau = 1.0;      ///< s: its reaction time (tau)
  bool operator==(const SumoCarModel&) const = default;
};

/// The car model of a CommonRoad interactive folder: the first vType of
/// NAME.add.xml (else of NAME.vehicles.rou.xml), SUMO's defaults for what it
/// leaves out. InputError naming the file and attribute for a value that is
/// not a positive number.
[[nodiscard]] SumoCarModel commonroad_car_model(const std::string& folder);

/// The config a SUMO run's planners plan with: SUMO's cars as SUMO drives
/// them. A car follows the ego once their bodies overlap (the sublane model,
/// traffic.sees_ego = overlapping) and by Krauss with `cars`' braking, gap
/// and reaction time (traffic.follow_decel, min_gap, reaction_time); the
/// rest of `config` as given.
[[nodiscard]] Config as_sumo_drives(Config config, const SumoCarModel& cars = {});

/// One episode on the built-in highway. InputError for settings out of range
/// (naming the setting); std::runtime_error where SUMO fails.
[[nodiscard]] CoSimResult run_highway(const planner::ClosedLoopPlanner& planner,
                                      const Config& config, const HighwaySettings& highway,
                                      const CoSimSettings& settings);

/// One episode of a CommonRoad interactive scenario folder (NAME.cr.xml,
/// NAME.net.xml, NAME.vehicles.rou.xml, NAME.add.xml): the ego starts at the
/// planning problem's initial state and is asked to change to the lane on
/// its left (to its right where it drives in the leftmost lane); SUMO moves
/// the recorded cars from their recorded starts. The folder is only read.
/// InputError naming the folder or file for a malformed one.
[[nodiscard]] CoSimResult run_commonroad(const planner::ClosedLoopPlanner& planner,
                                         const Config& config, const std::string& folder,
                                         const CoSimSettings& settings);

/// Checks the settings; InputError naming the first bad one.
void validate(const HighwaySettings& highway);
void validate(const CoSimSettings& settings);

}  // namespace lanechange::sumo
