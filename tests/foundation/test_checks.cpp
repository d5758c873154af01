#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lanechange/checks.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

constexpr double kW = 3.75;

std::vector<double> smooth_lane_change(double overshoot = 0.0) {
  std::vector<double> y;
  for (int k = 0; k <= 50; ++k) {
    const double s = k / 50.0;
    y.push_back(kW * (10 * std::pow(s, 3) - 15 * std::pow(s, 4) + 6 * std::pow(s, 5)) +
                overshoot * std::sin(std::numbers::pi * s));
  }
  return y;
}

TEST(Labeller, SmoothLaneChangeIsWellPosed) {
  const Labelled l = label_trajectory(smooth_lane_change(), 0.0, kW, LabelTolerances{});
  EXPECT_EQ(l.label, Label::WellPosed) << l.reason;
}

TEST(Labeller, RippleWithinToleranceIsWellPosedButAReversalIsNot) {
  std::vector<double> y = smooth_lane_change();
  y[40] = y[39] - 0.03;  // 3 cm ripple
  EXPECT_EQ(label_trajectory(y, 0.0, kW, LabelTolerances{}).label, Label::WellPosed);
  LabelTolerances strict;
  strict.reversal = 0.02;
  EXPECT_EQ(label_trajectory(y, 0.0, kW, strict).label, Label::IllPosed);
  std::vector<double> back = smooth_lane_change();
  back[45] = kW - 0.5;  // swerves half a metre back towards its old lane
  const Labelled l = label_trajectory(back, 0.0, kW, LabelTolerances{});
  EXPECT_EQ(l.label, Label::IllPosed);
  EXPECT_NE(l.reason.find("back"), std::string::npos);
  EXPECT_NEAR(largest_lateral_reversal(back), back[44] - back[45], 1e-12);
}

TEST(Labeller, OvershootThatSettlesOnTheCentreIsNotAReversal) {
  // 30 cm past the lane centre, then back onto it: lane keeping, not a
  // move back towards the old lane, unless the literal reading is asked for.
  std::vector<double> y = smooth_lane_change();
  for (int k = 30; k <= 40; ++k) y[k] = kW + 0.3 * std::sin(std::numbers::pi * (k - 30) / 10.0);
  for (int k = 41; k <= 50; ++k) y[k] = kW;
  EXPECT_EQ(label_trajectory(y, 0.0, kW, LabelTolerances{}).label, Label::WellPosed);
  EXPECT_NEAR(largest_lateral_reversal(y, kW), 0.0, 1e-12);
  LabelTolerances literal;
  literal.reference = ReversalReference::RunningMax;
  EXPECT_EQ(label_trajectory(y, 0.0, kW, literal).label, Label::IllPosed);
  // Dropping below the centre after the overshoot still counts.
  y[45] = kW - 0.2;
  EXPECT_EQ(label_trajectory(y, 0.0, kW, LabelTolerances{}).label, Label::IllPosed);
}

TEST(Labeller, LargeFinalHeadingIsIllPosed) {
  const Labelled l =
      label_trajectory(smooth_lane_change(), 11.0 * M_PI / 180.0, kW, LabelTolerances{});
  EXPECT_EQ(l.label, Label::IllPosed);
  EXPECT_EQ(
      label_trajectory(smooth_lane_change(), -9.0 * M_PI / 180.0, kW, LabelTolerances{}).label,
      Label::WellPosed);
}

TEST(Labeller, NotReachingTheTargetLaneIsFailure) {
  std::vector<double> y = smooth_lane_change();
  for (double& v : y) v *= 0.5;
  EXPECT_EQ(label_trajectory(y, 0.0, kW, LabelTolerances{}).label, Label::Failure);
  EXPECT_EQ(label_trajectory({}, 0.0, kW, LabelTolerances{}).label, Label::Failure);
  y.back() = std::nan("");
  EXPECT_EQ(label_trajectory(y, 0.0, kW, LabelTolerances{}).label, Label::Failure);
}

TEST(Collision, FindsTheFirstContactWithAPredictedCar) {
  Scenario s = scenario_from_json(testing::example_scenario_json(), Config{});
  s.leader() = {20.0, 0.0, 0.0};  // a stopped car 20 m ahead in the ego lane
  const TrafficPrediction others = predict_traffic(s, Config{}, 20, 0.1);
  std::vector<EgoState> ego;
  for (int k = 0; k <= 20; ++k) ego.push_back({10.0 * k * 0.1, 0.0, 10.0, 0.0, 0.0});
  // The bumpers touch once the ego has covered 20 - 4.4 = 15.6 m: after 1.56 s.
  const auto hit = first_collision(ego, others, s);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->car, car_of(Role::Leader));
  EXPECT_NEAR(hit->time, 1.575, 0.03);
  // The same drive in the other lane misses the leader and the target-lane cars.
  s.follower() = {-50.0, 0.0, 0.0};
  s.target() = {60.0, 0.0, 0.0};
  const TrafficPrediction clear = predict_traffic(s, Config{}, 20, 0.1);
  for (auto& e : ego) e.y = s.lane_width;
  EXPECT_FALSE(first_collision(ego, clear, s).has_value());
}

TEST(Collision, ACarsOwnSizeDecidesContact) {
  Scenario s = scenario_from_json(testing::example_scenario_json(), Config{});
  s.leader() = {20.0, 0.0, 0.0};
  s.cars[car_of(Role::Leader)].size = VehicleSize{12.0, 2.5};  // a truck
  const TrafficPrediction others = predict_traffic(s, Config{}, 20, 0.1);
  std::vector<EgoState> ego;
  for (int k = 0; k <= 20; ++k) ego.push_back({10.0 * k * 0.1, 0.0, 10.0, 0.0, 0.0});
  // Centres 0.5 (4.4 + 12) = 8.2 m apart at contact: after 1.18 s, not 1.56 s.
  const auto hit = first_collision(ego, others, s);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->time, 1.18, 0.03);
  // Passing beside it, off its lane's centre: a wider body reaches further.
  const double beside = 0.5 * (s.vehicle.width + 2.5) - 0.05;
  for (auto& e : ego) e.y = beside;
  EXPECT_TRUE(first_collision(ego, others, s).has_value());
  s.cars[car_of(Role::Leader)].size.reset();
  EXPECT_FALSE(first_collision(ego, predict_traffic(s, Config{}, 20, 0.1), s).has_value());
}

}  // namespace
}  // namespace lanechange
