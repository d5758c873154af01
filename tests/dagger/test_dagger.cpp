#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "dagger/collect.hpp"
#include "lanechange/dagger/dagger.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "lanechange/learn/learn_data.hpp"
#include "lanechange/learn/model.hpp"
#include "lanechange/learn/train.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sim/simulator.hpp"
#include "scripted_learner.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

namespace fs = std::filesystem;

Config small_config() {
  Config c = testing::untimed_config();
  c.expert.steps = 20;
  return c;
}

// A learner whose "network" always asks for the same control, and whose
// classifier always says `label`.
planner::MlpMiqpPlanner constant_learner(const Config& config, EgoControl u,
                                         Label label = Label::WellPosed) {
  return testing::scripted_learner(config, label, [u](const planner::Observation&) { return u; });
}

// The lines of a CSV file, split into cells (our tables quote nothing).
std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

// Each query is the expert's plan from a state the network drove to: one
// node, at the rollout's time, starting where the ego was.
TEST(Dagger, TheExpertLabelsTheStatesTheNetworkVisits) {
  const Config config = small_config();
  const planner::MlpMiqpPlanner learner = constant_learner(config, {0.0, 0.05});
  const Scenario scene = testing::open_road_scenario();
  const int stride = 3;
  const auto queries = dagger::detail::collect_scene(scene, learner, config, {stride, 1, 60.0});
  ASSERT_GE(queries.size(), 3U);
  const double dt = scene.horizon / scene.steps;
  bool some_plan = false;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const Trajectory& path = queries[i].outcome.trajectory;
    if (path.nodes() == 0) continue;
    some_plan = true;
    ASSERT_EQ(path.nodes(), 1);
    EXPECT_NEAR(path.t[0], double(i * stride) * dt, 1e-9);
    EXPECT_TRUE(std::isfinite(path.controls[0].a));
  }
  EXPECT_TRUE(some_plan);
  // The network steers left from the start, so the second query starts off
  // the ego lane's centre: a visited state, not the scene's start.
  ASSERT_GT(queries[1].outcome.trajectory.nodes(), 0);
  EXPECT_GT(queries[1].outcome.trajectory.ego[0].y, scene.ego.y + 1e-3);
}

// With more nodes kept, each query carries the expert's plan on from the
// visited state, on the rollout's clock.
TEST(Dagger, KeptNodesFollowTheVisitedStateOnTheRolloutsClock) {
  const Config config = small_config();
  const planner::MlpMiqpPlanner learner = constant_learner(config, {0.0, 0.0});
  const Scenario scene = testing::open_road_scenario();
  const double dt = scene.horizon / scene.steps;
  const auto one = dagger::detail::collect_scene(scene, learner, config, {4, 1, 60.0});
  const auto four = dagger::detail::collect_scene(scene, learner, config, {4, 4, 60.0});
  ASSERT_EQ(one.size(), four.size());
  ASSERT_GE(four.size(), 2U);
  const Trajectory& a = one[1].outcome.trajectory;
  const Trajectory& b = four[1].outcome.trajectory;
  ASSERT_EQ(a.nodes(), 1);
  ASSERT_EQ(b.nodes(), 4);
  EXPECT_EQ(b.ego[0].x, a.ego[0].x);
  EXPECT_EQ(b.controls[0].a, a.controls[0].a);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(b.t[k], (4 + k) * dt, 1e-9);
  EXPECT_GT(b.ego[3].x, b.ego[0].x);
}

// With the strategy fixed, every well-posed label keeps the lane modes of
// the expert's plan from the scene's start, shifted to its step. The learner
// replays that plan's controls, so those modes stay feasible on its way.
TEST(Dagger, FixedStrategyLabelsKeepTheExpertsLaneModes) {
  const Config config = small_config();
  const Scenario scene = testing::open_road_scenario();
  const double dt = scene.horizon / scene.steps;
  const planner::MlpMiqpPlanner planning = constant_learner(config, {0.0, 0.0});
  const expert::ExpertResult start = planning.expert().plan(scene);
  ASSERT_EQ(start.status, expert::PlanStatus::Converged);
  const planner::MlpMiqpPlanner learner =
      testing::scripted_learner(config, Label::WellPosed, [&start](const planner::Observation& o) {
        const auto k = std::min(static_cast<std::size_t>(o.step), start.path.controls.size() - 1);
        return EgoControl{start.path.controls[k](0), start.path.controls[k](1)};
      });
  dagger::detail::Labelling labelling{4, 0, 60.0};
  labelling.fixed_strategy = true;
  const auto queries = dagger::detail::collect_scene(scene, learner, config, labelling);
  int compared = 0;
  for (const auto& q : queries) {
    if (q.outcome.label != Label::WellPosed) continue;
    const auto step = static_cast<std::size_t>(std::lround(q.outcome.trajectory.t[0] / dt));
    const auto& lanes = q.outcome.lane_modes;
    for (std::size_t k = 1; k < lanes.size() && k + step < start.occupancy.size(); ++k) {
      ASSERT_TRUE(start.occupancy[k + step].has_value());
      EXPECT_EQ(lanes[k], static_cast<int>(*start.occupancy[k + step])) << "step " << step;
      ++compared;
    }
  }
  EXPECT_GT(compared, 10);

  // Driven straight on, the ego falls behind that plan's lane change and its
  // modes no longer hold: the free search labels those states instead.
  const planner::MlpMiqpPlanner straight = constant_learner(config, {0.0, 0.0});
  const auto well_posed = [](const std::vector<dagger::detail::Query>& all) {
    return std::count_if(all.begin(), all.end(),
                         [](const auto& q) { return q.outcome.label == Label::WellPosed; });
  };
  const auto fixed = dagger::detail::collect_scene(scene, straight, config, labelling);
  labelling.fixed_strategy = false;
  const auto free = dagger::detail::collect_scene(scene, straight, config, labelling);
  ASSERT_EQ(fixed.size(), free.size());
  EXPECT_EQ(well_posed(fixed), well_posed(free));
  EXPECT_GT(well_posed(free), 0);
}

// Gated (HG-DAgger), the learner is mlp-miqp: the labels are the bare
// rollout's up to the take-over, plus the take-over's own state, and none
// from the states the expert drives afterwards.
TEST(Dagger, GatedLabelsEndAtTheTakeOver) {
  const Config config = small_config();
  const planner::MlpMiqpPlanner learner = constant_learner(config, {0.0, 0.05});
  const Scenario scene = testing::open_road_scenario();
  const sim::Rollout gated_run = sim::simulate(scene, learner, config);
  const auto first_takeover = std::find_if(
      gated_run.steps.begin(), gated_run.steps.end(),
      [](const sim::StepRecord& r) { return r.status == planner::ActStatus::TookOver; });
  ASSERT_NE(first_takeover, gated_run.steps.end()) << "the test needs a take-over";
  const auto takeover_step = static_cast<int>(first_takeover - gated_run.steps.begin());
  const int stride = 3;
  const auto bare = dagger::detail::collect_scene(scene, learner, config, {stride, 1, 60.0});
  const auto gated =
      dagger::detail::collect_scene(scene, learner, config, {stride, 1, 60.0, false, true});
  const int before = (takeover_step + stride - 1) / stride;  // stride steps before the take-over
  ASSERT_EQ(static_cast<int>(gated.size()), before + 1);
  ASSERT_LT(gated.size(), bare.size());
  const double dt = scene.horizon / scene.steps;
  for (std::size_t i = 0; i + 1 < gated.size(); ++i) {
    const Trajectory& g = gated[i].outcome.trajectory;
    const Trajectory& b = bare[i].outcome.trajectory;
    ASSERT_EQ(g.nodes(), b.nodes());
    if (g.nodes() == 0) continue;
    EXPECT_EQ(g.ego[0].y, b.ego[0].y);
    EXPECT_EQ(g.controls[0].a, b.controls[0].a);
  }
  const Trajectory& last = gated.back().outcome.trajectory;
  if (last.nodes() > 0) {
    EXPECT_NEAR(last.t[0], takeover_step * dt, 1e-9);
  }
}

// With time past the take-over, the expert's recovery is labelled too
// (HG-DAgger): at stride 1 the labelled states are mlp-miqp's own rollout,
// cut that many steps after the take-over.
// A learner that steers left from the start, on the open road: mlp-miqp's
// check takes over after a few steps.
struct SteeringLeft {
  Config config = small_config();
  planner::MlpMiqpPlanner learner = constant_learner(config, {0.0, 0.05});
  Scenario scene = testing::open_road_scenario();
  double dt = scene.horizon / scene.steps;
};

TEST(Dagger, GatedLabelsGoOnPastTheTakeOverForTheGivenTime) {
  const auto [config, learner, scene, dt] = SteeringLeft{};
  const int past_steps = 4;
  const sim::Rollout mlp_miqp = sim::simulate(scene, learner, config);
  const auto at = dagger::detail::collect_scene(scene, learner, config, {1, 1, 60.0, false, true});
  const auto past = dagger::detail::collect_scene(scene, learner, config,
                                                  {1, 1, 60.0, false, true, past_steps * dt});
  ASSERT_EQ(past.size(), at.size() + past_steps);
  ASSERT_LT(past.size(), mlp_miqp.trajectory.ego.size());
  for (std::size_t i = 0; i < past.size(); ++i) {
    const Trajectory& p = past[i].outcome.trajectory;
    if (p.nodes() == 0) continue;
    EXPECT_NEAR(p.t[0], static_cast<double>(i) * dt, 1e-9);
    EXPECT_EQ(p.ego[0].y, mlp_miqp.trajectory.ego[i].y) << i;
    EXPECT_EQ(p.ego[0].x, mlp_miqp.trajectory.ego[i].x) << i;
  }
}

// With the look-ahead labelled, the take-over adds the states the network
// would have driven to (the check's prediction, up to the node that failed
// it), every stride-th, on the rollout's clock after the take-over's state.
TEST(Dagger, GatedLabelsTakeTheFailedLookAheadToo) {
  const auto [config, learner, scene, dt] = SteeringLeft{};
  const int stride = 2;
  dagger::detail::Labelling labelling{stride, 1, 60.0, false, true};
  const auto at = dagger::detail::collect_scene(scene, learner, config, labelling);
  labelling.lookahead = true;
  const auto ahead = dagger::detail::collect_scene(scene, learner, config, labelling);
  ASSERT_GE(at.size(), 1U);
  ASSERT_GT(ahead.size(), at.size());
  const auto lookahead_steps =
      static_cast<std::size_t>(std::lround(config.closed_loop.lookahead / dt));
  EXPECT_LE(ahead.size() - at.size(), lookahead_steps / stride);
  for (std::size_t i = 0; i < at.size(); ++i) {
    ASSERT_EQ(ahead[i].outcome.trajectory.nodes(), at[i].outcome.trajectory.nodes());
    if (at[i].outcome.trajectory.nodes() > 0) {
      EXPECT_EQ(ahead[i].outcome.trajectory.ego[0].y, at[i].outcome.trajectory.ego[0].y);
    }
  }
  const Trajectory& takeover = at.back().outcome.trajectory;
  ASSERT_GT(takeover.nodes(), 0);
  double last_y = takeover.ego[0].y;
  for (std::size_t j = at.size(); j < ahead.size(); ++j) {
    const Trajectory& p = ahead[j].outcome.trajectory;
    if (p.nodes() == 0) continue;
    const auto k = static_cast<double>((j - at.size() + 1) * stride);
    EXPECT_NEAR(p.t[0], takeover.t[0] + k * dt, 1e-9) << j;
    // The network steers left all along: its predicted states drift left.
    EXPECT_GT(p.ego[0].y, last_y) << j;
    last_y = p.ego[0].y;
  }
}

// The states a rollout labels, in order (nodes 0; none where no plan).
std::vector<std::optional<EgoState>> visited(const std::vector<dagger::detail::Query>& queries) {
  std::vector<std::optional<EgoState>> out;
  for (const auto& q : queries) {
    const Trajectory& path = q.outcome.trajectory;
    out.push_back(path.nodes() > 0 ? std::optional(path.ego[0]) : std::nullopt);
  }
  return out;
}

bool same_states(const std::vector<std::optional<EgoState>>& a,
                 const std::vector<std::optional<EgoState>>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const auto& p, const auto& q) {
    return p.has_value() == q.has_value() && (!p || (p->x == q->x && p->y == q->y));
  });
}

// Ross et al.'s mixture at beta = 1 is the expert alone: replaying its
// labels' controls (the lane keeper's where it had no plan) as the network's
// visits the very same states, and none of the network's own.
TEST(Dagger, AtExpertShareOneTheExpertDrivesEveryStep) {
  const auto [config, learner, scene, dt] = SteeringLeft{};
  dagger::detail::Labelling mixed{1, 1, 60.0};
  mixed.expert_share = 1.0;
  const auto expert_driven = dagger::detail::collect_scene(scene, learner, config, mixed);
  ASSERT_GE(expert_driven.size(), 3U);
  const planner::LaneKeeper keeper(config);
  const planner::MlpMiqpPlanner replay =
      testing::scripted_learner(config, Label::WellPosed, [&](const planner::Observation& o) {
        const auto step = static_cast<std::size_t>(o.step);
        if (step >= expert_driven.size()) return EgoControl{0.0, 0.0};
        const auto& outcome = expert_driven[step].outcome;
        const bool planned = outcome.status == "converged" && outcome.trajectory.nodes() > 0;
        return planned ? outcome.trajectory.controls[0] : planner::fallback_control(keeper, o);
      });
  const auto replayed = dagger::detail::collect_scene(scene, replay, config, {1, 1, 60.0});
  EXPECT_TRUE(same_states(visited(expert_driven), visited(replayed)));
  const auto network_driven = dagger::detail::collect_scene(scene, learner, config, {1, 1, 60.0});
  EXPECT_FALSE(same_states(visited(expert_driven), visited(network_driven)));
}

// Between the two, a seeded coin picks the driver at every step: the same
// seed gives the same rollout, another seed another, and neither is the
// pure network's or the pure expert's.
TEST(Dagger, APartialExpertShareMixesTheDriversByASeededCoin) {
  const SteeringLeft left;
  const auto run = [&left](double share, std::uint64_t seed) {
    dagger::detail::Labelling labelling{1, 1, 60.0};
    labelling.expert_share = share;
    labelling.coin_seed = seed;
    return visited(dagger::detail::collect_scene(left.scene, left.learner, left.config, labelling));
  };
  const auto half = run(0.5, 1);
  EXPECT_TRUE(same_states(half, run(0.5, 1)));
  EXPECT_FALSE(same_states(half, run(0.5, 2)));
  EXPECT_FALSE(same_states(half, run(0.0, 1)));
  EXPECT_FALSE(same_states(half, run(1.0, 1)));
}

// mlp-miqp never lets the network drive a scene its classifier refuses, so
// by default neither does DAgger; every_scene rolls out there too.
TEST(Dagger, ScenesTheClassifierRefusesAreNotRolledOut) {
  const Config config = small_config();
  const planner::MlpMiqpPlanner refusing = constant_learner(config, {0.0, 0.0}, Label::Failure);
  const Scenario scene = testing::open_road_scenario();
  EXPECT_TRUE(dagger::detail::collect_scene(scene, refusing, config, {4, 1, 60.0}).empty());
  EXPECT_FALSE(dagger::detail::collect_scene(scene, refusing, config, {4, 1, 60.0, true}).empty());
  const planner::MlpMiqpPlanner trying = constant_learner(config, {0.0, 0.0}, Label::IllPosed);
  EXPECT_FALSE(dagger::detail::collect_scene(scene, trying, config, {4, 1, 60.0}).empty());
}

// The suite's base data set is made once per CTest run (SHARED_SUITES in
// CMakeLists.txt) and only read: each test runs in its own process.
class DaggerCli : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::made_once(shared_, [this] {
      testing::write_text(config_, nlohmann::json(small_config()).dump());
      const auto made = testing::run_cli("--config " + config_ +
                                         " generate --count 40 --seed 3 --jobs 2 --out " + data_);
      ASSERT_EQ(made.exit_code, 0) << made.output;
    });
  }
  [[nodiscard]] testing::CommandResult run_dagger(const std::string& extra) const {
    return testing::run_cli("--config " + config_ +
                            " dagger --quick --no-plots --max-epochs 10 --jobs 2 --data " + data_ +
                            " --out " + dir_.file("model") + " " + extra);
  }
  testing::TempDir dir_;
  std::filesystem::path shared_ = std::filesystem::path(LANECHANGE_TEST_SHARED_DIR) / "base";
  std::string config_ = (shared_ / "config.json").string();
  std::string data_ = (shared_ / "data").string();
};

// A retrain of the DAgger run in `work`: its base model, its data sets and
// the aggregated labels.
learn::RetrainOptions retrain_on_the_run(const std::string& work) {
  learn::RetrainOptions o;
  o.base_model = work + "/model-0";
  o.data_dirs = nlohmann::json::parse(testing::read_text(work + "/dagger.json"))
                    .at("data")
                    .get<std::vector<std::string>>();
  o.data_dirs.push_back(work + "/data");
  o.plots = false;
  return o;
}

// The retrain stops early on exactly the base's validation rows, so every
// DAgger row trains; with validate_on_added, some DAgger rows validate.
void expect_like_for_like_validation(const std::string& work, long long dagger_rows) {
  const auto metrics = [&](const std::string& model) {
    return nlohmann::json::parse(testing::read_text(work + "/" + model + "/metrics.json"))
        .at("network");
  };
  const auto base = metrics("model-0");
  const auto retrained = metrics("model-1");
  EXPECT_EQ(retrained["validation_rows"], base["validation_rows"]);
  EXPECT_EQ(retrained["train_rows"].get<long long>(),
            base["train_rows"].get<long long>() + dagger_rows);
  EXPECT_EQ(retrained["test_rows"], base["test_rows"]);

  learn::RetrainOptions all = retrain_on_the_run(work);
  all.out_dir = work + "/model-all";
  all.network.max_epochs = 2;
  all.validate_on_added = true;
  const auto mixed = learn::retrain_network(all).metrics.at("network");
  EXPECT_GT(mixed["validation_rows"].get<long long>() + mixed["train_rows"].get<long long>(),
            base["validation_rows"].get<long long>() + base["train_rows"].get<long long>());
  EXPECT_NE(mixed["validation_rows"], base["validation_rows"]);
}

learn::PolicyWeights policy_of(const std::string& model) {
  return learn::PolicyWeights::from_json(
      nlohmann::json::parse(testing::read_text(model + "/policy.json")));
}

// A fine-tuned retrain starts from the warm model's network under its
// standardizers: with a vanishing learning rate it acts as that network
// does, where fresh weights do not.
void expect_fine_tune_starts_from_the_warm_network(const std::string& work) {
  learn::RetrainOptions o = retrain_on_the_run(work);
  o.network.max_epochs = 1;
  o.network.learning_rate = 1e-9;
  o.warm_start = work + "/model-1";
  o.out_dir = work + "/model-warm";
  (void)learn::retrain_network(o);
  o.warm_start.clear();
  o.out_dir = work + "/model-fresh";
  (void)learn::retrain_network(o);

  const learn::PolicyWeights warm = policy_of(work + "/model-1");
  const learn::PolicyWeights tuned = policy_of(work + "/model-warm");
  EXPECT_EQ(tuned.input_mean, warm.input_mean);
  EXPECT_EQ(tuned.output_scale, warm.output_scale);
  const learn::Policy before(warm), after(tuned), fresh(policy_of(work + "/model-fresh"));
  const auto data = learn::load_learning_data(o.data_dirs);
  double moved = 0.0, fresh_gap = 0.0;
  for (Eigen::Index r = 0; r < std::min<Eigen::Index>(data.samples.rows(), 50); ++r) {
    const learn::Observation x = data.samples.inputs.row(r).transpose();
    moved = std::max(moved, (after.act(x) - before.act(x)).cwiseAbs().maxCoeff());
    fresh_gap = std::max(fresh_gap, (fresh.act(x) - before.act(x)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(moved, 1e-3);
  EXPECT_GT(fresh_gap, 10.0 * moved + 1e-3);

  o.warm_start = work + "/nowhere";
  o.out_dir = work + "/model-bad";
  EXPECT_THROW((void)learn::retrain_network(o), InputError);
  EXPECT_FALSE(fs::exists(o.out_dir));
}

TEST_F(DaggerCli, OneRoundAddsLabelsAsAValidDataSetAndTabulatesEachRound) {
  const std::string work = dir_.file("work");
  const auto run = run_dagger("--rounds 1 --dir " + work + " --scenes 8 --stride 2 --eval-count 6");
  ASSERT_EQ(run.exit_code, 0) << run.output;

  const std::string aggregated = work + "/data";
  EXPECT_EQ(testing::run_cli("dataset-info --data " + aggregated).exit_code, 0);
  const data::DatasetSummary summary = data::summarize_dataset(aggregated);
  EXPECT_GT(summary.scenarios, 0);
  EXPECT_GT(summary.samples, 0);
  EXPECT_LE(summary.samples, summary.scenarios);  // one sample per query with a plan
  EXPECT_TRUE(summary.parameters.contains("dagger"));
  const auto before = learn::load_learning_data({data_});
  const auto after = learn::load_learning_data({data_, aggregated});
  EXPECT_GT(after.samples.rows(), before.samples.rows());

  const auto table = read_csv(work + "/dagger.csv");
  ASSERT_EQ(table.size(), 1U + 2U + 1U);  // header, rounds 0 and 1, miqp
  const auto& header = table.front();
  for (std::size_t r = 1; r < table.size(); ++r) {
    ASSERT_EQ(table[r].size(), header.size());
    EXPECT_EQ(table[r][1], r <= 2 ? "mlp-miqp" : "miqp");
    EXPECT_EQ(std::stoll(table[r][2]), 6);
    for (std::size_t c = 3; c <= 6; ++c) {
      if (c == 4) continue;  // take-overs per rollout: not a share
      EXPECT_GE(std::stod(table[r][c]), 0.0);
      EXPECT_LE(std::stod(table[r][c]), 1.0);
    }
    EXPECT_GE(std::stod(table[r][4]), 0.0);
  }
  EXPECT_EQ(table[1][0], "0");
  EXPECT_EQ(table[2][0], "1");
  EXPECT_EQ(std::stoll(table[2][11]), after.samples.rows() - before.samples.rows());
  EXPECT_EQ(std::stoll(table[2][10]), std::stoll(table[2][11]));  // one node per query
  // The network drives the same scenes every round, and only it is taken over there.
  EXPECT_EQ(table[1][7], table[2][7]);
  for (std::size_t r = 1; r <= 2; ++r) {
    EXPECT_LE(std::stoll(table[r][8]) + std::stoll(table[r][9]), std::stoll(table[r][7]));
  }
  EXPECT_EQ(table[3][7], "0");
  // The rounds are scored with the step budget lifted, whatever the run's
  // config says, so that their scores do not depend on the machine's load.
  for (const char* eval : {"/eval-0/evaluation.json", "/eval-miqp/evaluation.json"}) {
    const auto written = nlohmann::json::parse(testing::read_text(work + eval));
    EXPECT_EQ(written["parameters"]["config"]["closed_loop"]["step_budget_ms"].get<double>(),
              dagger::detail::untimed(small_config()).closed_loop.step_budget_ms);
  }
  EXPECT_GT(dagger::detail::untimed(small_config()).closed_loop.step_budget_ms,
            small_config().closed_loop.step_budget_ms);

  // --out holds the last round's model: a new network, the base's classifiers.
  const learn::Model model = learn::Model::load(dir_.file("model"));
  const learn::Model base = learn::Model::load(work + "/model-0");
  EXPECT_TRUE(model.description().contains("retrained_network"));
  EXPECT_EQ(model.description()["data"]["datasets"].size(), 2U);
  const auto& files = model.description()["files"];
  const auto& base_files = base.description()["files"];
  EXPECT_EQ(files["classifiers/plain/svm.libsvm"], base_files["classifiers/plain/svm.libsvm"]);
  EXPECT_NE(files["policy.json"], base_files["policy.json"]);
  expect_like_for_like_validation(work, after.samples.rows() - before.samples.rows());
  expect_fine_tune_starts_from_the_warm_network(work);

  // The same command again finds every step done and tabulates the same.
  const std::string csv = testing::read_text(work + "/dagger.csv");
  const auto again =
      run_dagger("--rounds 1 --dir " + work + " --scenes 8 --stride 2 --eval-count 6");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(again.output.find("expert queries"), std::string::npos) << again.output;
  EXPECT_EQ(testing::read_text(work + "/dagger.csv"), csv);

  // The table reads back as written (the experiments report reads it); a
  // damaged one is refused by name.
  const dagger::DaggerReport back = dagger::read_report(work);
  ASSERT_EQ(back.rounds.size(), 2U);
  EXPECT_EQ(back.expert.planner, "miqp");
  EXPECT_EQ(back.rounds[1].dagger_samples, std::stoll(table[2][11]));
  EXPECT_EQ(back.rounds[1].driven, std::stoll(table[2][7]));
  EXPECT_EQ(back.rounds[1].taken_over_later, std::stoll(table[2][9]));
  EXPECT_DOUBLE_EQ(back.rounds[0].success_rate, std::stod(table[1][3]));
  const std::string damaged = dir_.file("damaged");
  fs::create_directories(damaged);
  testing::write_text(damaged + "/dagger.csv",
                      csv.substr(0, csv.find('\n') + 1) + "0,mlp-miqp,six\n");
  EXPECT_THROW((void)dagger::read_report(damaged), InputError);
  EXPECT_THROW((void)dagger::read_report(dir_.file("nowhere")), InputError);
}

// The retrains' learning rate: fine-tuned at a vanishing rate, round 1's
// network acts as round 0's; at round 0's rate it moves.
TEST_F(DaggerCli, TheRetrainsLearnAtTheirOwnRate) {
  auto largest_move = [this](const std::string& rate) {
    const std::string work = dir_.file("work" + rate);
    const auto run = run_dagger("--rounds 1 --fine-tune --dir " + work +
                                " --scenes 8 --stride 2 --eval-count 2" +
                                (rate.empty() ? "" : " --learning-rate " + rate));
    EXPECT_EQ(run.exit_code, 0) << run.output;
    const learn::Policy before(policy_of(work + "/model-0")), after(policy_of(work + "/model-1"));
    const auto data = learn::load_learning_data({data_});
    double moved = 0.0;
    for (Eigen::Index r = 0; r < std::min<Eigen::Index>(data.samples.rows(), 50); ++r) {
      const learn::Observation x = data.samples.inputs.row(r).transpose();
      moved = std::max(moved, (after.act(x) - before.act(x)).cwiseAbs().maxCoeff());
    }
    return moved;
  };
  const double vanishing = largest_move("1e-30");
  EXPECT_LT(vanishing, 1e-3);
  EXPECT_GT(largest_move(""), 10.0 * vanishing + 1e-3);
}

// With --average, round r's policy averages the networks of rounds
// 0..r: each round adds its own network to the last round's members, and a
// fine-tune goes on from that newest network.
TEST_F(DaggerCli, AveragedRoundsAddTheirNetworkToTheLastRoundsMembers) {
  const std::string work = dir_.file("work");
  const auto run = run_dagger("--rounds 2 --average --fine-tune --dir " + work +
                              " --scenes 6 --stride 2 --eval-count 2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto members_of = [&](int round) {
    return learn::policy_members_from_json(nlohmann::json::parse(
        testing::read_text(work + "/model-" + std::to_string(round) + "/policy.json")));
  };
  const auto round0 = members_of(0);
  const auto round1 = members_of(1);
  const auto round2 = members_of(2);
  ASSERT_EQ(round0.size(), 1U);
  ASSERT_EQ(round1.size(), 2U);
  ASSERT_EQ(round2.size(), 3U);
  EXPECT_EQ(round1[0].to_json(), round0[0].to_json());
  EXPECT_EQ(round2[0].to_json(), round0[0].to_json());
  EXPECT_EQ(round2[1].to_json(), round1[1].to_json());
  EXPECT_NE(round2[2].to_json(), round1[1].to_json());
  // The fine-tune starts from the newest member, under its standardizers.
  EXPECT_EQ(round2[2].input_mean, round1[1].input_mean);
  // What mlp-miqp loads is the average.
  const learn::Model model = learn::Model::load(work + "/model-2");
  EXPECT_EQ(model.policy().members(), 3);
  const auto data = learn::load_learning_data({data_});
  const learn::Observation x = data.samples.inputs.row(0).transpose();
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& m : round2) mean += learn::Policy(m).act(x) / 3.0;
  EXPECT_NEAR((model.policy().act(x) - mean).cwiseAbs().maxCoeff(), 0.0, 1e-9);
  const auto metrics =
      nlohmann::json::parse(testing::read_text(work + "/model-2/metrics.json")).at("network");
  EXPECT_EQ(metrics.at("members").get<int>(), 3);
}

// With candidates, a round retrains once per network seed, measures each on
// the selection scenes and keeps the one with the fewest take-overs there.
// Round r lets the expert act with probability beta^r; the aggregated data
// set records each round's share and stays a data set.
TEST_F(DaggerCli, MixedRoundsRecordTheirExpertShareInTheDataSet) {
  const std::string work = dir_.file("work");
  const auto run =
      run_dagger("--rounds 2 --beta 0.5 --dir " + work + " --scenes 6 --stride 2 --eval-count 2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto manifest = nlohmann::json::parse(testing::read_text(work + "/data/manifest.json"));
  const auto& shards = manifest.at("parameters").at("dagger").at("shards");
  ASSERT_EQ(shards.size(), 2U);
  EXPECT_DOUBLE_EQ(shards[0].at("expert_share").get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(shards[1].at("expert_share").get<double>(), 0.25);
  EXPECT_EQ(testing::run_cli("dataset-info --data " + work + "/data").exit_code, 0);
  // Another beta is another run: a resume with it is refused.
  const auto other =
      run_dagger("--rounds 2 --beta 0.7 --dir " + work + " --scenes 6 --stride 2 --eval-count 2");
  EXPECT_EQ(other.exit_code, 2) << other.output;
}

TEST_F(DaggerCli, ARoundKeepsTheRetrainWithTheFewestTakeOversOnTheSelectionScenes) {
  const std::string work = dir_.file("work");
  const auto run = run_dagger("--rounds 1 --dir " + work +
                              " --scenes 8 --stride 2 --eval-count 2"
                              " --candidates 2 --select-count 4 --select-seed 7"
                              " --eval-seed 8");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto table = read_csv(work + "/selection.csv");
  ASSERT_EQ(table.size(), 3U);  // header, two candidates of round 1
  int chosen = -1;
  std::vector<double> takeovers;
  for (std::size_t r = 1; r < table.size(); ++r) {
    const auto& row = table[r];
    ASSERT_EQ(row.size(), table.front().size());
    EXPECT_EQ(row[0], "1");
    const std::string candidate = work + "/round-1-candidate-" + row[1];
    // The number is the selection scenes' (select-1-j), not the held-out ones'.
    const auto rollouts = sim::read_rollouts(work + "/select-1-" + row[1] + "/rollouts.csv");
    ASSERT_EQ(rollouts.size(), 4U);
    double sum = 0.0;
    for (const auto& r4 : rollouts) sum += r4.takeovers;
    EXPECT_NEAR(std::stod(row[3]), sum / 4.0, 1e-6);
    takeovers.push_back(std::stod(row[3]));
    if (row[5] == "1") {
      EXPECT_EQ(chosen, -1) << "one candidate is chosen";
      chosen = std::stoi(row[1]);
    }
  }
  ASSERT_GE(chosen, 0);
  EXPECT_LE(takeovers[static_cast<std::size_t>(chosen)], takeovers[1 - chosen]);
  // Two seeds, two networks; the round's model is the chosen one.
  const std::string policy0 = testing::read_text(work + "/round-1-candidate-0/policy.json");
  const std::string policy1 = testing::read_text(work + "/round-1-candidate-1/policy.json");
  EXPECT_NE(policy0, policy1);
  EXPECT_EQ(testing::read_text(work + "/model-1/policy.json"), chosen == 0 ? policy0 : policy1);
  EXPECT_EQ(read_csv(work + "/dagger.csv").size(), 4U);
}

TEST_F(DaggerCli, BadOptionsAreRefusedAndWriteNothing) {
  const std::string work = dir_.file("work");
  for (const char* bad : {"--rounds -1",
                          "--rounds 1 --scenes 0",
                          "--rounds 1 --stride 0",
                          "--rounds 1 --eval-seed 7001",
                          "--rounds 1 --label-nodes -1",
                          "--scenes 5",
                          "--every-scene",
                          "--validate-all",
                          "--rounds 1 --rollout sideways",
                          "--rollout gated",
                          "--rounds 1 --past-takeover 1",
                          "--rounds 1 --label-lookahead",
                          "--rounds 1 --beta -0.1",
                          "--rounds 1 --beta 1.5",
                          "--rounds 1 --rollout gated --beta 0.5",
                          "--beta 0.5",
                          "--rounds 1 --learning-rate -1",
                          "--rounds 1 --learning-rate 2",
                          "--rounds 1 --candidates 0",
                          "--rounds 1 --candidates 21",
                          "--rounds 1 --candidates 2 --select-seed 2026",
                          "--rounds 1 --candidates 2 --select-seed 7001",
                          "--rounds 1 --candidates 2 --select-count 0",
                          "--candidates 2",
                          "--rounds 1 --rollout gated --past-takeover -1"}) {
    std::string options = bad;
    options += " --dir ";
    options += work;
    const auto run = run_dagger(options);
    EXPECT_EQ(run.exit_code, 2) << bad << ": " << run.output;
    EXPECT_FALSE(fs::exists(work)) << bad;
  }
  const auto missing = testing::run_cli("dagger --data " + dir_.file("nowhere") + " --out " +
                                        dir_.file("model") + " --rounds 1");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_FALSE(fs::exists(dir_.file("model")));
}

}  // namespace
}  // namespace lanechange
