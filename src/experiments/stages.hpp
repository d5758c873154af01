#pragma once
// Stages that are reused when their inputs have not changed. A finished
// stage leaves DIR/stages/NAME.json holding its inputs; a stage whose inputs
// differ (another config, seed, commit or upstream result) has its outputs
// removed and runs again, and a killed one runs again over what it left
// (generate, train and evaluate resume by themselves).
#include <functional>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "lanechange/experiments/experiments.hpp"

namespace lanechange::experiments {

class StageRunner {
 public:
  /// Rank 0 of `team` keeps the stamps; every rank learns its decisions.
  StageRunner(std::string out_dir, std::ostream* progress, run::Team& team);

  /// Who runs a stage's body: every rank (it splits its work over them
  /// itself, as generate and evaluate do) or rank 0 alone.
  enum class Ranks { All, First };

  /// Runs `body` unless the stage finished before with the same inputs.
  /// `outputs` are paths under the run's directory that belong to the stage
  /// (removed when its inputs changed). Returns the stage's fingerprint, for
  /// the inputs of the stages that use its results.
  std::string run(const std::string& name, const nlohmann::json& inputs,
                  const std::vector<std::string>& outputs, Ranks ranks,
                  const std::function<void()>& body);

  [[nodiscard]] const std::vector<StageRecord>& records() const { return records_; }

 private:
  /// Rank 0: whether the stage is done with these inputs; else removes
  /// what a run with other inputs left and records that it starts.
  bool reuse_or_prepare(const std::string& name, const nlohmann::json& inputs,
                        const std::string& print, const std::vector<std::string>& outputs);

  std::string out_dir_;
  std::ostream* progress_;
  run::Team& team_;
  std::vector<StageRecord> records_;
};

/// FNV-1a (64 bit) of the text, in hex: stable across machines and runs.
[[nodiscard]] std::string fingerprint(const std::string& text);

}  // namespace lanechange::experiments
