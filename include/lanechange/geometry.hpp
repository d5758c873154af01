#pragma once
// Cars as rectangles in the road plane. The ego turns, so its box is
// oriented; the other cars keep their lanes and are boxes with heading 0.

namespace lanechange {

struct OrientedBox {
  double x = 0.0;        ///< centre, m
  double y = 0.0;        ///< centre, m
  double heading = 0.0;  ///< rad, from the x axis
  double length = 0.0;   ///< along the heading, m
  double width = 0.0;    ///< across the heading, m
};

/// The separating-axis measure: the smallest overlap of the two boxes'
/// projections over the four edge normals. Positive means the boxes
/// interpenetrate, zero that they touch, negative that a gap separates them
/// (and then its magnitude is a lower bound on the gap).
[[nodiscard]] double overlap_depth(const OrientedBox& a, const OrientedBox& b);

/// Closed boxes: touching counts as a collision, as any contact would.
[[nodiscard]] inline bool boxes_collide(const OrientedBox& a, const OrientedBox& b) {
  return overlap_depth(a, b) >= 0.0;
}

}  // namespace lanechange
