// DAgger's data collection (docs/dagger.md). The learner is the
// bare action network (classic DAgger rolls the learner out), or the network
// under mlp-miqp's check, whose take-over ends the labels (HG-DAgger).
#include "dagger/collect.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <thread>

#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/run/progress.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/simulator.hpp"
#include "planner/miqp_planner.hpp"

namespace lanechange::dagger::detail {

namespace {

// Node 0 of the plan from now is the observation's state; the plan's clock
// starts there, so its times move by the rollout's.
Query first_nodes(data::PlanOutcome outcome, double t, int nodes) {
  Trajectory& path = outcome.trajectory;
  if (nodes > 0 && path.nodes() > nodes) {
    const auto keep = static_cast<std::size_t>(nodes);
    path.t.resize(keep);
    path.ego.resize(keep);
    path.controls.resize(keep);
    outcome.lane_modes.resize(std::min(outcome.lane_modes.size(), keep));
  }
  for (double& time : path.t) time += t;
  return {std::move(outcome)};
}

// mlp-miqp never lets the network drive a refused scene, so its states
// there are not the network's distribution; most of their labels were
// ill-posed plans that train nothing.
bool rolled_out(const Scenario& scene, const planner::MlpMiqpPlanner& learner,
                const Labelling& labelling) {
  return labelling.every_scene || learner.tries(scene);
}

// The expert committed to its lane strategy for the scene: the mixed-integer
// expert's plan jumps between strategies for states a few centimetres
// apart, and labels from both sides of a jump contradict each other where the
// network cannot tell the states apart. With the modes fixed, the plan is a
// convex QP's, continuous in the state.
class StrategyLabeller {
 public:
  StrategyLabeller(const planner::MlpMiqpPlanner& learner, const Scenario& scene)
      : fixed_(learner.config(), std::make_shared<expert::FixedModeLaneChangeSolver>()),
        plan_(learner.expert().plan(scene)) {}

  // The plan from `now` (the scene at `step`) with the start's modes; none
  // when the start had no converged plan.
  [[nodiscard]] std::optional<data::PlanOutcome> label(const Scenario& now, int step,
                                                       double time_limit_s) const {
    if (plan_.status != expert::PlanStatus::Converged) return std::nullopt;
    const double dt = now.horizon / now.steps;
    const std::vector<int> modes = planner::shifted(plan_.modes, step, now.steps);
    const expert::Iterate guess = planner::shifted(plan_.path, step, now.steps, dt);
    expert::PlanHints hints{&guess, &modes, false};
    hints.gap = &plan_.gap;
    return data::plan_outcome(fixed_, now, time_limit_s, hints);
  }

 private:
  expert::ExpertPlanner fixed_;
  expert::ExpertResult plan_;
};

class LearnerSession final : public planner::PlannerSession {
 public:
  LearnerSession(const planner::MlpMiqpPlanner& learner, const Labelling& labelling,
                 std::vector<Query>& sink, std::unique_ptr<planner::PlannerSession> gate,
                 std::optional<StrategyLabeller> strategy, expert::GapFrame gap)
      : learner_(learner),
        gap_(gap),
        labelling_(labelling),
        sink_(sink),
        gate_(std::move(gate)),
        strategy_(std::move(strategy)) {}

  [[nodiscard]] planner::Decision act(const planner::Observation& o) override {
    if (!gate_) {
      const bool labelled = o.step % labelling_.stride == 0;
      if (expert_turn()) return expert_decision(o, labelled);
      if (labelled) label(o);
      return network_decision(o);
    }
    if (takeover_step_ < 0) {
      planner::Decision d = gate_->act(o);
      if (d.status == planner::ActStatus::Planned) {
        if (o.step % labelling_.stride == 0) label(o);
        return d;
      }
      // The take-over's state is where the network went wrong: always labelled.
      takeover_step_ = o.step;
      label(o);
      if (labelling_.lookahead) label_lookahead();
      return d;
    }
    const int past = o.step - takeover_step_;
    // Nothing is labelled any more: the cheapest driver ends the rollout.
    if (past > past_takeover_steps(o)) return network_decision(o);
    // HG-DAgger labels the expert's recovery from where the network left it.
    if (past % labelling_.stride == 0) label(o);
    return gate_->act(o);
  }

 private:
  [[nodiscard]] planner::Decision network_decision(const planner::Observation& o) const {
    return {learner_.network(o, gap_), planner::ActStatus::Planned, ""};
  }

  // Drawn at every step, so that a scene's coins do not depend on who drove.
  [[nodiscard]] bool expert_turn() {
    return labelling_.expert_share > 0.0 && coin_.uniform(0.0, 1.0) < labelling_.expert_share;
  }

  // The expert acts as miqp would from this state without a warm start:
  // its plan's first control, or the lane keeper where it found none.
  [[nodiscard]] planner::Decision expert_decision(const planner::Observation& o, bool labelled) {
    Query query = plan_at(o);
    const Trajectory& path = query.outcome.trajectory;
    const bool planned = query.outcome.status == expert::to_string(expert::PlanStatus::Converged) &&
                         path.nodes() > 0;
    const EgoControl u = planned ? path.controls[0] : planner::fallback_control(keeper_, o);
    if (labelled) sink_.push_back(std::move(query));
    return {u, planner::ActStatus::Planned, ""};
  }

  [[nodiscard]] int past_takeover_steps(const planner::Observation& o) const {
    const double dt = o.scene->horizon / o.scene->steps;
    return static_cast<int>(std::lround(labelling_.past_takeover_s / dt));
  }

  // The states the network would have driven to, which its check refused.
  void label_lookahead() {
    const auto* session = dynamic_cast<const planner::MlpMiqpSession*>(gate_.get());
    if (session == nullptr) return;
    const std::vector<planner::Observation>& ahead = session->lookahead();
    for (std::size_t k = 1; k <= ahead.size(); ++k) {
      if (k % static_cast<std::size_t>(labelling_.stride) == 0) label(ahead[k - 1]);
    }
  }

  // The call miqp's re-plan makes, from the scene as it is now, but
  // without a warm start: the learner's path is not the expert's.
  [[nodiscard]] Query plan_at(const planner::Observation& o) const {
    const Scenario now = planner::scene_now(o, learner_.config());
    if (strategy_) {
      auto fixed = strategy_->label(now, o.step, labelling_.time_limit_s);
      if (fixed && fixed->label == Label::WellPosed) {
        return first_nodes(std::move(*fixed), o.t, labelling_.nodes);
      }
    }
    return first_nodes(data::plan_outcome(learner_.expert(), now, labelling_.time_limit_s), o.t,
                       labelling_.nodes);
  }

  void label(const planner::Observation& o) { sink_.push_back(plan_at(o)); }

  const planner::MlpMiqpPlanner& learner_;
  expert::GapFrame gap_;  ///< the gap the learner drives to
  const Labelling& labelling_;
  std::vector<Query>& sink_;
  std::unique_ptr<planner::PlannerSession> gate_;  ///< mlp-miqp's session when gated
  std::optional<StrategyLabeller> strategy_;       ///< Labelling::fixed_strategy
  int takeover_step_ = -1;                         ///< the gate's first take-over; -1: none yet
  Rng coin_{labelling_.coin_seed};                 ///< Labelling::expert_share's draws
  planner::LaneKeeper keeper_{learner_.config()};  ///< the expert's fallback, as miqp's
};

class LearnerPlanner final : public planner::ClosedLoopPlanner {
 public:
  LearnerPlanner(const planner::MlpMiqpPlanner& learner, const Labelling& labelling,
                 std::vector<Query>& sink)
      : learner_(learner), labelling_(labelling), sink_(sink) {}
  [[nodiscard]] std::string_view name() const override { return "dagger-learner"; }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(
      const Scenario& scene) const override {
    std::optional<StrategyLabeller> strategy;
    if (labelling_.fixed_strategy) strategy.emplace(learner_, scene);
    return std::make_unique<LearnerSession>(learner_, labelling_, sink_,
                                            labelling_.gated ? learner_.start(scene) : nullptr,
                                            std::move(strategy), learner_.choose(scene).gap);
  }

 private:
  const planner::MlpMiqpPlanner& learner_;
  const Labelling& labelling_;
  std::vector<Query>& sink_;
};

// Not the scene's own sub-seed, which drew the scene itself.
std::uint64_t coin_seed(std::uint64_t scene_seed, std::uint64_t scene_index) {
  return Rng(scenario_seed(scene_seed, scene_index) ^ 0xbe7a5eedULL).next();
}

}  // namespace

Config untimed(const Config& config) {
  Config out = config;
  out.closed_loop.deadline = Deadline::WallClock;
  out.closed_loop.step_budget_ms = 1e12;
  return out;
}

std::vector<Query> collect_scene(const Scenario& scene, const planner::MlpMiqpPlanner& learner,
                                 const Config& config, const Labelling& labelling) {
  if (!rolled_out(scene, learner, labelling)) return {};
  // The expert's queries are labelling, not driving: they must never count
  // as an overrun that hands the step to the fallback.
  std::vector<Query> queries;
  const LearnerPlanner planner(learner, labelling, queries);
  (void)sim::simulate(scene, planner, untimed(config));
  return queries;
}

RoundData collect_round(const CollectJob& job, const std::string& dir, long long shard,
                        long long first_index) {
  const ScenarioSampler sampler(job.config, job.scene_seed);
  std::vector<std::vector<Query>> per_scene(static_cast<std::size_t>(job.scenes));
  std::atomic<long long> next{0};
  std::atomic<long long> refused{0};
  run::Progress progress(job.progress, false, job.scenes, -1.0, "dagger", "learner rollouts");
  auto work = [&] {
    for (long long i = next++; i < job.scenes; i = next++) {
      const auto scene_index = static_cast<std::uint64_t>(job.first_scene + i);
      const Scenario scene = sampler.sample(scene_index);
      Labelling labelling = job.labelling;
      labelling.coin_seed = coin_seed(job.scene_seed, scene_index);
      per_scene[static_cast<std::size_t>(i)] =
          collect_scene(scene, job.learner, job.config, labelling);
      if (!rolled_out(scene, job.learner, job.labelling)) ++refused;
      progress.add(1);
    }
  };
  const int jobs =
      job.jobs > 0 ? job.jobs : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  std::vector<std::thread> threads;
  for (int t = 1; t < jobs; ++t) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
  progress.finish();

  RoundData out;
  out.range = {shard, first_index, 0};
  out.refused = refused;
  data::ShardFiles files(dir, shard);
  for (long long i = 0; i < job.scenes; ++i) {
    const auto scene_index = static_cast<std::uint64_t>(job.first_scene + i);
    const Scenario scene = sampler.sample(scene_index);
    for (const Query& query : per_scene[static_cast<std::size_t>(i)]) {
      const auto index = static_cast<std::uint64_t>(first_index + out.range.count++);
      if (query.outcome.label == Label::WellPosed) {
        ++out.labelled;
        out.samples += query.outcome.trajectory.nodes();
      }
      files.write(data::scenario_rows(index, scenario_seed(job.scene_seed, scene_index), scene,
                                      query.outcome));
    }
  }
  files.commit();
  return out;
}

}  // namespace lanechange::dagger::detail
