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
  StageRunner(std::string out_dir, std::ostream* progress);

  /// Runs `body` unless the stage finished before with the same inputs.
  /// `outputs` are paths under the run's directory that belong to the stage
  /// (removed when its inputs changed). Returns the stage's fingerprint, for
  /// the inputs of the stages that use its results.
  std::string run(const std::string& name, const nlohmann::json& inputs,
                  const std::vector<std::string>& outputs, const std::function<void()>& body);

  [[nodiscard]] const std::vector<StageRecord>& records() const { return records_; }

 private:
  std::string out_dir_;
  std::ostream* progress_;
  std::vector<StageRecord> records_;
};

/// FNV-1a (64 bit) of the text, in hex: stable across machines and runs.
[[nodiscard]] std::string fingerprint(const std::string& text);

}  // namespace lanechange::experiments
