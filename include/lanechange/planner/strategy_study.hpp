#pragma once
// `lanechange strategy-study`: strategy-qp against the exact expert, open
// loop, as CoCo and MLOPT report a learned integer part (docs/strategy.md):
// on sampled scenes, the share where the top-1 and the top-k strategies are
// feasible among those where the expert finds a plan, the cost ratio to the
// exact optimum, and the time per plan with the speedup over the expert.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::planner {

struct StrategyStudyOptions {
  Config config;
  std::string model_dir;
  int count = 200;
  std::uint64_t seed = 99;           ///< use one the training data did not
  std::optional<Behavior> behavior;  ///< none: drawn per scene
  std::ostream* progress = nullptr;
};

/// Runs the study on one thread (for clean times). The result holds the
/// counts, shares, cost ratios and times; InputError for bad options or a
/// model without a strategy model.
[[nodiscard]] nlohmann::json run_strategy_study(const StrategyStudyOptions& options);

/// The study as a Markdown table.
[[nodiscard]] std::string strategy_study_markdown(const nlohmann::json& study);

}  // namespace lanechange::planner
