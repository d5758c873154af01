// Our frame on a bent SUMO road, and back.
#include <gtest/gtest.h>

#include <cmath>

#include "sumo/road_frame.hpp"

namespace lanechange::sumo::detail {
namespace {

// A lane that runs along +x for 100 m, then turns 30 degrees to the left.
RoadFrame bent(Side side) {
  const double turn = M_PI / 6;
  return RoadFrame({{0, 0}, {100, 0}, {100 + 100 * std::cos(turn), 100 * std::sin(turn)}}, 3.5,
                   side);
}

TEST(RoadFrame, MapsToTheRoadAndBackOnEitherSide) {
  for (const Side side : {Side::Left, Side::Right}) {
    const RoadFrame frame = bent(side);
    for (const RoadPose pose : {RoadPose{-20, 1, 0.05}, RoadPose{40, 3.5, -0.1},
                                RoadPose{150, 0.5, 0.2}, RoadPose{260, 2, 0}}) {
      const RoadPose back = frame.to_road(frame.to_world(pose));
      EXPECT_NEAR(back.x, pose.x, 1e-9);
      EXPECT_NEAR(back.y, pose.y, 1e-9);
      EXPECT_NEAR(back.theta, pose.theta, 1e-9);
    }
  }
}

TEST(RoadFrame, TheTargetLaneLiesOnItsSide) {
  const WorldPose left_of_line{50, 3.5, 0};
  EXPECT_NEAR(bent(Side::Left).to_road(left_of_line).y, 3.5, 1e-12);
  EXPECT_NEAR(bent(Side::Right).to_road(left_of_line).y, -3.5, 1e-12);
  const RoadFrame frame = bent(Side::Left);
  EXPECT_EQ(frame.lane_at(0.4), Lane::Ego);
  EXPECT_EQ(frame.lane_at(3.0), Lane::Target);
  EXPECT_FALSE(frame.lane_at(-2.5).has_value());
  EXPECT_FALSE(frame.lane_at(5.5).has_value());
  // Past the bend, x keeps counting along the lane.
  const double turn = M_PI / 6;
  EXPECT_NEAR(frame.to_road({100 + 50 * std::cos(turn), 50 * std::sin(turn), turn}).x, 150, 1e-9);
}

}  // namespace
}  // namespace lanechange::sumo::detail
