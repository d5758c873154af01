#include "lanechange/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lanechange {
namespace {

struct Axis {
  double ux;
  double uy;
};

double half_extent_along(const OrientedBox& box, Axis axis) {
  const double c = std::cos(box.heading);
  const double s = std::sin(box.heading);
  return 0.5 * box.length * std::abs(c * axis.ux + s * axis.uy) +
         0.5 * box.width * std::abs(-s * axis.ux + c * axis.uy);
}

double overlap_along(const OrientedBox& a, const OrientedBox& b, Axis axis) {
  const double centre_distance = std::abs((b.x - a.x) * axis.ux + (b.y - a.y) * axis.uy);
  return half_extent_along(a, axis) + half_extent_along(b, axis) - centre_distance;
}

}  // namespace

double overlap_depth(const OrientedBox& a, const OrientedBox& b) {
  double depth = std::numeric_limits<double>::infinity();
  for (const OrientedBox* box : {&a, &b}) {
    const double c = std::cos(box->heading);
    const double s = std::sin(box->heading);
    depth = std::min(depth, overlap_along(a, b, {c, s}));
    depth = std::min(depth, overlap_along(a, b, {-s, c}));
  }
  return depth;
}

}  // namespace lanechange
