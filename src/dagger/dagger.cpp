// DAgger rounds (docs/dagger.md): round 0 is the model trained
// on the expert's data; round r rolls round r-1's network out on fresh
// training scenes, has the expert label the states it visits, adds them to
// the aggregated data set and trains the network again on everything. Each
// step leaves its result on disk, so a killed run resumes where it stopped.
#include "lanechange/dagger/dagger.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/json_fields.hpp"
#include "dagger/collect.hpp"
#include "data/manifest.hpp"
#include "lanechange/error.hpp"
#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/learn/model.hpp"
#include "lanechange/run/markdown.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "planner/mlp_miqp_planner.hpp"
#include "sim/evaluation_files.hpp"

namespace lanechange::dagger {

namespace fs = std::filesystem;

std::string_view to_string(Rollout rollout) {
  return rollout == Rollout::Gated ? "gated" : "network";
}

Rollout parse_rollout(std::string_view name, const char* field) {
  if (name == "network") return Rollout::Network;
  if (name == "gated") return Rollout::Gated;
  throw InputError(field, "must be \"network\" or \"gated\", not \"" + std::string(name) + "\"");
}

using nlohmann::json;

namespace {

std::string model_dir(const DaggerOptions& o, int round) {
  return (fs::path(o.work_dir) / ("model-" + std::to_string(round))).string();
}
std::string data_dir(const DaggerOptions& o) { return (fs::path(o.work_dir) / "data").string(); }
bool has_model(const std::string& dir) { return fs::exists(fs::path(dir) / learn::kModelFile); }

void require(bool ok, const char* field, const std::string& problem) {
  if (!ok) throw InputError(field, problem);
}

void validate(const DaggerOptions& o) {
  require(o.rounds >= 0 && o.rounds <= 100, "--rounds", "rounds must be in [0, 100]");
  require(o.scenes >= 1, "--scenes", "must be at least 1");
  require(o.stride >= 1, "--stride", "must be at least 1");
  require(o.label_nodes >= 0, "--label-nodes", "must be at least 0 (0: whole plans)");
  require(o.past_takeover_s >= 0.0 && o.past_takeover_s <= 60.0, "--past-takeover",
          "must be in [0, 60] s");
  require(o.past_takeover_s == 0.0 || o.rollout == Rollout::Gated, "--past-takeover",
          "only goes with --rollout gated");
  require(!o.label_lookahead || o.rollout == Rollout::Gated, "--label-lookahead",
          "only goes with --rollout gated");
  require(o.beta >= 0.0 && o.beta <= 1.0, "--beta", "must be in [0, 1]");
  require(o.beta == 0.0 || o.rollout == Rollout::Network, "--beta",
          "only goes with --rollout network: gated rollouts hand steps to the expert "
          "at the take-over");
  require(o.retrain_learning_rate >= 0.0 && o.retrain_learning_rate <= 1.0, "--learning-rate",
          "must be in [0, 1] (0: round 0's)");
  require(o.eval_count >= 1, "--eval-count", "must be at least 1");
  require(o.candidates >= 1 && o.candidates <= 20, "--candidates", "must be in [1, 20]");
  require(o.select_count >= 1, "--select-count", "must be at least 1");
  require(o.candidates == 1 || (o.select_seed != o.eval_seed && o.select_seed != o.scene_seed),
          "--select-seed",
          "must differ from --eval-seed and --scene-seed: selection scenes are neither "
          "held out nor labelled");
  require(o.eval_seed != o.scene_seed, "--eval-seed",
          "must differ from --scene-seed: the evaluation scenes must be held out");
  require(o.label_time_limit_s > 0.0, "label_time_limit_s", "must be positive");
  require(!o.work_dir.empty(), "--dir", "must not be empty");
  require(!o.train.out_dir.empty(), "--out", "must not be empty");
  require(!o.train.data_dirs.empty(), "--data", "at least one data set is needed");
  const fs::path out(o.train.out_dir);
  require(!fs::exists(out) || fs::is_empty(out) || has_model(o.train.out_dir), "--out",
          o.train.out_dir + " is not empty and holds no model; refusing to replace it");
  for (const std::string& dir : o.train.data_dirs) {
    require(fs::is_directory(dir), "--data", dir + " is not a directory");
  }
  require(o.base_model.empty() || has_model(o.base_model), "base_model",
          o.base_model + " holds no model");
}

// What fixes the run's content; a resume must match it (rounds may grow).
json run_parameters(const DaggerOptions& o) {
  const json config = o.config;
  json p = {{"data", o.train.data_dirs},
            {"train", o.train.config()},
            {"scenes_per_round", o.scenes},
            {"scene_seed", o.scene_seed},
            {"stride", o.stride},
            {"label_nodes", o.label_nodes},
            {"eval_count", o.eval_count},
            {"eval_seed", o.eval_seed},
            {"label_time_limit_s", o.label_time_limit_s},
            {"max_epochs", o.train.network.max_epochs},
            {"every_scene", o.every_scene},
            {"rollout", to_string(o.rollout)},
            {"past_takeover_s", o.past_takeover_s},
            {"fine_tune", o.fine_tune},
            {"validate_on_dagger", o.validate_on_dagger},
            {"base_model", o.base_model},
            {"config", config}};
  // Only when on: the runs from before the option resume as before.
  if (o.label_lookahead) p["label_lookahead"] = true;
  if (o.fixed_strategy) p["fixed_strategy"] = true;
  if (o.average) p["average"] = true;
  if (o.beta > 0.0) p["beta"] = o.beta;
  if (o.retrain_learning_rate > 0.0) p["retrain_learning_rate"] = o.retrain_learning_rate;
  if (o.candidates > 1) {
    p["candidates"] = o.candidates;
    p["select_count"] = o.select_count;
    p["select_seed"] = o.select_seed;
  }
  return p;
}

void prepare_work_dir(const DaggerOptions& o) {
  const fs::path file = fs::path(o.work_dir) / "dagger.json";
  const json parameters = run_parameters(o);
  if (fs::exists(file)) {
    if (lanechange::detail::read_json_file(file.string()) != parameters) {
      throw InputError("--dir", o.work_dir +
                                    " holds a DAgger run with other parameters; use a new "
                                    "directory or the same options");
    }
    return;
  }
  if (fs::exists(o.work_dir) && !fs::is_empty(o.work_dir)) {
    throw InputError("--dir", o.work_dir + " is not empty and holds no DAgger run");
  }
  fs::create_directories(o.work_dir);
  lanechange::detail::write_file_atomically(file.string(), parameters.dump(2) + "\n");
}

// driven[i]: whether the classifier lets the network drive held-out scene i
// (empty for the reference planner).
RoundRow score(const std::string& rollouts_csv, const std::string& planner, int round,
               const std::vector<char>& driven) {
  const std::vector<sim::RolloutRow> all = sim::read_rollouts(rollouts_csv);
  std::vector<const sim::RolloutRow*> mine;
  RoundRow row;
  for (const sim::RolloutRow& r : all) {
    if (r.planner != planner) continue;
    mine.push_back(&r);
    const auto i = static_cast<std::size_t>(r.index);
    if (i >= driven.size() || driven[i] == 0) continue;
    ++row.driven;
    if (std::isnan(r.first_takeover_t)) continue;
    ++(r.first_takeover_t == 0.0 ? row.taken_over_at_start : row.taken_over_later);
  }
  const sim::RolloutRates rates = sim::rates_of(mine);
  row.round = round;
  row.planner = planner;
  row.rollouts = rates.rollouts;
  row.success_rate = rates.success;
  row.takeovers_per_rollout = rates.takeovers;
  row.collision_rate = rates.collision;
  row.at_fault_collision_rate = rates.at_fault;
  return row;
}

// Which held-out scenes round 0's classifier lets the network drive; the
// rounds share it, as they share its classifiers.
std::vector<char> driven_scenes(const DaggerOptions& o) {
  const auto model = std::make_shared<const learn::Model>(learn::Model::load(model_dir(o, 0)));
  const planner::MlpMiqpPlanner learner(o.config, model,
                                        std::make_shared<expert::FastLaneChangeSolver>());
  const ScenarioSampler sampler(o.config, o.eval_seed);
  std::vector<char> driven(static_cast<std::size_t>(o.eval_count));
  for (std::size_t i = 0; i < driven.size(); ++i) {
    driven[i] = learner.tries(sampler.sample(static_cast<std::uint64_t>(i))) ? 1 : 0;
  }
  return driven;
}

struct Scenes {
  long long count;
  std::uint64_t seed;
};

Scenes held_out(const DaggerOptions& o) { return {o.eval_count, o.eval_seed}; }

// One planner's evaluation on `scenes`; evaluate resumes on its own.
RoundRow evaluate(const DaggerOptions& o, Scenes scenes, const std::string& planner,
                  const std::string& model, const std::string& name, int round,
                  const std::vector<char>& driven, std::ostream* progress) {
  sim::EvaluateOptions e;
  e.count = scenes.count;
  e.seed = scenes.seed;
  e.planners = {planner};
  e.model_dir = model;
  e.out_dir = (fs::path(o.work_dir) / name).string();
  e.config = detail::untimed(o.config);
  sim::EvaluateRun run;
  run.jobs = o.jobs;
  run.progress = progress;
  (void)sim::evaluate(e, run);
  RoundRow row = score((fs::path(e.out_dir) / "rollouts.csv").string(), planner, round, driven);
  if (progress != nullptr) {
    *progress << "dagger: "
              << (round < 0 ? std::string("reference") : "round " + std::to_string(round)) << " ("
              << name << "), " << planner << ": success " << row.success_rate
              << ", take-overs per rollout " << row.takeovers_per_rollout << ", collisions "
              << row.collision_rate << std::endl;
  }
  return row;
}

// The aggregated data set: one shard per round, listed in the manifest's
// parameters.dagger.shards with how many well-posed labels each holds.
// The implicit noexcept move sees nlohmann::json's invariant check
// (JSON_ASSERT) as a possible throw.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct Aggregate {
  json parameters;
  std::vector<data::ShardRange> shards;
  std::vector<long long> labelled;
  std::vector<long long> samples;  // well-posed rows
  [[nodiscard]] long long count() const {
    return shards.empty() ? 0 : shards.back().first + shards.back().count;
  }
};

Aggregate read_aggregate(const DaggerOptions& o) {
  Aggregate a;
  const json data_config =
      data::read_manifest(o.train.data_dirs.front()).at("parameters").at("config");
  const json closed_loop = o.config;
  a.parameters = {{"version", LANECHANGE_VERSION},
                  {"count", 0},
                  {"seed", o.scene_seed},
                  {"behavior", "all"},
                  {"solver", "fast"},
                  {"time_limit_s", o.label_time_limit_s},
                  {"config", data_config},
                  {"dagger",
                   {{"labels",
                     "the closed-loop expert (miqp's re-plan) from states the action "
                     "network visits; node 0 is the visited state"},
                    {"stride", o.stride},
                    {"label_nodes", o.label_nodes},
                    {"rollout", to_string(o.rollout)},
                    {"past_takeover_s", o.past_takeover_s},
                    {"label_lookahead", o.label_lookahead},
                    {"scenes_per_round", o.scenes},
                    {"closed_loop_config", closed_loop},
                    {"shards", json::array()}}}};
  if (o.fixed_strategy) a.parameters["dagger"]["fixed_strategy"] = true;
  if (!fs::exists(fs::path(data_dir(o)) / data::kManifestName)) return a;
  data::remove_stale_temporaries(data_dir(o));  // a killed round's shard
  const json old = data::read_manifest(data_dir(o)).at("parameters");
  for (const json& s : old.at("dagger").at("shards")) {
    a.shards.push_back({s.at("index").get<long long>(), s.at("first").get<long long>(),
                        s.at("count").get<long long>()});
    a.labelled.push_back(s.at("well_posed_labels").get<long long>());
    a.samples.push_back(s.value("well_posed_samples", a.labelled.back()));
    a.parameters["dagger"]["shards"].push_back(s);
  }
  return a;
}

// Ross et al.'s beta_i = p^(i-1) with their first iteration our round 0,
// the expert's own data.
double expert_share(const DaggerOptions& o, int round) {
  return o.beta > 0.0 ? std::pow(o.beta, round) : 0.0;
}

void add_round(Aggregate& a, const DaggerOptions& o, int round, std::ostream* progress) {
  const auto model =
      std::make_shared<const learn::Model>(learn::Model::load(model_dir(o, round - 1)));
  const planner::MlpMiqpPlanner learner(o.config, model,
                                        std::make_shared<expert::FastLaneChangeSolver>());
  fs::create_directories(data_dir(o));
  const detail::CollectJob job{
      learner,
      o.config,
      o.scene_seed,
      (round - 1) * o.scenes,
      o.scenes,
      {o.stride, o.label_nodes, o.label_time_limit_s, o.every_scene, o.rollout == Rollout::Gated,
       o.past_takeover_s, o.label_lookahead, o.fixed_strategy, expert_share(o, round)},
      o.jobs,
      progress};
  const detail::RoundData got = detail::collect_round(job, data_dir(o), round - 1, a.count());
  a.shards.push_back(got.range);
  a.labelled.push_back(got.labelled);
  a.samples.push_back(got.samples);
  a.parameters["dagger"]["shards"].push_back({{"index", got.range.shard},
                                              {"round", round},
                                              {"model", model_dir(o, round - 1)},
                                              {"first", got.range.first},
                                              {"count", got.range.count},
                                              {"first_scene", job.first_scene},
                                              {"scenes_refused", got.refused},
                                              {"well_posed_labels", got.labelled},
                                              {"well_posed_samples", got.samples}});
  if (job.labelling.expert_share > 0.0) {
    a.parameters["dagger"]["shards"].back()["expert_share"] = job.labelling.expert_share;
  }
  a.parameters["count"] = a.count();
  char host[256] = {};
  (void)::gethostname(host, sizeof host - 1);
  const json run = {{"host", host}, {"ranks", 1}, {"jobs_per_rank", o.jobs}};
  data::write_manifest_of_shards(data_dir(o), a.parameters, run, a.shards);
  if (progress != nullptr) {
    *progress << "dagger: round " << round << ": " << o.scenes - got.refused
              << " scenes rolled out, " << got.range.count << " expert queries, " << got.labelled
              << " well-posed labels" << std::endl;
  }
}

// The last round's model, published at --out as train publishes its own.
void publish_copy(const std::string& from, const std::string& to) {
  fs::path out = fs::path(to).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();
  const fs::path staging = out.string() + ".tmp." + std::to_string(::getpid());
  fs::remove_all(staging);
  fs::copy(from, staging, fs::copy_options::recursive);
  fs::remove_all(out);
  fs::rename(staging, out);
}

void write_tables(const DaggerOptions& o, const DaggerReport& report) {
  std::string csv = sim::detail::csv_header(table_columns());
  std::vector<RoundRow> rows = report.rounds;
  rows.push_back(report.expert);
  for (const RoundRow& r : rows) {
    const std::vector<std::string> cells = {std::to_string(r.round),
                                            r.planner,
                                            std::to_string(r.rollouts),
                                            std::to_string(r.success_rate),
                                            std::to_string(r.takeovers_per_rollout),
                                            std::to_string(r.collision_rate),
                                            std::to_string(r.at_fault_collision_rate),
                                            std::to_string(r.driven),
                                            std::to_string(r.taken_over_at_start),
                                            std::to_string(r.taken_over_later),
                                            std::to_string(r.labels),
                                            std::to_string(r.dagger_samples)};
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (i > 0) csv += ',';
      csv += cells[i];
    }
    csv += '\n';
  }
  const fs::path dir(o.work_dir);
  lanechange::detail::write_file_atomically((dir / "dagger.csv").string(), csv);
  lanechange::detail::write_file_atomically((dir / "dagger.md").string(), markdown_table(report));
}

void retrain(const DaggerOptions& o, int round, const std::string& out,
             std::uint64_t network_seed_offset) {
  learn::RetrainOptions retrain;
  retrain.base_model = model_dir(o, 0);
  retrain.data_dirs = o.train.data_dirs;
  retrain.data_dirs.push_back(data_dir(o));
  retrain.out_dir = out;
  retrain.network = o.train.network;
  if (o.retrain_learning_rate > 0.0) retrain.network.learning_rate = o.retrain_learning_rate;
  retrain.plots = o.train.plots;
  retrain.progress = o.train.progress;
  retrain.validate_on_added = o.validate_on_dagger;
  retrain.network_seed_offset = network_seed_offset;
  if (o.fine_tune) retrain.warm_start = model_dir(o, round - 1);
  if (o.average) retrain.average_with = model_dir(o, round - 1);
  retrain.note = {{"dagger_round", round}, {"data", data_dir(o)}};
  (void)learn::retrain_network(retrain);
}

// Round r's candidates, each retrained and measured on the selection scenes
// (each step resumes), and the best published as model-r. The held-out
// scenes play no part in the choice.
void select_retrain(const DaggerOptions& o, int round, std::vector<Candidate>& table,
                    std::ostream* progress) {
  const auto candidate_dir = [&](int j) {
    return (fs::path(o.work_dir) /
            ("round-" + std::to_string(round) + "-candidate-" + std::to_string(j)))
        .string();
  };
  const auto first = static_cast<std::ptrdiff_t>(table.size());
  for (int j = 0; j < o.candidates; ++j) {
    const auto offset = static_cast<std::uint64_t>(j);
    if (!has_model(candidate_dir(j))) retrain(o, round, candidate_dir(j), offset);
    const RoundRow row =
        evaluate(o, {o.select_count, o.select_seed}, "mlp-miqp", candidate_dir(j),
                 "select-" + std::to_string(round) + "-" + std::to_string(j), round, {}, progress);
    table.push_back({round, j, offset, row.takeovers_per_rollout, row.success_rate, false});
  }
  // Fewest take-overs, then the higher success; the first of equals.
  Candidate& best = *std::min_element(
      table.begin() + first, table.end(), [](const Candidate& a, const Candidate& b) {
        return a.takeovers_per_rollout < b.takeovers_per_rollout ||
               (a.takeovers_per_rollout == b.takeovers_per_rollout &&
                a.success_rate > b.success_rate);
      });
  best.chosen = true;
  if (!has_model(model_dir(o, round)))
    publish_copy(candidate_dir(best.candidate), model_dir(o, round));
  if (progress != nullptr) {
    *progress << "dagger: round " << round << ": candidate " << best.candidate
              << " chosen (take-overs per rollout on the selection scenes "
              << best.takeovers_per_rollout << ")" << std::endl;
  }
}

void write_selection(const DaggerOptions& o, const std::vector<Candidate>& table) {
  std::string csv =
      "round,candidate,network_seed_offset,takeovers_per_rollout,success_rate,chosen\n";
  for (const Candidate& c : table) {
    csv += std::to_string(c.round) + ',' + std::to_string(c.candidate) + ',' +
           std::to_string(c.network_seed_offset) + ',' + std::to_string(c.takeovers_per_rollout) +
           ',' + std::to_string(c.success_rate) + ',' + (c.chosen ? "1" : "0") + '\n';
  }
  lanechange::detail::write_file_atomically((fs::path(o.work_dir) / "selection.csv").string(), csv);
}

}  // namespace

std::vector<std::string> table_columns() {
  return {"round",
          "planner",
          "rollouts",
          "success_rate",
          "takeovers_per_rollout",
          "collision_rate",
          "at_fault_collision_rate",
          "driven",
          "taken_over_at_start",
          "taken_over_later",
          "labels",
          "dagger_samples"};
}

std::string markdown_table(const DaggerReport& report) {
  run::Table table{
      {"round", "planner", "rollouts", "success", "take-overs per rollout", "collisions",
       "at-fault collisions", "network drives", "taken over at the start", "taken over later",
       "new well-posed labels", "DAgger samples so far"},
      {}};
  std::vector<RoundRow> rows = report.rounds;
  rows.push_back(report.expert);
  const auto format = [](const char* pattern, double value) {
    char text[32];
    std::snprintf(text, sizeof text, pattern, value);
    return std::string(text);
  };
  for (const RoundRow& r : rows) {
    table.rows.push_back(
        {r.round < 0 ? "-" : std::to_string(r.round), r.planner, std::to_string(r.rollouts),
         format("%.1f%%", 100.0 * r.success_rate), format("%.2f", r.takeovers_per_rollout),
         format("%.1f%%", 100.0 * r.collision_rate),
         format("%.1f%%", 100.0 * r.at_fault_collision_rate), std::to_string(r.driven),
         std::to_string(r.taken_over_at_start), std::to_string(r.taken_over_later),
         std::to_string(r.labels), std::to_string(r.dagger_samples)});
  }
  return run::markdown(table);
}

DaggerReport read_report(const std::string& work_dir) {
  const std::string path = (fs::path(work_dir) / "dagger.csv").string();
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open the DAgger table");
  std::string line;
  std::getline(in, line);
  if (line + "\n" != sim::detail::csv_header(table_columns())) {
    throw InputError(path, "is not a DAgger table of this version (its header differs)");
  }
  DaggerReport report;
  long long number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::istringstream cells(line);
    RoundRow r;
    std::string round;
    std::string rollouts;
    std::vector<std::string> rest(9);
    std::getline(cells, round, ',');
    std::getline(cells, r.planner, ',');
    std::getline(cells, rollouts, ',');
    for (std::string& cell : rest) std::getline(cells, cell, ',');
    try {
      r.round = std::stoi(round);
      r.rollouts = std::stoll(rollouts);
      r.success_rate = std::stod(rest[0]);
      r.takeovers_per_rollout = std::stod(rest[1]);
      r.collision_rate = std::stod(rest[2]);
      r.at_fault_collision_rate = std::stod(rest[3]);
      r.driven = std::stoll(rest[4]);
      r.taken_over_at_start = std::stoll(rest[5]);
      r.taken_over_later = std::stoll(rest[6]);
      r.labels = std::stoll(rest[7]);
      r.dagger_samples = std::stoll(rest[8]);
    } catch (const std::exception&) {
      throw InputError(path, "line " + std::to_string(number) + " is malformed");
    }
    (r.round < 0 ? report.expert : report.rounds.emplace_back()) = r;
  }
  if (report.rounds.empty()) throw InputError(path, "holds no round");
  return report;
}

DaggerReport run(const DaggerOptions& options, std::ostream* progress) {
  validate(options);
  prepare_work_dir(options);
  DaggerReport report;
  if (!has_model(model_dir(options, 0)) && !options.base_model.empty()) {
    publish_copy(options.base_model, model_dir(options, 0));
  } else if (!has_model(model_dir(options, 0))) {
    learn::TrainOptions train = options.train;
    train.out_dir = model_dir(options, 0);
    (void)learn::train_models(train);
  }
  report.expert = evaluate(options, held_out(options), "miqp", "", "eval-miqp", -1, {}, progress);
  const std::vector<char> driven = driven_scenes(options);
  report.rounds.push_back(evaluate(options, held_out(options), "mlp-miqp", model_dir(options, 0),
                                   "eval-0", 0, driven, progress));
  Aggregate aggregate = read_aggregate(options);
  long long samples = 0;
  for (int r = 1; r <= options.rounds; ++r) {
    if (static_cast<int>(aggregate.shards.size()) < r) add_round(aggregate, options, r, progress);
    if (options.candidates > 1) {
      select_retrain(options, r, report.candidates, progress);
    } else if (!has_model(model_dir(options, r))) {
      retrain(options, r, model_dir(options, r), 0);
    }
    RoundRow row = evaluate(options, held_out(options), "mlp-miqp", model_dir(options, r),
                            "eval-" + std::to_string(r), r, driven, progress);
    row.labels = aggregate.labelled[static_cast<std::size_t>(r - 1)];
    samples += aggregate.samples[static_cast<std::size_t>(r - 1)];
    row.dagger_samples = samples;
    report.rounds.push_back(row);
  }
  if (options.rounds > 0) report.dataset_dir = data_dir(options);
  write_tables(options, report);
  if (options.candidates > 1) write_selection(options, report.candidates);
  publish_copy(model_dir(options, options.rounds), options.train.out_dir);
  return report;
}

}  // namespace lanechange::dagger
