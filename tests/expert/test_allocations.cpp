// A thread's plans allocate nothing once its workspace, memory and result
// have held a plan of each scene: this program replaces operator new to
// count the heap allocations of the calling thread. With
// LANECHANGE_TRACE_ALLOCATIONS=1 it prints where each counted one was made.
#include <execinfo.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "lanechange/expert/planner.hpp"
#include "lanechange/learn/policy.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/simulator.hpp"
#include "planner/miqp_planner.hpp"
#include "scripted_learner.hpp"

namespace {

thread_local bool t_counting = false;
thread_local long t_allocations = 0;

void note_allocation() {
  if (!t_counting) return;
  ++t_allocations;
  static const bool trace = std::getenv("LANECHANGE_TRACE_ALLOCATIONS") != nullptr;
  if (!trace) return;
  t_counting = false;  // backtrace itself may allocate
  void* frames[12];
  const int depth = backtrace(frames, 12);
  backtrace_symbols_fd(frames, depth, STDERR_FILENO);
  std::fputs("--\n", stderr);
  t_counting = true;
}

}  // namespace

void* operator new(std::size_t size) {
  note_allocation();
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t /*size*/) noexcept { std::free(p); }
// Over-aligned types (Eigen's, with wider vector units) come through these.
void* operator new(std::size_t size, std::align_val_t alignment) {
  note_allocation();
  const auto align = static_cast<std::size_t>(alignment);
  const std::size_t rounded = (size + align - 1) / align * align;
  if (void* p = std::aligned_alloc(align, rounded == 0 ? align : rounded)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p, std::align_val_t /*alignment*/) noexcept { std::free(p); }
void operator delete(void* p, std::size_t /*size*/, std::align_val_t /*alignment*/) noexcept {
  std::free(p);
}

namespace lanechange::expert {
namespace {

// Counts the allocations `f` makes on this thread.
template <class F>
long allocations_of(F&& f) {
  t_allocations = 0;
  t_counting = true;
  f();
  t_counting = false;
  return t_allocations;
}

// Three-car scenes and dense ones (eight cars in the target lane), some of
// which no gap admits: plans that converge and plans that fail.
std::vector<Scenario> mixed_scenes() {
  Config dense;
  dense.sampler.target_lane_cars = {8, 8};
  const ScenarioSampler three_cars(Config{}, 2026);
  const ScenarioSampler eight_cars(dense, 2026);
  std::vector<Scenario> scenes;
  for (std::uint64_t i = 0; i < 12; ++i) scenes.push_back(three_cars.sample(i));
  for (std::uint64_t i = 0; i < 10; ++i) scenes.push_back(eight_cars.sample(i));
  return scenes;
}

TEST(Allocations, APlanAllocatesNothingOnceItsThreadHasPlannedTheSceneBefore) {
  const Config config;
  const std::vector<Scenario> scenes = mixed_scenes();
  const ExpertPlanner planner(config, std::make_shared<FastLaneChangeSolver>());
  const auto workspace = planner.solver().make_workspace();
  PlanMemory memory;
  PlanHints hints;
  hints.workspace = workspace.get();
  hints.memory = &memory;
  ExpertResult result;
  for (const Scenario& scene : scenes) planner.plan(scene, {}, hints, result);
  int converged = 0;
  int failed = 0;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const long count = allocations_of([&] { planner.plan(scenes[i], {}, hints, result); });
    EXPECT_EQ(count, 0) << "scene " << i << " (status " << to_string(result.status) << ")";
    (result.status == PlanStatus::Converged ? converged : failed) += 1;
  }
  // Both kinds of plan are counted.
  EXPECT_GE(converged, 10);
  EXPECT_GE(failed, 2);
}

// A step that planned anew, or whose network drove: it says nothing. A step
// that falls back, follows an old plan or hands over says why in words,
// which it may allocate.
bool planned_anew(const planner::Decision& d) {
  return d.status == planner::ActStatus::Planned && d.reason.empty();
}

// Counts the allocations of each step of the sessions it starts.
class CountingPlanner final : public planner::ClosedLoopPlanner {
 public:
  struct Step {
    long allocations = 0;
    planner::Decision decision;
  };
  explicit CountingPlanner(const planner::ClosedLoopPlanner& inner) : inner_(inner) {}
  [[nodiscard]] std::string_view name() const override { return inner_.name(); }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(
      const Scenario& scene) const override {
    steps_.clear();
    return std::make_unique<Session>(inner_.start(scene), steps_);
  }
  [[nodiscard]] const std::vector<Step>& steps() const { return steps_; }

 private:
  class Session final : public planner::PlannerSession {
   public:
    Session(std::unique_ptr<planner::PlannerSession> inner, std::vector<Step>& steps)
        : inner_(std::move(inner)), steps_(steps) {}
    planner::Decision act(const planner::Observation& observation) override {
      planner::Decision decision;
      const long count = allocations_of([&] { decision = inner_->act(observation); });
      steps_.push_back({count, decision});
      return decision;
    }

   private:
    std::unique_ptr<planner::PlannerSession> inner_;
    std::vector<Step>& steps_;
  };
  const planner::ClosedLoopPlanner& inner_;
  mutable std::vector<Step> steps_;
};

TEST(Allocations, AMiqpStepThatFollowsANewPlanAllocatesNothingOnceItsSessionHasPlanned) {
  const Config config;
  const planner::MiqpPlanner miqp(config, std::make_shared<FastLaneChangeSolver>());
  const CountingPlanner counting(miqp);
  const std::vector<Scenario> scenes = mixed_scenes();
  int counted = 0;
  int planned = 0;
  for (std::size_t i = 0; i < scenes.size(); i += 3) {
    const sim::Rollout rollout = sim::simulate(scenes[i], counting, config);
    const auto& steps = counting.steps();
    ASSERT_FALSE(steps.empty());
    // The first new plan sizes the session's memory (a first step cut by its
    // work budget falls back and plans nothing).
    const auto first = std::find_if(steps.begin(), steps.end(),
                                    [](const auto& step) { return planned_anew(step.decision); });
    for (auto k = static_cast<std::size_t>(first - steps.begin()) + 1; k < steps.size(); ++k) {
      if (!planned_anew(steps[k].decision)) continue;
      EXPECT_EQ(steps[k].allocations, 0) << "scene " << i << ", step " << k;
      ++counted;
    }
    planned += static_cast<int>(steps.size());
  }
  // Most steps follow a new plan.
  EXPECT_GE(counted, planned / 2);
}

// The allocations of mlp-miqp's network steps in rollouts of `scenes`, each
// after its session's first two (the look-ahead window built), into `counts`.
void count_network_steps(const planner::MlpMiqpPlanner& mlp, const std::vector<Scenario>& scenes,
                         const Config& config, std::vector<long>& counts) {
  const CountingPlanner counting(mlp);
  for (const Scenario& scene : scenes) {
    (void)sim::simulate(scene, counting, config);
    const auto& steps = counting.steps();
    for (std::size_t k = 2; k < steps.size(); ++k) {
      if (planned_anew(steps[k].decision)) counts.push_back(steps[k].allocations);
    }
  }
}

// mlp-miqp's network steps: the network and the look-ahead check, which each
// step extends by one node. One scripted network keeps its lane behind the
// car ahead (never taken over, in three-car and dense scenes alike), the
// other steers into the target lane (the checks of the target lane; taken
// over in most scenes at once).
TEST(Allocations, AnMlpMiqpNetworkStepAllocatesNothingOnceItsSessionHasStepped) {
  const Config config;
  const planner::LaneKeeper keeper(config);
  const planner::MlpMiqpPlanner keeps = testing::scripted_learner(
      config, Label::WellPosed,
      [&keeper](const planner::Observation& o) { return planner::fallback_control(keeper, o); });
  const planner::MlpMiqpPlanner changes =
      testing::scripted_learner(config, Label::WellPosed, [&keeper](const planner::Observation& o) {
        return keeper.control(o.ego, o.scene->lane_width, std::nullopt);
      });
  const std::vector<Scenario> scenes = mixed_scenes();
  // Two three-car and two dense scenes for the lane keeper: the sanitizer
  // build runs the whole test in about a minute.
  std::vector<long> keeping, changing;
  count_network_steps(keeps, {scenes[0], scenes[6], scenes[12], scenes[18]}, config, keeping);
  count_network_steps(changes, {scenes[3], scenes[9], scenes[14]}, config, changing);
  for (const auto* counts : {&keeping, &changing}) {
    EXPECT_GE(counts->size(), 50U) << "too few network steps to count";
    EXPECT_EQ(std::count(counts->begin(), counts->end(), 0L), std::ssize(*counts));
  }
}

// The action network itself, the other half of a network step: widths on
// both of its product paths (lazy up to kLazyWidth, GEMV above) and an ensemble.
learn::PolicyWeights random_network(int inputs, int width, unsigned seed) {
  std::srand(seed);
  learn::PolicyWeights w;
  for (int i = 0; i < inputs; ++i) w.inputs.push_back("input" + std::to_string(i));
  w.outputs = {"a", "omega"};
  w.input_mean = Eigen::VectorXd::Random(inputs);
  w.input_scale = Eigen::VectorXd::Constant(inputs, 2.0);
  w.output_mean = Eigen::VectorXd::Zero(learn::kActions);
  w.output_scale = Eigen::VectorXd::Ones(learn::kActions);
  int in = inputs;
  for (int l = 0; l <= learn::kHiddenLayers; ++l) {
    const int out = l == learn::kHiddenLayers ? learn::kActions : width;
    w.weights.push_back(Eigen::MatrixXf::Random(out, in));
    w.biases.push_back(Eigen::VectorXf::Random(out));
    in = out;
  }
  return w;
}

TEST(Allocations, APolicysActionAllocatesNothing) {
  constexpr int kInputs = 28;
  const std::vector<learn::Policy> policies{
      learn::Policy(random_network(kInputs, learn::kHiddenWidth, 1)),
      learn::Policy(random_network(kInputs, learn::kMaxHiddenWidth, 2)),
      learn::Policy(std::vector{random_network(kInputs, 32, 3), random_network(kInputs, 32, 4),
                                random_network(kInputs, 32, 5)})};
  for (const learn::Policy& policy : policies) {
    const learn::Observation x = learn::Observation::Random(kInputs);
    Eigen::Vector2d u;
    const long count = allocations_of([&] { u = policy.act(x); });
    EXPECT_EQ(count, 0) << "width " << policy.width() << ", members " << policy.members();
    EXPECT_TRUE(u.allFinite());
  }
}

}  // namespace
}  // namespace lanechange::expert
