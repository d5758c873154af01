// Replayed cars: they move exactly as recorded in the closed loop, and no
// planner ever sees their records.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "commonroad_fixture.hpp"
#include "lanechange/commonroad/import.hpp"
#include "lanechange/error.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/traffic.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

// The fixture's planning problem: cars 2 and 5 in the ego lane, 3 and 4 in
// the lane to its left, every one replayed.
Scenario replayed_scene() {
  const auto report = commonroad::import_scenes(
      commonroad::recording_from_text(testing::two_lane_commonroad(0.3), "two.xml"), Config{}, {});
  return report.scenes.at(0).scene;
}

TEST(ReplayedCars, EveryImportedCarCarriesItsRecordFromTheStart) {
  const Scenario s = replayed_scene();
  EXPECT_EQ(s.behavior, Behavior::Replay);
  for (const OtherCar& car : s.cars) {
    EXPECT_EQ(car.behavior, Behavior::Replay) << car.id;
    ASSERT_TRUE(car.record.has_value()) << car.id;
    EXPECT_NEAR(car.record->x.front(), car.state.x, 1e-9);
  }
  // Car 5 leaves the ego lane at step 25: its record ends there.
  EXPECT_EQ(s.cars.at(*s.find("5")).record->x.size(), 25u);
  EXPECT_EQ(s.cars.at(*s.find("2")).record->x.size(), 61u);
}

TEST(ReplayedCars, MoveExactlyAsRecordedInTheClosedLoop) {
  const Scenario s = replayed_scene();
  const auto keep_lane = planner::make_planner("keep-lane", testing::untimed_config());
  const sim::Rollout r = sim::simulate(s, *keep_lane, testing::untimed_config());
  const auto& others = r.trajectory.others;
  for (CarIndex c = 0; c < s.car_count(); ++c) {
    const RecordedTrack& record = *s.cars[c].record;
    ASSERT_GT(others.car(c).x.size(), 30u);
    for (std::size_t k = 0; k < others.car(c).x.size(); ++k) {
      const CarState expected = record.at(static_cast<double>(k) * others.dt);
      ASSERT_NEAR(others.car(c).x[k], expected.x, 1e-9) << s.cars[c].id << " node " << k;
      ASSERT_NEAR(others.car(c).v[k], expected.v, 1e-9) << s.cars[c].id << " node " << k;
    }
  }
  // Past the end of its record car 5 drives on at its last speed.
  const CarIndex five = *s.find("5");
  const RecordedTrack& r5 = *s.cars[five].record;
  EXPECT_NEAR(others.car(five).x[30] - r5.x.back(), r5.v.back() * 0.6, 1e-9);
}

// Sees what a planner sees, and keeps the lane.
class Peeking final : public planner::ClosedLoopPlanner {
 public:
  explicit Peeking(int* records_seen) : records_seen_(records_seen) {}
  [[nodiscard]] std::string_view name() const override { return "peeking"; }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(
      const Scenario& scene) const override {
    count(scene);
    return std::make_unique<Session>(this);
  }

 private:
  struct Session final : planner::PlannerSession {
    explicit Session(const Peeking* p) : owner(p) {}
    planner::Decision act(const planner::Observation& o) override {
      owner->count(*o.scene);
      return {{0.0, 0.0}, planner::ActStatus::Planned, ""};
    }
    const Peeking* owner;
  };
  void count(const Scenario& scene) const {
    for (const OtherCar& car : scene.cars)
      *records_seen_ += car.record || car.behavior == Behavior::Replay ? 1 : 0;
  }
  int* records_seen_;
};

TEST(ReplayedCars, NoPlannerSeesARecord) {
  const Scenario s = replayed_scene();
  int records_seen = 0;
  const Peeking peeking(&records_seen);
  (void)sim::simulate(s, peeking, testing::untimed_config());
  EXPECT_EQ(records_seen, 0);
  // A prediction made from the scene itself ignores the records too: car 5
  // would be predicted into the other lane's speed profile otherwise.
  Config config;
  config.traffic.followers_react = false;
  const TrafficPrediction p = predict_traffic(s, config, 20, 0.1);
  const CarIndex two = *s.find("2");
  EXPECT_NEAR(p.car(two).x[20], s.car(two).x + s.car(two).v * 2.0, 1e-9);
  const Scenario view = planning_view(s, config.traffic);
  EXPECT_EQ(view.behavior, Behavior::ConstantSpeed);
  EXPECT_FALSE(view.cars[two].record.has_value());
}

TEST(ReplayedCars, TheRecordIsReadAsStrictlyAsTheRest) {
  const Scenario s = replayed_scene();
  const auto refused_field = [](nlohmann::json j) -> std::string {
    try {
      (void)scenario_from_json(j, Config{});
    } catch (const InputError& e) {
      return e.field();
    }
    return "";
  };
  nlohmann::json j = scenario_to_json(s);
  EXPECT_EQ(scenario_to_json(scenario_from_json(j, Config{})), j);
  j["cars"][0]["record"]["x"][0] = j["cars"][0]["x"].get<double>() + 1.0;
  EXPECT_EQ(refused_field(j), "cars[0].record.x[0]");
  j = scenario_to_json(s);
  j["cars"][1]["record"]["v"].push_back(3.0);
  EXPECT_EQ(refused_field(j), "cars[1].record.v");
  j = scenario_to_json(s);
  j["cars"][0].erase("record");
  EXPECT_EQ(refused_field(j), "cars[0].record");
  j = scenario_to_json(s);
  j["cars"][0]["behavior"] = "idm";
  EXPECT_EQ(refused_field(j), "cars[0].record");
  nlohmann::json paper = testing::example_scenario_json();
  paper["behavior"] = "replay";
  EXPECT_EQ(refused_field(paper), "behavior");
}

}  // namespace
}  // namespace lanechange
