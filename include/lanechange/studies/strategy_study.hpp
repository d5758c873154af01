#pragma once
// `lanechange strategy-study`: strategy-qp against the exact expert, open
// loop, as CoCo and MLOPT report a learned integer part (docs/strategy.md):
// on sampled scenes, the share where the top-1 and the top-k strategies are
// feasible among those where the expert finds a plan, the cost ratio to the
// exact optimum, and the time per plan with the speedup over the expert.
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>

#include "lanechange/config.hpp"
#include "lanechange/learn/strategy.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::studies {

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
/// The same with a strategy model in hand (options.model_dir is only
/// recorded). The result's per_scene lists the scenes with an expert plan:
/// index, behavior, the exact plan's objective and strategy, each
/// candidate's strategy and outcome, the one followed (-1: the exact
/// fallback) and the cost ratio.
[[nodiscard]] nlohmann::json run_strategy_study(const StrategyStudyOptions& options,
                                                std::shared_ptr<const learn::StrategyModel> model);

/// The study as a Markdown table.
[[nodiscard]] std::string strategy_study_markdown(const nlohmann::json& study);

}  // namespace lanechange::studies
