#include "lanechange/studies/strategy_study.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "lanechange/error.hpp"
#include "lanechange/learn/model.hpp"
#include "lanechange/run/markdown.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sampler.hpp"
#include "planner/strategy_qp_planner.hpp"

namespace lanechange::studies {

using planner::CandidateOutcome;
using planner::StrategyPlan;
using planner::StrategyQpPlanner;

using nlohmann::json;

namespace {

json summary(const std::vector<double>& v) {
  if (v.empty()) return {{"count", 0}};
  return {{"count", v.size()},
          {"median", run::nearest_rank(v, 0.5)},
          {"p95", run::nearest_rank(v, 0.95)},
          {"max", *std::max_element(v.begin(), v.end())}};
}

// What one scene contributes.
struct Tally {
  long long scenes = 0, expert_plans = 0, top1 = 0, topk = 0, followed = 0, fallbacks = 0;
  long long own_strategy_holds = 0;  // a perfect vote's top-1
  // Why the candidates of the scenes with an expert plan failed.
  std::map<std::string, long long> candidate_outcomes;
  std::vector<double> ratio, ratio_learned, strategy_ms, expert_ms, strategy_ms_learned;
  std::vector<double> rounds_run;  // candidates whose rounds a plan ran
  std::vector<double> screen_ms, predict_ms, followed_rounds, followed_ms;
  // Plans without the fallback: their interior-point iterations, and the
  // time per iteration (what a faster QP would change).
  std::vector<double> qp_iterations_learned, us_per_iteration_learned;
  json per_scene = json::array();  // the scenes with an expert plan, one record each
};

std::string outcome_of(const CandidateOutcome& o) {
  if (o.status != expert::PlanStatus::Converged) return std::string(expert::to_string(o.status));
  return o.collision ? "collision" : o.rescued ? "feasible_trust_region" : "feasible";
}

// The exact plan's strategy in the model's terms (nodes 1..), to set beside
// the candidates of a scene where none of them held.
std::string exact_strategy(const expert::ExpertResult& exact) {
  std::vector<int> lanes;
  for (const auto& o : exact.occupancy) lanes.push_back(o ? static_cast<int>(*o) : -1);
  // From node 0: the strategy's first character is node 1, as the model's are.
  return lanes.size() > 1 ? learn::strategy_of(lanes, 0) : "";
}

void add_scene(const StrategyQpPlanner& planner, const Scenario& scene, int index, Tally& t) {
  ++t.scenes;
  const expert::ExpertResult exact = planner.exact().plan(scene);
  const StrategyPlan learned = planner.plan(scene);
  t.expert_ms.push_back(exact.total_ms);
  t.strategy_ms.push_back(learned.total_ms);
  const bool expert_found = exact.status == expert::PlanStatus::Converged &&
                            !planner.exact().to_trajectory(exact, scene).collision;
  if (learned.chosen >= 0) {
    t.strategy_ms_learned.push_back(learned.total_ms);
    const auto iterations = static_cast<double>(learned.qp_iterations);
    t.qp_iterations_learned.push_back(iterations);
    if (iterations > 0) t.us_per_iteration_learned.push_back(1e3 * learned.total_ms / iterations);
  }
  t.screen_ms.push_back(learned.screen_ms);
  t.predict_ms.push_back(learned.predict_ms);
  if (learned.chosen >= 0) {
    const auto& followed = learned.candidates[static_cast<std::size_t>(learned.chosen)];
    t.followed_rounds.push_back(followed.rounds);
    t.followed_ms.push_back(followed.rounds_ms);
  }
  t.rounds_run.push_back(double(std::count_if(learned.candidates.begin(), learned.candidates.end(),
                                              [](const auto& o) { return o.rounds_run; })));
  if (!expert_found) return;
  ++t.expert_plans;
  // Feasibility is the model's: every candidate's rounds, whatever the plan
  // followed (the screen runs only as many as it needs).
  const std::vector<CandidateOutcome> c = planner.assess(scene);
  const std::string own = exact_strategy(exact);
  const CandidateOutcome own_outcome = planner.assess_strategy(scene, own);
  t.own_strategy_holds += own_outcome.feasible() ? 1 : 0;
  json record = {
      {"index", index},
      {"behavior", to_string(scene.behavior)},
      {"exact_objective", exact.objective},
      {"exact_strategy", own},
      {"exact_strategy_outcome", outcome_of(own_outcome)},
      {"followed", learned.chosen},
      {"followed_strategy",
       learned.chosen >= 0 ? learned.candidates[static_cast<std::size_t>(learned.chosen)].strategy
                           : ""},
      {"candidates", json::array()}};
  for (const CandidateOutcome& o : c) {
    const std::string outcome = outcome_of(o);
    ++t.candidate_outcomes[outcome];
    record["candidates"].push_back({{"strategy", o.strategy}, {"outcome", outcome}});
  }
  const bool first = !c.empty() && c.front().feasible();
  t.top1 += first ? 1 : 0;
  t.topk += std::any_of(c.begin(), c.end(), [](const auto& o) { return o.feasible(); }) ? 1 : 0;
  t.followed += learned.chosen >= 0 ? 1 : 0;
  t.fallbacks += learned.chosen < 0 ? 1 : 0;
  if (learned.result.status == expert::PlanStatus::Converged) {
    const double ratio = learned.result.objective / exact.objective;
    record["cost_ratio"] = ratio;
    t.ratio.push_back(ratio);
    if (learned.chosen >= 0) t.ratio_learned.push_back(ratio);
  }
  t.per_scene.push_back(std::move(record));
}

}  // namespace

json run_strategy_study(const StrategyStudyOptions& o) {
  if (o.model_dir.empty()) throw InputError("--model", "must name a model directory");
  return run_strategy_study(o, learn::Model::load(o.model_dir).strategy());
}

json run_strategy_study(const StrategyStudyOptions& o,
                        std::shared_ptr<const learn::StrategyModel> model) {
  if (o.count < 1) throw InputError("--count", "must be at least 1");
  o.config.validate();
  // Open loop, as the data were made: the expert plans from the start with
  // the config's own expert.monotone_lateral, not the closed loop's.
  // Lane strategies are learned for Eq. 1's gap, so the exact plans they
  // are compared with go through it too.
  Config config = o.config;
  config.closed_loop.monotone_lateral = false;
  config.expert.gap = GapChoice::Fixed;
  const StrategyQpPlanner planner(config, std::move(model));
  const ScenarioSampler sampler(o.config, o.seed);
  Tally t;
  for (int i = 0; i < o.count; ++i) {
    add_scene(planner, sampler.sample(static_cast<std::uint64_t>(i), o.behavior), i, t);
    if (o.progress != nullptr && (i + 1) % 50 == 0) {
      *o.progress << "strategy-study: " << i + 1 << " of " << o.count << " scenes\n";
    }
  }
  const double plans = double(std::max<long long>(t.expert_plans, 1));
  const double expert_median = run::nearest_rank(t.expert_ms, 0.5);
  const double strategy_median = run::nearest_rank(t.strategy_ms, 0.5);
  return {{"model", o.model_dir},
          {"seed", o.seed},
          {"scenes", t.scenes},
          {"candidates", o.config.strategy_qp.candidates},
          {"screen", o.config.strategy_qp.screen},
          {"first_feasible", o.config.strategy_qp.first_feasible},
          {"expert_plans", t.expert_plans},
          {"top1_feasible", double(t.top1) / plans},
          {"topk_feasible", double(t.topk) / plans},
          {"topk_followed", double(t.followed) / plans},
          {"own_strategy_holds", double(t.own_strategy_holds) / plans},
          {"exact_fallbacks", t.fallbacks},
          {"candidate_outcomes", t.candidate_outcomes},
          {"cost_ratio", summary(t.ratio)},
          {"cost_ratio_learned", summary(t.ratio_learned)},
          {"strategy_ms", summary(t.strategy_ms)},
          {"strategy_ms_without_fallback", summary(t.strategy_ms_learned)},
          {"expert_ms", summary(t.expert_ms)},
          {"candidates_run_per_plan", summary(t.rounds_run)},
          {"predict_ms", summary(t.predict_ms)},
          {"screen_ms", summary(t.screen_ms)},
          {"followed_rounds", summary(t.followed_rounds)},
          {"followed_rounds_ms", summary(t.followed_ms)},
          {"qp_iterations_without_fallback", summary(t.qp_iterations_learned)},
          {"us_per_qp_iteration_without_fallback", summary(t.us_per_iteration_learned)},
          {"speedup_of_medians", expert_median / strategy_median},
          {"per_scene", std::move(t.per_scene)}};
}

namespace {

// "first/second": the nodes (from 1) where a strategy first crosses the
// line and first is wholly in the target lane; "-" for never.
std::string switch_nodes(const std::string& strategy) {
  const auto node = [&strategy](char mode) {
    const std::size_t at = strategy.find(mode);
    return at == std::string::npos ? std::string("-") : std::to_string(at + 1);
  };
  return node('1') + "/" + node('2');
}

// The scenes with an expert plan where none of the k strategies held, with
// the switch nodes of the exact plan and of each candidate.
std::string unheld_scenes_markdown(const json& s) {
  run::Table table{{"scene", "behavior", "exact plan", "candidates"}, {}};
  for (const json& r : s.value("per_scene", json::array())) {
    std::string candidates;
    bool held = false;
    for (const json& c : r.at("candidates")) {
      held = held || c.at("outcome").get<std::string>().rfind("feasible", 0) == 0;
      candidates += (candidates.empty() ? "" : ", ") + switch_nodes(c.at("strategy"));
    }
    if (held) continue;
    table.rows.push_back({std::to_string(r.at("index").get<int>()),
                          r.at("behavior").get<std::string>(), switch_nodes(r.at("exact_strategy")),
                          candidates});
  }
  if (table.rows.empty()) return "";
  return "\nScenes with an expert plan where no candidate held (switch nodes: first node across "
         "the line / first wholly in the target lane):\n\n" +
         run::markdown(table);
}

std::string number(const json& v, const char* format) {
  if (!v.is_number()) return "–";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, format, v.get<double>());
  return buffer;
}

std::string percent(double share) { return number(100.0 * share, "%.1f%%"); }

std::string headline_markdown(const json& s) {
  const run::Table table{
      {"scenes", "expert plans", "top-1 feasible", "top-k feasible", "top-k followed",
       "exact fallbacks", "speedup (medians)"},
      {{std::to_string(s.at("scenes").get<long long>()),
        std::to_string(s.at("expert_plans").get<long long>()),
        percent(s.at("top1_feasible").get<double>()), percent(s.at("topk_feasible").get<double>()),
        percent(s.at("topk_followed").get<double>()),
        std::to_string(s.at("exact_fallbacks").get<long long>()),
        number(s.at("speedup_of_medians"), "%.1f")}}};
  std::string out = run::markdown(table);
  if (s.contains("own_strategy_holds")) {
    out += "\nThe exact plan's own strategy, fixed, holds in " +
           percent(s.at("own_strategy_holds").get<double>()) +
           " of the scenes with an expert plan: what a perfect vote's top-1 would get.\n";
  }
  out += "\nCandidates of the scenes with an expert plan:";
  for (const auto& [what, n] : s.at("candidate_outcomes").items()) {
    out += " " + what + " " + std::to_string(n.get<long long>()) + ";";
  }
  return out + "\n\n";
}

std::string measures_markdown(const json& s) {
  run::Table table{{"measure", "median", "p95", "worst"}, {}};
  const auto row = [&](const char* what, const json& v) {
    table.rows.push_back({what, number(v.value("median", json()), "%.4f"),
                          number(v.value("p95", json()), "%.4f"),
                          number(v.value("max", json()), "%.4f")});
  };
  row("cost / exact optimum (all expert plans)", s.at("cost_ratio"));
  row("cost / exact optimum (learned strategy followed)", s.at("cost_ratio_learned"));
  row("strategy-qp ms per plan", s.at("strategy_ms"));
  row("strategy-qp ms per plan, no fallback", s.at("strategy_ms_without_fallback"));
  row("exact expert ms per plan", s.at("expert_ms"));
  row("candidates whose rounds ran, per plan", s.at("candidates_run_per_plan"));
  row("strategy prediction ms", s.at("predict_ms"));
  row("screen ms (one QP per candidate)", s.at("screen_ms"));
  row("rounds of the candidate followed", s.at("followed_rounds"));
  row("its rounds' ms (with the collision check)", s.at("followed_rounds_ms"));
  row("QP iterations per plan, no fallback", s.at("qp_iterations_without_fallback"));
  row("µs per QP iteration (plan time / iterations), no fallback",
      s.at("us_per_qp_iteration_without_fallback"));
  return run::markdown(table);
}

}  // namespace

std::string strategy_study_markdown(const json& s) {
  return headline_markdown(s) + measures_markdown(s) + unheld_scenes_markdown(s);
}

}  // namespace lanechange::studies
