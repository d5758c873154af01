#pragma once
// Lane-change scenes cut out of a CommonRoad recording (docs/recorded.md):
// for each chosen ego and start time, a format-2 scene in the frame of the
// ego's lane, with every car of the ego lane and of the target lane within a
// range, each with its recorded body.
#include <map>
#include <string>
#include <vector>

#include "lanechange/commonroad/recording.hpp"
#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::commonroad {

/// Which egos the scenes are cut for.
enum class EgoChoice {
  PlanningProblems,  ///< each planning problem, at its initial state
  RecordedCars,      ///< recorded cars (all, or those of ImportSettings::cars)
};

struct ImportSettings {
  EgoChoice egos = EgoChoice::PlanningProblems;
  /// With RecordedCars: the obstacle ids to take; empty takes every car.
  std::vector<int> cars;
  /// With RecordedCars: seconds between the start times of one car's
  /// scenes, from its first recorded state.
  double every = 2.0;
  /// A recorded ego's scene needs this much record after its start, so
  /// that what its driver did next is known.
  double min_record_after = 5.0;
  /// Cars whose centre lies farther ahead or behind the ego (m, along the
  /// lane) are left out.
  double range = 100.0;
  /// Also cut scenes with the target lane to the right.
  bool right = false;
  /// Every car's behavior in the scene. Replay: each car moves as recorded,
  /// until its record ends or it leaves its lane, and on at its last speed.
  Behavior behavior = Behavior::Replay;
  /// The cars behind the ego follow IDM instead, so that a cut-in meets a
  /// car that answers it (a replayed car never brakes for the ego).
  bool reactive_behind = false;
  /// The ego's speed bound in the scene: highway traffic outruns the
  /// paper's urban bound.
  double max_speed = 120.0 / 3.6;
};

struct ImportedScene {
  std::string name;  ///< file stem: recording, ego, start step, side
  Scenario scene;
};

struct ImportReport {
  std::vector<ImportedScene> scenes;
  /// Start points that gave no scene, counted by reason.
  std::map<std::string, int> skipped;
};

/// Cuts the scenes. The scene's x is along the ego lane's centre line from
/// the ego (ego.x = 0), its y across it; the cars of the ego lane and of the
/// adjacent lane on the target side keep their recorded speeds along the
/// lane and their bodies. A start point whose scene would not validate (the
/// ego off the road, cars that overlap as projected) is skipped and counted.
[[nodiscard]] ImportReport import_scenes(const Recording& recording, const Config& defaults,
                                         const ImportSettings& settings);

}  // namespace lanechange::commonroad
