#include "experiments/report.hpp"

#include <sys/utsname.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <thread>

#include "lanechange/sumo/evaluate.hpp"

namespace lanechange::experiments {

namespace {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown CPU";
}

std::string machine() {
  utsname name{};
  std::string system = uname(&name) == 0 ? std::string(name.sysname) + " " + name.release : "";
  system += ", ";
  system += cpu_model();
  system += ", ";
  system += std::to_string(std::thread::hardware_concurrency());
  system += " cores";
  return system;
}

std::string seconds(double s) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(s < 10 ? 1 : 0);
  out << s << " s";
  return out.str();
}

std::string command_of(const ExperimentOptions& o, const ExperimentSizes& sizes) {
  std::string command = "lanechange experiments --out ";
  command += o.out_dir;
  command += " --scale ";
  command += to_string(o.scale);
  if (o.eval_count > 0) command += " --eval-count " + std::to_string(sizes.eval_per_behavior);
  if (!o.planners.empty()) {
    command += " --planner ";
    for (std::size_t i = 0; i < o.planners.size(); ++i) {
      command += (i > 0 ? "," : "") + o.planners[i];
    }
  }
  return command;
}

void provenance(Document& d, const ReportInputs& in) {
  const ExperimentOptions& o = *in.options;
  d.paragraph("Made by one command, from a run of this commit; no number below is typed by hand.");
  d.code(command_of(o, in.sizes));
  std::vector<std::string> items = {
      "commit: `" + code_version() + "`",
      "machine: " + machine(),
      "scale: `" + std::string(to_string(o.scale)) +
          "`: " + std::to_string(in.sizes.data_per_behavior) +
          " expert scenarios per behavior for learning, " +
          std::to_string(in.sizes.eval_per_behavior) +
          " closed-loop scenarios per behavior for evaluation",
      "lane rule of the default config: `" +
          nlohmann::json(o.config).at("expert").at("lane_rule").get<std::string>() + "`; preset `" +
          o.config.preset + "`",
  };
  std::string seeds = "seeds: expert data ";
  seeds += std::to_string(in.seeds.at("data"));
  if (in.seeds.contains("dense data")) {
    seeds += ", dense expert data ";
    seeds += std::to_string(in.seeds.at("dense data"));
  }
  seeds += ", evaluation ";
  seeds += std::to_string(in.seeds.at("evaluation"));
  seeds +=
      " (each +0, +1, +2 for constant speed, constant acceleration, IDM: learning and "
      "evaluation never share a scene), training ";
  seeds += std::to_string(in.seeds.at("train"));
  items.push_back(seeds);
  d.bullets(items);
  Table stages{{"stage", "wall time", "this run"}, {}};
  for (const auto& s : in.stages) {
    stages.rows.push_back({s.name, seconds(s.wall_s), s.reused ? "reused" : "ran"});
  }
  stages.rows.push_back({"whole command (this invocation)", seconds(in.wall_s), ""});
  d.table(stages);
}

void table_one(Document& d, const ReportInputs& in) {
  d.heading(2, "Table I: scene classifiers");
  const auto& data = in.metrics.at("data");
  d.paragraph("Held-out accuracy on " + data.at("test_scenarios").dump() + " test scenes (" +
              data.at("train_scenarios").dump() +
              " for training, split by scenario). The paper's classifiers take the 13 scene "
              "features; \"with behavior\" adds the other cars' behavior as an input. The "
              "gap classifiers (docs/learning.md) take the scene through the gaps around the "
              "ego and name the gap to take, or none: \"gap named\" is the share that names "
              "the expert's own answer (with every gap labelled, \"gap completable\" is the "
              "share whose gap the expert completes well-posed, or that rightly name none).");
  d.table(classifier_table(in.metrics));
  d.paragraph("The SVM's confusion matrix, normalised by row (the paper's Fig. 3):");
  d.table(svm_confusion_table(in.metrics));
  d.figure("figures/confusion_svm.png", "Normalised confusion matrix of the SVM (13 features).");
}

void table_two(Document& d, int level, const std::string& title,
               const std::vector<sim::RolloutRow>& rows, const ReportInputs& in) {
  d.heading(level, "Table II: planners in closed loop (" + title + ")");
  if (level == 2) {
    d.paragraph(
        "Every planner on the same scenes and loop. Success = ends well-posed without "
        "collision; \"where miqp succeeds\" is the share of the scenes the re-planning expert "
        "masters, which does not depend on how many scenes of the distribution are impossible. "
        "Step times are per planner step (a re-plan, for the planners that re-plan every step): "
        "p50 is the median of each rollout's median, p99 the 99th percentile of each rollout's "
        "99th percentile, max the worst step of all. RMS jerk in m/s^3 (mean over rollouts), "
        "max abs(a) in m/s^2. An unsafe cut-in made another car brake harder than "
        "`closed_loop.unsafe_decel` (MOBIL's b_safe, 4 m/s^2).");
  }
  d.table(comparison_table(rows, in.planners));
  const auto verdicts = where_others_beat_ours(rows, in.planners);
  if (!verdicts.empty()) d.bullets(verdicts);
}

// A variant run's Tables II and III, one level down, under `title`.
void variant_tables(Document& d, const std::string& title, const std::vector<sim::RolloutRow>& rows,
                    const ReportInputs& in) {
  table_two(d, 3, title, rows, in);
  d.heading(3, "Table III (" + title + ")");
  d.table(behavior_table(rows, in.planners));
}

void paper_section(Document& d, const ReportInputs& in) {
  d.heading(2, "The paper's own formulation");
  d.paragraph(
      "Every planner again on the same scenes, with the paper's expert (`expert.gap = fixed`: "
      "Eq. 1's one gap between follower and target; `expert.cut_in_decel = null`: Eq. 1's "
      "distances alone) in the paper's traffic (`traffic.followers_react = false`: cars that "
      "ignore the ego and each other; `traffic.max_decel = null`: IDM brakes without limit). "
      "This is the reproduction of the paper; the tables above are the defaults. The models "
      "are those trained above.");
  variant_tables(d, "the paper's formulation", in.paper, in);
}

// Who drove mlp-miqp's successes: the network alone, or the expert after a
// take-over.
void network_share(Document& d, const std::vector<sim::RolloutRow>& rows) {
  long long successes = 0;
  long long alone = 0;
  for (const auto& r : rows) {
    if (r.planner != "mlp-miqp" || !r.success()) continue;
    ++successes;
    alone += r.takeovers == 0 ? 1 : 0;
  }
  if (successes == 0) return;
  d.paragraph("mlp-miqp's network drove " + std::to_string(alone) + " of its " +
              std::to_string(successes) + " successes alone (" + percent(alone, successes) +
              "); the expert took over in the others.");
}

void dense_section(Document& d, const ReportInputs& in) {
  d.heading(2, "Dense traffic");
  d.paragraph(
      "Every planner on as many scenes of denser traffic: " +
      std::to_string(std::lround(in.dense_target_lane_cars.lo)) + " to " +
      std::to_string(std::lround(in.dense_target_lane_cars.hi)) +
      " cars in the target lane, a leader and a car behind the ego in its lane "
      "(`sampler.target_lane_cars`, docs/scenarios.md, \"Dense traffic\"), the default "
      "formulation and traffic. The expert chooses among all gaps. mlp-miqp and strategy-qp "
      "use a model of their own (stages `dense-data`, `dense-model`: as many dense scenes "
      "per behavior as the paper's data, planned by the closed-loop expert's formulation, "
      "every gap labelled): mlp-miqp's gap classifier names the gap and its network drives "
      "to it (docs/learning.md, docs/closed_loop.md). " +
      traffic_check(in.dense, in.car_decel_limit) + ".");
  variant_tables(d, "dense traffic", in.dense, in);
  network_share(d, in.dense);
  if (in.dense_metrics.contains("data")) {
    d.paragraph("The dense model's classifiers, held out as in Table I (" +
                in.dense_metrics.at("data").at("test_scenarios").dump() + " test scenes):");
    d.table(classifier_table(in.dense_metrics));
  }
}

void sumo_section(Document& d, const ReportInputs& in) {
  d.heading(2, "SUMO traffic (beyond the paper)");
  std::string densities;
  for (const double density : in.sumo_densities) {
    densities += (densities.empty() ? "" : " and ") + sumo::highway_group(density).substr(8);
  }
  d.paragraph(
      "Every planner in traffic that SUMO moves: its cars follow (Krauss), change lanes "
      "(SL2015) and react to the ego (docs/sumo.md). The built-in highway at " +
      densities + " cars per lane and km, " + std::to_string(in.sizes.sumo_episodes) +
      " seeded episodes each (`lanechange evaluate --sumo-highway`); and, where the run names "
      "them, CommonRoad's interactive scenarios (`--commonroad DIR`: recorded cars from their "
      "recorded starts). Each rollout starts when the change is asked and lasts the horizon "
      "plus `closed_loop.settle_time`. `mlp-miqp` and `strategy-qp` use the dense model, "
      "which reads any number of cars. An unsafe cut-in made a SUMO car of the target lane "
      "brake harder than `closed_loop.unsafe_decel`.");
  std::vector<std::string> groups;
  for (const auto& r : in.sumo) {
    if (std::find(groups.begin(), groups.end(), r.behavior) == groups.end())
      groups.push_back(r.behavior);
  }
  for (const std::string& group : groups) {
    std::vector<sim::RolloutRow> rows;
    for (const auto& r : in.sumo) {
      if (r.behavior == group) rows.push_back(r);
    }
    table_two(d, 3, "SUMO, " + group, rows, in);
  }
}

void dagger_section(Document& d, const ReportInputs& in) {
  const dagger::DaggerOptions& o = in.dagger_options;
  d.heading(2, "DAgger for the action network (beyond the paper)");
  d.paragraph(
      "The paper names DAgger (Ross et al. 2011) as future work (docs/dagger.md). Each round "
      "rolls the last round's policy out " +
      std::string(o.rollout == dagger::Rollout::Gated
                      ? "under mlp-miqp's check (labels up to the take-over)"
                      : "on its own (no take-over)") +
      " on those of " + std::to_string(o.scenes) + " fresh training scenes (seed " +
      std::to_string(o.scene_seed) +
      " on) that the classifier lets it drive, has the closed-loop expert label the states the "
      "policy drives into (every " +
      std::to_string(o.stride) +
      " steps), adds those labels to the expert's data and retrains the "
      "networks. The policy is an ensemble: the mean action of " +
      std::to_string(o.train.network.networks) +
      " networks of the paper's shape, each from its own seed (docs/learning.md), because one "
      "network's seed moved the take-overs as much as a round's labels did; round 0 is the "
      "model above with that ensemble in place of its one network. " +
      std::string(o.average ? "Round r's policy is the mean of the ensembles of rounds 0 to r "
                              "(each retrained on every label so far): the deterministic form of "
                              "the mixture of the rounds' policies, for which DAgger's guarantee "
                              "holds. "
                            : "") +
      "mlp-miqp is then scored on " + std::to_string(o.eval_count) +
      " held-out scenes of all behaviors (seed " + std::to_string(o.eval_seed) +
      "), and miqp once on the same scenes, both with the step budget lifted as for the "
      "labels, so that the rounds' scores do not depend on the machine's load (Table II's are "
      "timed). \"Network drives\" counts the held-out rollouts the "
      "classifier lets the network drive; of those, the check takes some over at the network's "
      "first step (the scene's own start) and some later. The same run alone: "
      "`lanechange dagger --data DATA... --networks " +
      std::to_string(o.train.network.networks) + " --rounds R" + (o.average ? " --average" : "") +
      "` (docs/dagger.md).");
  d.table(dagger_table(*in.dagger));
  d.bullets(dagger_verdicts(*in.dagger));
  d.figure("figures/dagger.png", "DAgger: mlp-miqp's success and take-overs per round.");
}

}  // namespace

Document build_report(const ReportInputs& in) {
  Document d;
  d.heading(1, "The paper's experiments, reproduced");
  provenance(d, in);
  table_one(d, in);
  table_two(d, 2, "footprint lane rule", in.footprint, in);
  d.heading(2, "Table III: success per behavior of the other cars (footprint lane rule)");
  d.table(behavior_table(in.footprint, in.planners));
  d.figure("figures/success.png", "Success per planner and behavior (footprint lane rule).");
  d.figure("figures/step_times.png",
           "Compute time per step: the distribution of each rollout's median, log scale.");
  const auto general = generalization_table(in.footprint, in.labels, in.planners);
  d.heading(2, "Generalization: scenes the expert plans ill-posed");
  d.paragraph("Of the evaluation scenes, " + std::to_string(general.ill_posed) + " of " +
              std::to_string(in.labels.size()) +
              " are planned ill-posed by the expert in open loop (the paper tests 1000). The "
              "share each planner ends well-posed, in closed loop:");
  d.table(general.table);
  if (!in.expert_planners.empty()) {
    d.heading(2, "The lane rule: either_or (the paper's literal reading)");
    d.paragraph(
        "The planners that use the expert run again with `expert.lane_rule = either_or`; the "
        "baselines know no lane rule, so their rows repeat the footprint run. The action network "
        "is the one trained on footprint data.");
    variant_tables(d, "either_or lane rule", in.either_or, in);
  }
  paper_section(d, in);
  dense_section(d, in);
  if (!in.sumo.empty()) sumo_section(d, in);
  if (in.dagger) dagger_section(d, in);
  d.heading(2, "Example rollouts");
  if (in.examples.empty()) d.paragraph("No scene of this run qualified as an example.");
  for (const auto& scene : in.examples) {
    d.heading(3, scene.name + ": " + scene.behavior + " scene " + std::to_string(scene.index));
    d.paragraph(scene.why + ".");
    for (const auto& planner : in.planners) {
      if (planner == "keep-lane") continue;
      d.figure("figures/" + scene.name + "_" + planner + ".png",
               planner + " on " + scene.behavior + " scene " + std::to_string(scene.index));
    }
  }
  return d;
}

}  // namespace lanechange::experiments
