#include "commonroad/lanes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "lanechange/error.hpp"

namespace lanechange::commonroad::detail {
namespace {

double distance(Point a, Point b) { return std::hypot(b.x - a.x, b.y - a.y); }

Point midpoint(Point a, Point b) { return {(a.x + b.x) / 2.0, (a.y + b.y) / 2.0}; }

// The lanelet's outline: the left bound forward, the right bound back.
std::vector<Point> outline(const Lanelet& l) {
  std::vector<Point> ring(l.left);
  ring.insert(ring.end(), l.right.rbegin(), l.right.rend());
  return ring;
}

// Crossing number of p against an outline.
bool inside(const std::vector<Point>& ring, Point p) {
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Point a = ring[i];
    const Point b = ring[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) {
      in = !in;
    }
  }
  return in;
}

std::vector<Point> centre_points(const Lanelet& l) {
  std::vector<Point> c;
  c.reserve(l.left.size());
  for (std::size_t i = 0; i < l.left.size(); ++i) c.push_back(midpoint(l.left[i], l.right[i]));
  return c;
}

}  // namespace

Polyline::Polyline(const std::vector<Point>& points) {
  // Repeated points (where lanelets join) would make zero-length segments.
  for (const Point p : points) {
    if (points_.empty() || distance(points_.back(), p) > 1e-6) points_.push_back(p);
  }
  if (points_.size() < 2) throw std::invalid_argument("a centre line needs two distinct points");
  s_.push_back(0.0);
  for (std::size_t i = 1; i < points_.size(); ++i)
    s_.push_back(s_.back() + distance(points_[i - 1], points_[i]));
}

Projection Polyline::project(Point p) const {
  Projection best;
  double best_distance = std::numeric_limits<double>::infinity();
  const std::size_t last = points_.size() - 2;
  for (std::size_t i = 0; i <= last; ++i) {
    const Point a = points_[i];
    const Point b = points_[i + 1];
    const double length = s_[i + 1] - s_[i];
    const double ux = (b.x - a.x) / length;
    const double uy = (b.y - a.y) / length;
    double along = (p.x - a.x) * ux + (p.y - a.y) * uy;
    // The end segments reach on beyond the line's ends.
    if (i > 0) along = std::max(along, 0.0);
    if (i < last) along = std::min(along, length);
    const Point foot{a.x + along * ux, a.y + along * uy};
    const double dist = distance(p, foot);
    if (dist < best_distance) {
      best_distance = dist;
      best.s = s_[i] + along;
      best.d = ux * (p.y - a.y) - uy * (p.x - a.x);
      best.heading = std::atan2(uy, ux);
    }
  }
  return best;
}

Projection Polyline::place(double s, double d, Point& point) const {
  const auto after = std::upper_bound(s_.begin(), s_.end(), s);
  const auto from_start = std::max<std::ptrdiff_t>(after - s_.begin() - 1, 0);
  const std::size_t i = std::min(static_cast<std::size_t>(from_start), points_.size() - 2);
  const Point a = points_[i];
  const Point b = points_[i + 1];
  const double length = s_[i + 1] - s_[i];
  const double ux = (b.x - a.x) / length;
  const double uy = (b.y - a.y) / length;
  const double along = s - s_[i];
  point = {a.x + along * ux - d * uy, a.y + along * uy + d * ux};
  return {s, d, std::atan2(uy, ux)};
}

bool LaneChain::holds(int lanelet) const {
  return std::find(lanelets.begin(), lanelets.end(), lanelet) != lanelets.end();
}

LaneNetwork::LaneNetwork(const Recording& recording) : recording_(recording) {
  centres_.reserve(recording.lanelets.size());
  outlines_.reserve(recording.lanelets.size());
  for (const Lanelet& l : recording.lanelets) {
    outlines_.push_back(outline(l));
    try {
      centres_.emplace_back(centre_points(l));
    } catch (const std::invalid_argument&) {
      throw InputError(std::string("lanelet ") + std::to_string(l.id),
                       "its bounds enclose no length of road");
    }
  }
}

std::optional<int> LaneNetwork::lanelet_at(Point p) const {
  std::optional<int> best;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < recording_.lanelets.size(); ++i) {
    const Lanelet& l = recording_.lanelets[i];
    if (!inside(outlines_[i], p)) continue;
    const double d = std::abs(centres_[i].project(p).d);
    if (d < best_d) {
      best_d = d;
      best = l.id;
    }
  }
  return best;
}

LaneChain LaneNetwork::lane_through(int lanelet) const {
  std::vector<int> chain{lanelet};
  // A cycle of successors would never end; a lane visits a lanelet once.
  for (const Lanelet* l = recording_.lanelet(lanelet); l && !l->predecessors.empty();) {
    const int prev = l->predecessors.front();
    if (std::find(chain.begin(), chain.end(), prev) != chain.end()) break;
    chain.insert(chain.begin(), prev);
    l = recording_.lanelet(prev);
  }
  for (const Lanelet* l = recording_.lanelet(lanelet); l && !l->successors.empty();) {
    const int next = l->successors.front();
    if (std::find(chain.begin(), chain.end(), next) != chain.end()) break;
    chain.push_back(next);
    l = recording_.lanelet(next);
  }
  std::vector<Point> centre;
  for (const int id : chain) {
    const std::vector<Point> c = centre_points(*recording_.lanelet(id));
    centre.insert(centre.end(), c.begin(), c.end());
  }
  return {chain, Polyline(centre)};
}

std::set<int> LaneNetwork::neighbours(const LaneChain& lane, bool left) const {
  std::set<int> out;
  for (const int id : lane.lanelets) {
    const Lanelet& l = *recording_.lanelet(id);
    if (const auto n = left ? l.adjacent_left : l.adjacent_right) out.insert(*n);
  }
  return out;
}

double LaneNetwork::width_near(int lanelet, Point p) const {
  const Lanelet& l = *recording_.lanelet(lanelet);
  std::size_t nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < l.left.size(); ++i) {
    const double d = distance(midpoint(l.left[i], l.right[i]), p);
    if (d < best) {
      best = d;
      nearest = i;
    }
  }
  return distance(l.left[nearest], l.right[nearest]);
}

}  // namespace lanechange::commonroad::detail
