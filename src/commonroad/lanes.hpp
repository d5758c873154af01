#pragma once
// The lanes of a CommonRoad lanelet network and the frame along one of them:
// s along the lane's centre line, d across it (positive to the left).
#include <optional>
#include <set>
#include <vector>

#include "lanechange/commonroad/recording.hpp"

namespace lanechange::commonroad::detail {

struct Projection {
  double s = 0.0;        ///< along the centre line, m
  double d = 0.0;        ///< to the left of it, m
  double heading = 0.0;  ///< of the centre line there, rad
};

/// A centre line; positions beyond its ends project onto the end segments
/// extended.
class Polyline {
 public:
  explicit Polyline(const std::vector<Point>& points);
  [[nodiscard]] Projection project(Point p) const;
  /// The point `d` to the left of the line at `s` along it (beyond its ends,
  /// on the end segments extended), and the line's heading there: the
  /// inverse of project.
  [[nodiscard]] Projection place(double s, double d, Point& point) const;

 private:
  std::vector<Point> points_;
  std::vector<double> s_;  ///< arc length at each point
};

/// One lane: lanelets driven one after another, and their joint centre line.
struct LaneChain {
  std::vector<int> lanelets;
  Polyline centre;

  [[nodiscard]] bool holds(int lanelet) const;
};

class LaneNetwork {
 public:
  explicit LaneNetwork(const Recording& recording);

  /// The lanelet whose area holds p; the one whose centre is nearest where
  /// lanelets overlap at a joint. None off the road.
  [[nodiscard]] std::optional<int> lanelet_at(Point p) const;
  /// The lane through `lanelet`: its first predecessors back and first
  /// successors forward.
  [[nodiscard]] LaneChain lane_through(int lanelet) const;
  /// The neighbours of the lane's lanelets on one side, driven the same way.
  [[nodiscard]] std::set<int> neighbours(const LaneChain& lane, bool left) const;
  /// The lanelet's width (bound to bound) at its point pair nearest p.
  [[nodiscard]] double width_near(int lanelet, Point p) const;

 private:
  const Recording& recording_;
  std::vector<Polyline> centres_;             ///< of recording_.lanelets, in order
  std::vector<std::vector<Point>> outlines_;  ///< the same lanelets' areas, as rings
};

}  // namespace lanechange::commonroad::detail
