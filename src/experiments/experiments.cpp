#include "lanechange/experiments/experiments.hpp"

#include <sys/utsname.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "common/json_fields.hpp"
#include "experiments/document.hpp"
#include "experiments/figures.hpp"
#include "experiments/report.hpp"
#include "experiments/stages.hpp"
#include "experiments/tables.hpp"
#include "lanechange/baselines/baselines.hpp"
#include "lanechange/dagger/dagger.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "lanechange/learn/train.hpp"
#include "lanechange/plot.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/sumo/evaluate.hpp"

namespace lanechange::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Learning and evaluation never share scenes: other seeds.
constexpr std::uint64_t kDataSeed = 101;
constexpr std::uint64_t kEvalSeed = 2026;
// The dense-traffic Table II: cars in the target lane per scene.
constexpr Interval kDenseTargetLaneCars{4.0, 10.0};
// The dense model's data: scenes of their own (not the paper's data seeds
// 101-103, nor the evaluation's).
constexpr std::uint64_t kDenseDataSeed = 111;
// SUMO's built-in highway: light and dense traffic, cars per lane and km.
const std::vector<double> kSumoDensities{15.0, 40.0};
constexpr int kSumoSeed = 1;
constexpr std::uint64_t kTrainSeed = 1;
constexpr double kTestShare = 0.2;  // the paper's 1000 of 5000
// DAgger's training scenes (docs/dagger.md's seed), and every 2nd step labelled.
constexpr std::uint64_t kDaggerSeed = 7001;
constexpr int kDaggerStride = 2;
// DAgger's policy is an ensemble (docs/dagger.md):
// one network's seed moved the take-overs as much as a round's labels.
constexpr int kDaggerNetworks = 3;
// Round r's policy is the mean of the ensembles of rounds 0..r (docs/dagger.md):
// the deterministic form of the mixture
// of the rounds' policies that DAgger's guarantee is for, and with ensembles
// the one form whose take-overs fell with every round.
constexpr bool kDaggerAverage = true;

std::uint64_t seed_of(std::uint64_t base, std::size_t behavior) { return base + behavior; }

std::string behavior_name(Behavior b) { return std::string(to_string(b)); }

// The planners whose plans depend on the expert's lane rule.
bool uses_the_expert(const std::string& planner) {
  return planner == "miqp" || planner == "mlp-miqp" || planner == "strategy-qp";
}

std::vector<std::string> default_planners() {
  std::vector<std::string> planners = {"mlp-miqp", "miqp", "strategy-qp"};
  for (auto& name : baselines::baseline_names()) planners.push_back(std::move(name));
  planners.emplace_back("keep-lane");
  return planners;
}

void validate(const ExperimentOptions& o, const std::vector<std::string>& planners) {
  if (o.out_dir.empty()) throw InputError("--out", "must name a directory");
  if (o.eval_count < 0) throw InputError("--eval-count", "must not be negative");
  o.config.validate();
  const auto known = baselines::planner_names();
  for (const auto& p : planners) {
    if (std::find(known.begin(), known.end(), p) == known.end()) {
      std::string problem = "unknown planner \"";
      problem += p;
      problem += "\"";
      throw InputError("--planner", problem);
    }
  }
  if (fs::exists(o.out_dir) && !fs::is_directory(o.out_dir)) {
    throw InputError("--out", "exists and is not a directory");
  }
}

struct Context {
  const ExperimentOptions& options;
  run::Team& team;
  ExperimentSizes sizes;
  std::vector<std::string> planners;
  fs::path dir;
  json base_inputs;
};

std::string path_in(const Context& c, const std::string& relative) {
  return (c.dir / relative).string();
}

std::vector<std::string> per_behavior_dirs(const Context& c, const std::string& parent) {
  std::vector<std::string> dirs;
  dirs.reserve(kSampledBehaviors.size());
  for (Behavior b : kSampledBehaviors) dirs.push_back(path_in(c, parent + "/" + behavior_name(b)));
  return dirs;
}

// The options every stage's runs share: the jobs, the team, and progress
// on rank 0.
template <class RunOptions>
RunOptions run_options(const Context& c) {
  RunOptions run;
  run.jobs = c.options.jobs;
  run.team = &c.team;
  if (c.team.rank() == 0) {
    run.progress = c.options.progress;
    run.progress_on_terminal = c.options.progress_on_terminal;
  }
  return run;
}

// One data set per behavior; `gap_labels` labels every gap around the ego.
void generate_sets(const Context& c, const std::string& parent, std::uint64_t seed, long long count,
                   const Config& config, bool gap_labels = false) {
  for (std::size_t i = 0; i < kSampledBehaviors.size(); ++i) {
    data::GenerateOptions g;
    g.count = count;
    g.seed = seed_of(seed, i);
    g.behavior = kSampledBehaviors[i];
    g.out_dir = per_behavior_dirs(c, parent)[i];
    g.shard_size = std::max<long long>(1, std::min<long long>(200, count / 4));
    g.config = config;
    g.gap_labels = gap_labels;
    (void)data::generate(g, run_options<data::RunOptions>(c));
  }
}

// The scenes of the dense Table II, planned by the closed-loop expert's
// formulation: the network that learns from them drives in closed loop,
// where the expert never swings back before the line (docs/learning.md).
Config dense_config(Config config) {
  config.sampler.target_lane_cars = kDenseTargetLaneCars;
  return config;
}

Config dense_data_config(const Config& config) {
  Config dense = dense_config(config);
  dense.expert.monotone_lateral = true;
  return dense;
}

// `model`: the model directory of mlp-miqp and strategy-qp, in the run.
void evaluate_sets(const Context& c, const std::string& parent, const Config& config,
                   const std::vector<std::string>& planners, const std::string& model = "model") {
  for (std::size_t i = 0; i < kSampledBehaviors.size(); ++i) {
    sim::EvaluateOptions e;
    e.count = c.sizes.eval_per_behavior;
    e.seed = seed_of(kEvalSeed, i);
    e.behavior = kSampledBehaviors[i];
    e.planners = planners;
    e.model_dir = path_in(c, model);
    e.out_dir = per_behavior_dirs(c, parent)[i];
    e.shard_size = std::max<long long>(1, std::min<long long>(20, e.count / 4));
    e.config = config;
    e.make_planner = baselines::make_planner;
    (void)sim::evaluate(e, run_options<sim::EvaluateRun>(c));
  }
}

// Every planner in SUMO traffic: the highway at each density, and the
// CommonRoad interactive folders where the options name them. The learned
// planners use the dense model, which reads any number of cars; the paper's
// network needs a leader, a follower and a target, which SUMO's scenes often
// lack, and hands those to the expert from the start.
void evaluate_sumo(const Context& c, const std::vector<std::string>& planners) {
  sumo::EvaluateOptions e;
  e.densities = kSumoDensities;
  e.count = c.sizes.sumo_episodes;
  e.seed = kSumoSeed;
  e.planners = planners;
  e.model_dir = path_in(c, "dense/model");
  e.config = c.options.config;
  e.make_planner = baselines::make_planner;
  const auto run = run_options<sim::EvaluateRun>(c);
  e.out_dir = path_in(c, "eval/sumo/highway");
  (void)sumo::evaluate(e, run);
  if (c.options.commonroad_dir.empty()) return;
  e.densities.clear();
  e.commonroad_dir = c.options.commonroad_dir;
  e.out_dir = path_in(c, "eval/sumo/commonroad");
  (void)sumo::evaluate(e, run);
}

std::vector<sim::RolloutRow> read_sumo_rollouts(const Context& c) {
  std::vector<sim::RolloutRow> rows;
  for (const char* part : {"highway", "commonroad"}) {
    const fs::path file = c.dir / "eval" / "sumo" / part / "rollouts.csv";
    if (!fs::exists(file)) continue;
    for (auto& row : sim::read_rollouts(file.string())) rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<sim::RolloutRow> read_all_rollouts(const Context& c, const std::string& parent) {
  std::vector<sim::RolloutRow> rows;
  for (const auto& dir : per_behavior_dirs(c, parent)) {
    for (auto& row : sim::read_rollouts(dir + "/rollouts.csv")) rows.push_back(std::move(row));
  }
  return rows;
}

Scenario eval_scene(const Context& c, const std::string& behavior, long long index) {
  for (std::size_t i = 0; i < kSampledBehaviors.size(); ++i) {
    if (behavior_name(kSampledBehaviors[i]) != behavior) continue;
    const ScenarioSampler sampler(c.options.config, seed_of(kEvalSeed, i));
    return sampler.sample(static_cast<std::uint64_t>(index), kSampledBehaviors[i]);
  }
  throw InputError("behavior", "unknown behavior " + behavior);
}

// The scenes of the example figures: the most congested one the expert
// masters (the paper's Fig. 4) and three the expert plans ill-posed (Fig. 5).
std::vector<ExampleScene> example_scenes(const Context& c, const std::vector<sim::RolloutRow>& rows,
                                         const ExpertLabels& labels) {
  std::vector<ExampleScene> scenes;
  double tightest = 1e300;
  ExampleScene congested;
  for (const auto& r : rows) {
    if (r.planner != "miqp" || !r.success()) continue;
    const Scenario s = eval_scene(c, r.behavior, r.index);
    const double gap = s.target().x - s.follower().x -
                       0.5 * (s.size_of(Role::Target).length + s.size_of(Role::Follower).length);
    if (gap < tightest) {
      tightest = gap;
      congested = {"congested", r.behavior, r.index, "the tightest gap the expert masters"};
    }
  }
  if (!congested.name.empty()) scenes.push_back(congested);
  std::set<std::pair<std::string, long long>> evaluated;
  for (const auto& r : rows) evaluated.insert({r.behavior, r.index});
  int ill_posed = 0;
  for (const auto& [key, label] : labels) {
    if (label != "ill_posed" || evaluated.count(key) == 0) continue;
    if (!scenes.empty() && scenes.front().behavior == key.first &&
        scenes.front().index == key.second) {
      continue;  // already the congested example
    }
    scenes.push_back({"ill_posed_" + std::to_string(++ill_posed), key.first, key.second,
                      "planned ill-posed by the expert, open loop"});
    if (static_cast<int>(scenes.size()) >= c.sizes.example_scenes) break;
  }
  return scenes;
}

void draw_examples(const Context& c, const std::vector<ExampleScene>& scenes) {
  for (const auto& scene : scenes) {
    const Scenario s = eval_scene(c, scene.behavior, scene.index);
    for (const auto& planner_name : c.planners) {
      if (planner_name == "keep-lane") continue;
      const auto planner =
          baselines::make_planner(planner_name, c.options.config, path_in(c, "model"));
      const sim::Rollout rollout = sim::simulate(s, *planner, c.options.config);
      const std::string stem = path_in(c, "figures/" + scene.name + "_" + planner_name);
      sim::save_rollout(rollout, stem + ".json");
      PlotOptions plot;
      plot.vehicle = s.vehicle;
      plot_trajectory(rollout.trajectory, stem + ".png", plot);
    }
  }
}

learn::TrainOptions train_options(const Context& c) {
  learn::TrainOptions t;
  t.data_dirs = per_behavior_dirs(c, "data");
  t.out_dir = path_in(c, "model");
  t.seed = kTrainSeed;
  t.test_share = kTestShare;
  t.jobs = c.options.jobs;
  t.search.quick = c.sizes.quick_search;
  t.network.max_epochs = c.sizes.max_epochs;
  t.plots = c.options.figures;
  t.progress = c.options.progress;
  return t;
}

void train(const Context& c) { (void)learn::train_models(train_options(c)); }

// The dense model: the same training on the dense data, its network
// driving to the gap its gap classifier names.
void train_dense(const Context& c) {
  learn::TrainOptions t = train_options(c);
  t.data_dirs = per_behavior_dirs(c, "dense/data");
  t.out_dir = path_in(c, "dense/model");
  t.network.inputs = learn::NetworkInputs::Gap;
  t.plots = false;
  (void)learn::train_models(t);
}

// DAgger from the experiments' data, settings and seed, its round 0 the
// experiments' model with an ensemble in place of the paper's one network
// (the same classifiers: the same data and seed); its rounds' models,
// labels and evaluations stay under dagger/.
dagger::DaggerOptions dagger_options(const Context& c) {
  dagger::DaggerOptions d;
  d.train = train_options(c);
  d.train.out_dir = path_in(c, "dagger/model");
  d.train.plots = false;
  d.train.network.networks = kDaggerNetworks;
  d.average = kDaggerAverage;
  d.work_dir = path_in(c, "dagger/rounds");
  d.rounds = c.sizes.dagger_rounds;
  d.scenes = c.sizes.dagger_scenes;
  d.scene_seed = kDaggerSeed;
  d.stride = kDaggerStride;
  d.eval_count = 3 * c.sizes.eval_per_behavior;
  d.eval_seed = kEvalSeed;
  d.config = c.options.config;
  d.jobs = c.options.jobs;
  return d;
}

bool runs_dagger(const Context& c) {
  return c.sizes.dagger_rounds > 0 &&
         std::find(c.planners.begin(), c.planners.end(), "mlp-miqp") != c.planners.end();
}

void draw_summary_figures(const Context& c, const std::vector<sim::RolloutRow>& rows) {
  plot_success_bars(rows, c.planners, path_in(c, "figures/success.png"));
  plot_step_times(rows, c.planners, path_in(c, "figures/step_times.png"));
  const fs::path confusion = c.dir / "model" / "confusion_plain_svm.png";
  if (fs::exists(confusion)) {
    fs::copy_file(confusion, c.dir / "figures" / "confusion_svm.png",
                  fs::copy_options::overwrite_existing);
  }
}

}  // namespace

std::string_view to_string(Scale scale) {
  switch (scale) {
    case Scale::Tiny: return "tiny";
    case Scale::Small: return "small";
    case Scale::Paper: return "paper";
  }
  return "?";
}

Scale scale_from_string(std::string_view name, std::string_view field) {
  for (Scale s : {Scale::Tiny, Scale::Small, Scale::Paper}) {
    if (to_string(s) == name) return s;
  }
  std::string problem = "unknown scale \"";
  problem += name;
  problem += "\" (known: tiny, small, paper)";
  throw InputError(std::string(field), problem);
}

ExperimentSizes sizes_of(Scale scale) {
  switch (scale) {
    case Scale::Tiny: return {12, 2, true, 20, 2, 1, 3, 1};
    case Scale::Small: return {150, 20, true, 150, 4, 2, 40, 10};
    case Scale::Paper: return {5000, 500, false, 300, 4, 4, 150, 100};
  }
  return {};
}

ExperimentReport run_experiments(const ExperimentOptions& o) {
  const auto planners = o.planners.empty() ? default_planners() : o.planners;
  validate(o, planners);
  const auto start = std::chrono::steady_clock::now();
  run::Team& team = run::team_or_alone(o.team);
  Context c{o, team, sizes_of(o.scale), planners, fs::path(o.out_dir), {}};
  if (o.eval_count > 0) c.sizes.eval_per_behavior = o.eval_count;
  (void)run::decide_on_rank_zero(team, "--out", [&] {
    fs::create_directories(c.dir);
    return 0;
  });
  json config;
  to_json(config, o.config);
  c.base_inputs = {{"code_version", code_version()}, {"config", config}};
  StageRunner stages(o.out_dir, o.progress, team);

  const std::string data = stages.run(
      "data", {{"base", c.base_inputs}, {"count", c.sizes.data_per_behavior}, {"seed", kDataSeed}},
      {"data"}, StageRunner::Ranks::All,
      [&] { generate_sets(c, "data", kDataSeed, c.sizes.data_per_behavior, o.config); });
  const std::string models = stages.run("models",
                                        {{"data", data},
                                         {"seed", kTrainSeed},
                                         {"test_share", kTestShare},
                                         {"quick", c.sizes.quick_search},
                                         {"max_epochs", c.sizes.max_epochs},
                                         {"figures", o.figures}},
                                        {"model"}, StageRunner::Ranks::First, [&] { train(c); });
  const std::string labels = stages.run(
      "expert-labels",
      {{"base", c.base_inputs}, {"count", c.sizes.eval_per_behavior}, {"seed", kEvalSeed}},
      {"labels"}, StageRunner::Ranks::All,
      [&] { generate_sets(c, "labels", kEvalSeed, c.sizes.eval_per_behavior, o.config); });
  json eval_inputs = {{"base", c.base_inputs},
                      {"models", models},
                      {"count", c.sizes.eval_per_behavior},
                      {"seed", kEvalSeed},
                      {"planners", planners}};
  const std::string footprint =
      stages.run("evaluate-footprint", eval_inputs, {"eval/footprint"}, StageRunner::Ranks::All,
                 [&] { evaluate_sets(c, "eval/footprint", o.config, planners); });
  // The baselines know no lane rule: their rows are those of the default run.
  std::vector<std::string> expert_planners;
  for (const auto& p : planners) {
    if (uses_the_expert(p)) expert_planners.push_back(p);
  }
  Config either_or = o.config;
  either_or.expert.lane_rule = LaneRule::EitherOr;
  eval_inputs["lane_rule"] = "either_or";
  eval_inputs["planners"] = expert_planners;
  if (!expert_planners.empty()) {
    (void)stages.run("evaluate-either_or", eval_inputs, {"eval/either_or"}, StageRunner::Ranks::All,
                     [&] { evaluate_sets(c, "eval/either_or", either_or, expert_planners); });
  }
  // Every planner again on the same scenes under the paper's own formulation
  // and traffic, so that the reproduction of the paper stays visible.
  eval_inputs["planners"] = planners;
  eval_inputs.erase("lane_rule");
  eval_inputs["formulation"] = "paper";
  (void)stages.run("evaluate-paper", eval_inputs, {"eval/paper"}, StageRunner::Ranks::All,
                   [&] { evaluate_sets(c, "eval/paper", paper_formulation(o.config), planners); });
  // And in dense traffic: the same count of scenes, each with a platoon in
  // the target lane; the learned planners use a model of their own, learned
  // from dense scenes, whose network drives to the gap its classifier names.
  const Config dense_data = dense_data_config(o.config);
  json dense_data_config_json;
  to_json(dense_data_config_json, dense_data);
  const std::string dense_data_stage = stages.run(
      "dense-data",
      {{"base", c.base_inputs},
       {"config", dense_data_config_json},
       {"count", c.sizes.data_per_behavior},
       {"seed", kDenseDataSeed},
       {"gap_labels", true}},
      {"dense/data"}, StageRunner::Ranks::All, [&] {
        generate_sets(c, "dense/data", kDenseDataSeed, c.sizes.data_per_behavior, dense_data, true);
      });
  const std::string dense_model =
      stages.run("dense-model",
                 {{"data", dense_data_stage},
                  {"seed", kTrainSeed},
                  {"test_share", kTestShare},
                  {"quick", c.sizes.quick_search},
                  {"max_epochs", c.sizes.max_epochs},
                  {"network_inputs", "gap"}},
                 {"dense/model"}, StageRunner::Ranks::First, [&] { train_dense(c); });
  eval_inputs.erase("formulation");
  eval_inputs["target_lane_cars"] = {kDenseTargetLaneCars.lo, kDenseTargetLaneCars.hi};
  eval_inputs["dense_model"] = dense_model;
  (void)stages.run("evaluate-dense", eval_inputs, {"eval/dense"}, StageRunner::Ranks::All, [&] {
    evaluate_sets(c, "eval/dense", dense_config(o.config), planners, "dense/model");
  });
  // And in SUMO's traffic, which reacts and changes lanes (docs/sumo.md).
  eval_inputs.erase("target_lane_cars");
  eval_inputs["count"] = c.sizes.sumo_episodes;
  eval_inputs["sumo_highway"] = kSumoDensities;
  eval_inputs["seed"] = kSumoSeed;
  eval_inputs["commonroad"] = o.commonroad_dir.empty() ? json() : json(o.commonroad_dir);
  (void)stages.run("evaluate-sumo", eval_inputs, {"eval/sumo"}, StageRunner::Ranks::All,
                   [&] { evaluate_sumo(c, planners); });
  json figure_inputs = {{"evaluation", footprint}, {"labels", labels}};
  if (runs_dagger(c)) {
    figure_inputs["dagger"] = stages.run("dagger",
                                         {{"base", c.base_inputs},
                                          {"models", models},
                                          {"rounds", c.sizes.dagger_rounds},
                                          {"scenes", c.sizes.dagger_scenes},
                                          {"eval_count", 3 * c.sizes.eval_per_behavior},
                                          {"networks", kDaggerNetworks},
                                          {"average", kDaggerAverage},
                                          // Scored with the step budget lifted.
                                          {"scoring", "untimed"}},
                                         {"dagger"}, StageRunner::Ranks::First, [&] {
                                           (void)dagger::run(dagger_options(c), c.options.progress);
                                         });
  }
  ExperimentReport out;
  if (team.rank() != 0) {
    // The figures and the report are rank 0's; the others wait for it.
    if (o.figures) {
      (void)stages.run("figures", figure_inputs, {"figures"}, StageRunner::Ranks::First, [] {});
    }
    out.stages = stages.records();
    return out;
  }
  const auto rows = read_all_rollouts(c, "eval/footprint");
  const ExpertLabels expert_labels = read_expert_labels(per_behavior_dirs(c, "labels"));
  const auto examples = example_scenes(c, rows, expert_labels);
  if (o.figures) {
    (void)stages.run("figures", figure_inputs, {"figures"}, StageRunner::Ranks::First, [&] {
      fs::create_directories(c.dir / "figures");
      draw_summary_figures(c, rows);
      if (runs_dagger(c)) {
        plot_dagger(dagger::read_report(dagger_options(c).work_dir),
                    path_in(c, "figures/dagger.png"));
      }
      draw_examples(c, examples);
    });
  }
  ReportInputs report;
  report.options = &o;
  report.sizes = c.sizes;
  report.planners = planners;
  report.expert_planners = expert_planners;
  report.metrics = json::parse(std::ifstream(c.dir / "model" / "metrics.json"));
  report.footprint = rows;
  if (!expert_planners.empty()) {
    report.either_or = read_all_rollouts(c, "eval/either_or");
    for (const auto& r : rows) {
      if (!uses_the_expert(r.planner)) report.either_or.push_back(r);
    }
  }
  report.paper = read_all_rollouts(c, "eval/paper");
  report.dense = read_all_rollouts(c, "eval/dense");
  report.dense_metrics = json::parse(std::ifstream(c.dir / "dense" / "model" / "metrics.json"));
  report.dense_target_lane_cars = kDenseTargetLaneCars;
  report.sumo = read_sumo_rollouts(c);
  report.sumo_densities = kSumoDensities;
  report.car_decel_limit = o.config.traffic.max_decel;
  report.labels = expert_labels;
  if (runs_dagger(c)) {
    const auto d = dagger_options(c);
    report.dagger = dagger::read_report(d.work_dir);
    report.dagger_options = d;
  }
  report.examples = examples;
  report.seeds = {{"data", kDataSeed},
                  {"dense data", kDenseDataSeed},
                  {"evaluation", kEvalSeed},
                  {"train", kTrainSeed}};
  report.stages = stages.records();
  out.stages = stages.records();
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.wall_s = out.wall_s;
  const Document document = build_report(report);
  out.report_md = path_in(c, "report.md");
  out.report_html = path_in(c, "report.html");
  lanechange::detail::write_file_atomically(out.report_md, document.markdown());
  lanechange::detail::write_file_atomically(
      out.report_html, document.html(o.out_dir, "lanechange: the paper's experiments"));
  return out;
}

}  // namespace lanechange::experiments
