#include <gtest/gtest.h>

#include <algorithm>

#include "../foundation/test_helpers.hpp"
#include "lanechange/expert/gap_slots.hpp"

namespace lanechange {
namespace {

using expert::gap_features;
using expert::gap_slots;
using expert::kGapSlotBeside;
using expert::kOpenGapDistance;

// The value of the feature `name` in a scene's features.
double feature(const Scenario& s, const std::string& name) {
  const auto& names = expert::gap_feature_names();
  const auto at = std::find(names.begin(), names.end(), name);
  EXPECT_NE(at, names.end()) << name;
  return gap_features(s, gap_slots(s)).at(static_cast<std::size_t>(at - names.begin()));
}

TEST(GapSlots, BesideTheEgoLiesThePapersGapWithTheOthersAroundIt) {
  const Scenario s = testing::open_road_scenario();  // follower behind the ego, target ahead
  const expert::GapSlots slots = gap_slots(s);
  ASSERT_TRUE(slots.gaps[kGapSlotBeside].has_value());
  EXPECT_EQ(slots.slot_of(expert::paper_gap(s)), kGapSlotBeside);
  EXPECT_FALSE(slots.gaps[0].has_value());  // the lane has one gap behind the beside one
  ASSERT_TRUE(slots.gaps[1].has_value());
  EXPECT_EQ(slots.gaps[1]->car_ahead(), car_of(Role::Follower));
  EXPECT_FALSE(slots.gaps[1]->car_behind().has_value());
  ASSERT_TRUE(slots.gaps[3].has_value());
  EXPECT_EQ(slots.gaps[3]->car_behind(), car_of(Role::Target));
  EXPECT_FALSE(slots.gaps[4].has_value());
  // A gap framed by the same cars is the same slot, whatever else it lists.
  expert::Gap ahead_of_target;
  ahead_of_target.behind = {car_of(Role::Target)};
  EXPECT_EQ(slots.slot_of(ahead_of_target), 3);
}

TEST(GapSlots, InDenseTrafficEverySlotHoldsAGapInLaneOrder) {
  // Eight cars from 60 m behind, every 16 m: 4 at or behind the ego.
  const Scenario s = testing::dense_scenario(8);
  const expert::GapSlots slots = gap_slots(s);
  const std::vector<expert::Gap> lane = expert::target_lane_gaps(s, GapChoice::Best);
  for (int slot = 0; slot < expert::kGapSlots; ++slot) {
    ASSERT_TRUE(slots.gaps[static_cast<std::size_t>(slot)].has_value()) << slot;
    EXPECT_EQ(*slots.gaps[static_cast<std::size_t>(slot)],
              lane[static_cast<std::size_t>(slot + 2)]);
  }
  const expert::Gap& beside = *slots.gaps[kGapSlotBeside];
  EXPECT_LE(s.car(*beside.car_behind()).x, s.ego.x);
  EXPECT_GT(s.car(*beside.car_ahead()).x, s.ego.x);
  // The gaps at either end of the lane are beyond the slots.
  EXPECT_EQ(slots.slot_of(lane.front()), -1);
  EXPECT_EQ(slots.slot_of(lane.back()), -1);
}

TEST(GapSlots, FeaturesAreRelativeToTheEgoAndReadAMissingCarAsFarAway) {
  const Scenario s = testing::open_road_scenario();
  EXPECT_EQ(gap_features(s, gap_slots(s)).size(), expert::gap_feature_names().size());
  EXPECT_DOUBLE_EQ(feature(s, "gap_0_behind_dx"), s.follower().x - s.ego.x);
  EXPECT_DOUBLE_EQ(feature(s, "gap_0_ahead_dv"), s.target().v - s.ego.v);
  EXPECT_DOUBLE_EQ(feature(s, "lane_ahead_dx"), s.leader().x - s.ego.x);
  // The open ends of the lane, and a slot without a gap.
  EXPECT_DOUBLE_EQ(feature(s, "gap_m1_behind_dx"), -kOpenGapDistance);
  EXPECT_DOUBLE_EQ(feature(s, "gap_p1_ahead_dx"), kOpenGapDistance);
  EXPECT_DOUBLE_EQ(feature(s, "lane_behind_dx"), -kOpenGapDistance);
  EXPECT_DOUBLE_EQ(feature(s, "gap_p2_behind_dx"), kOpenGapDistance);
  EXPECT_DOUBLE_EQ(feature(s, "gap_p2_ahead_dx"), kOpenGapDistance);
  EXPECT_DOUBLE_EQ(feature(s, "gap_m2_ahead_dx"), -kOpenGapDistance);
}

}  // namespace
}  // namespace lanechange
