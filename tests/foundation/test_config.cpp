#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "lanechange/config.hpp"
#include "lanechange/error.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

TEST(Config, SaveAndLoadRoundTrip) {
  testing::TempDir dir;
  Config c = make_preset("authors");
  c.expert.steps = 40;
  c.safety.follower.time_headway = 1.25;
  c.expert.lane_rule = LaneRule::EitherOr;
  save_config(c, dir.file("c.json"));
  const Config loaded = load_config(dir.file("c.json"));
  EXPECT_EQ(nlohmann::json(loaded), nlohmann::json(c));
  EXPECT_EQ(loaded.expert.steps, 40);
  EXPECT_EQ(loaded.expert.lane_rule, LaneRule::EitherOr);
}

// Data sets and models are matched on the expert's part of the config: a
// planner setting may change (or be added) without orphaning them.
TEST(Config, ExpertDataConfigLeavesOutThePlannersOwnSections) {
  Config base;
  Config tuned = base;
  tuned.strategy_qp.candidates = 9;
  tuned.mpc.max_iterations += 1;
  tuned.dwa.accel_samples += 2;
  EXPECT_NE(nlohmann::json(tuned), nlohmann::json(base));
  EXPECT_EQ(expert_data_config(nlohmann::json(tuned)), expert_data_config(nlohmann::json(base)));
  Config other_expert = base;
  other_expert.expert.steps = 40;
  EXPECT_NE(expert_data_config(nlohmann::json(other_expert)),
            expert_data_config(nlohmann::json(base)));
  EXPECT_FALSE(expert_data_config(nlohmann::json(base)).contains("strategy_qp"));
  EXPECT_TRUE(expert_data_config(nlohmann::json(base)).contains("closed_loop"));
}

TEST(Config, GlobalisationRoundTripsThroughJson) {
  const Config c = config_from_json(nlohmann::json::parse(
      R"({"expert": {"globalisation": "off", "trust_radius": 0.75, "trust_shrink": 0.25,
                     "trust_rounds": 4}})"));
  EXPECT_EQ(c.expert.globalisation, Globalisation::Off);
  EXPECT_DOUBLE_EQ(c.expert.trust_radius, 0.75);
  EXPECT_DOUBLE_EQ(c.expert.trust_shrink, 0.25);
  EXPECT_EQ(c.expert.trust_rounds, 4);
  const nlohmann::json written = c;
  EXPECT_EQ(written["expert"]["globalisation"], "off");
  EXPECT_EQ(nlohmann::json(config_from_json(written)), written);
  EXPECT_EQ(Config{}.expert.globalisation, Globalisation::TrustRegion);
  // The authors' code has no globalisation: its preset keeps their verdicts.
  EXPECT_EQ(make_preset("authors").expert.globalisation, Globalisation::Off);
}

TEST(Config, TheTrafficCapIsOptional) {
  const Config none = config_from_json(nlohmann::json::parse(R"({"traffic_max_speed": null})"));
  EXPECT_FALSE(none.traffic_max_speed.has_value());
  const nlohmann::json written = none;
  EXPECT_TRUE(written["traffic_max_speed"].is_null());
  EXPECT_FALSE(config_from_json(written).traffic_max_speed.has_value());
  const Config fast = config_from_json(nlohmann::json::parse(R"({"traffic_max_speed": 36.1})"));
  EXPECT_DOUBLE_EQ(fast.traffic_max_speed.value_or(0.0), 36.1);
}

TEST(Config, PartialFileStartsFromItsPreset) {
  const Config c = config_from_json(
      nlohmann::json::parse(R"({"preset": "authors", "expert": {"max_iterations": 3}})"));
  EXPECT_EQ(c.expert.max_iterations, 3);
  EXPECT_EQ(c.expert.lane_rule, LaneRule::Footprint);  // from the authors preset
  EXPECT_DOUBLE_EQ(c.safety.leader.time_headway, 3.0);
}

TEST(Config, PaperDefaultsFollowNotes) {
  const Config c;
  EXPECT_EQ(c.expert.steps, 50);
  EXPECT_DOUBLE_EQ(c.expert.horizon, 5.0);
  EXPECT_DOUBLE_EQ(c.dt(), 0.1);
  EXPECT_DOUBLE_EQ(c.expert.weight_accel, 0.5);
  EXPECT_DOUBLE_EQ(c.expert.weight_jerk, 100.0);
  EXPECT_DOUBLE_EQ(c.expert.weight_lateral, 1.0);
  EXPECT_EQ(c.expert.lane_rule, LaneRule::Footprint);  // NOTES.md: the body decides
  EXPECT_DOUBLE_EQ(c.lane_width, 3.75);
  EXPECT_NEAR(c.limits.v.hi, 60.0 / 3.6, 1e-12);
}

TEST(Config, RejectsUnknownKeysAndBadValuesByName) {
  auto field_of = [](const char* text) {
    try {
      (void)config_from_json(nlohmann::json::parse(text));
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("<accepted>");
  };
  EXPECT_EQ(field_of(R"({"expert": {"stepz": 3}})"), "expert.stepz");
  EXPECT_EQ(field_of(R"({"lane_width": -1})"), "lane_width");
  EXPECT_EQ(field_of(R"({"limits": {"a": [2, -2]}})"), "limits.a");
  EXPECT_EQ(field_of(R"({"expert": {"lane_rule": "sideways"}})"), "expert.lane_rule");
  EXPECT_EQ(field_of(R"({"expert": {"globalisation": "hope"}})"), "expert.globalisation");
  EXPECT_EQ(field_of(R"({"expert": {"trust_radius": 0}})"), "expert.trust_radius");
  EXPECT_EQ(field_of(R"({"expert": {"trust_shrink": 1}})"), "expert.trust_shrink");
  EXPECT_EQ(field_of(R"({"expert": {"trust_rounds": 0}})"), "expert.trust_rounds");
  EXPECT_EQ(field_of(R"({"expert": {"min_turn_radius": -5}})"), "expert.min_turn_radius");
  EXPECT_EQ(field_of(R"({"expert": {"min_turn_radius": 5}})"), "<accepted>");
  EXPECT_EQ(field_of(R"({"preset": "nobody"})"), "preset");
  EXPECT_EQ(field_of(R"({"traffic_max_speed": 0})"), "traffic_max_speed");
  EXPECT_EQ(field_of(R"({"closed_loop": {"keeper_rear_horizon": -1}})"),
            "closed_loop.keeper_rear_horizon");
  EXPECT_EQ(field_of(R"({"closed_loop": {"keeper_backout_heading": 0}})"),
            "closed_loop.keeper_backout_heading");
  EXPECT_EQ(field_of(R"({"closed_loop": {"keeper_backout_heading": 2}})"),
            "closed_loop.keeper_backout_heading");
  EXPECT_EQ(field_of(R"({"traffic_max_speed": "none"})"), "traffic_max_speed");
  EXPECT_EQ(field_of(R"({"idm": {"max_accel": "fast"}})"), "idm.max_accel");
  EXPECT_EQ(field_of(R"({"expert": {"cycle_tolerance": -1e-3}})"), "expert.cycle_tolerance");
  EXPECT_EQ(field_of(R"({"expert": {"cycle_tolerance": 0}})"), "<accepted>");
}

}  // namespace
}  // namespace lanechange
