#pragma once
// A CommonRoad scenario file (format 2020a) as read: the lanelet network, the
// dynamic obstacles with their recorded states, and the planning problems
// (docs/recorded.md). Coordinates are the file's own (m, rad, s).
#include <optional>
#include <string>
#include <vector>

namespace lanechange::commonroad {

struct Point {
  double x = 0.0;
  double y = 0.0;
};

/// One state of an obstacle or a planning problem's initial state. Exact
/// values only; a quantity the file leaves out is 0 (acceleration, often).
struct State {
  int time_step = 0;
  Point position;
  double orientation = 0.0;
  double velocity = 0.0;
  double acceleration = 0.0;
};

struct Lanelet {
  int id = 0;
  /// Bounds as the driver sees them, in driving order, with equally many
  /// points (CommonRoad pairs them up).
  std::vector<Point> left;
  std::vector<Point> right;
  /// Neighbours driven in the same direction; an opposite one is left out.
  std::optional<int> adjacent_left;
  std::optional<int> adjacent_right;
  std::vector<int> predecessors;
  std::vector<int> successors;
};

/// A dynamic obstacle with a rectangular shape and its recorded states, the
/// initial state first and one per time step after it.
struct Obstacle {
  int id = 0;
  std::string type;  ///< CommonRoad's obstacle type: car, truck, bus, ...
  double length = 0.0;
  double width = 0.0;
  std::vector<State> states;

  /// The state at `time_step`, or none outside the record.
  [[nodiscard]] const State* at(int time_step) const;
};

struct PlanningProblem {
  int id = 0;
  State initial;
};

struct Recording {
  std::string benchmark_id;
  double time_step_size = 0.1;  ///< s per time step
  std::vector<Lanelet> lanelets;
  std::vector<Obstacle> obstacles;
  std::vector<PlanningProblem> planning_problems;

  [[nodiscard]] const Lanelet* lanelet(int id) const;
};

/// Reads a CommonRoad 2020a file with pugixml. Throws InputError naming the
/// file, the element and its line for a file that is not XML, not
/// CommonRoad 2020a, or holds something this reader does not take (an
/// obstacle that is not a rectangle, a prediction as an occupancy set, an
/// interval where an exact value is needed, bounds of unequal length, a
/// reference to a lanelet the file lacks).
[[nodiscard]] Recording read_recording(const std::string& path);
/// The same for XML text; `name` stands for the file in messages.
[[nodiscard]] Recording recording_from_text(const std::string& xml, const std::string& name);

}  // namespace lanechange::commonroad
