#include <algorithm>

#include "lanechange/error.hpp"
#include "planner/mlp_miqp_planner.hpp"
#include "planner/strategy_qp_planner.hpp"

namespace lanechange::planner {

namespace {

// Never changes lanes: the lane keeper behind the leader. The floor every
// planner falls back to, and a baseline of its own ("what if we stay").
class KeepLaneSession final : public PlannerSession {
 public:
  explicit KeepLaneSession(const Config& config) : keeper_(config) {}
  [[nodiscard]] Decision act(const Observation& o) override {
    return {keeper_.control(o.ego, 0.0, car_ahead(o, false)), ActStatus::Fallback,
            "this planner never changes lanes"};
  }

 private:
  LaneKeeper keeper_;
};

class KeepLanePlanner final : public ClosedLoopPlanner {
 public:
  explicit KeepLanePlanner(Config config) : config_(std::move(config)) {}
  [[nodiscard]] std::string_view name() const override { return "keep-lane"; }
  [[nodiscard]] std::unique_ptr<PlannerSession> start(const Scenario& /*scene*/) const override {
    return std::make_unique<KeepLaneSession>(config_);
  }

 private:
  Config config_;
};

}  // namespace

std::vector<std::string> planner_names() {
  return {"miqp", "mlp-miqp", "strategy-qp", "keep-lane", "mlp-miqp-oracle"};
}

std::shared_ptr<const ClosedLoopPlanner> make_planner(std::string_view name, const Config& config,
                                                      const std::string& model_dir) {
  if (name == "mlp-miqp" || name == "mlp-miqp-oracle") {
    if (model_dir.empty()) {
      throw InputError("--model",
                       std::string(name) + " needs a model directory (lanechange train)");
    }
    // The network's inputs are checked by name when the planner maps them
    // onto an observation; the closed loop's config may differ from the data's.
    auto model = std::make_shared<const learn::Model>(learn::Model::load(model_dir));
    if (name == "mlp-miqp-oracle") return make_oracle_mlp_miqp(config, model);
    return std::make_shared<MlpMiqpPlanner>(config, std::move(model),
                                            std::make_shared<expert::FastLaneChangeSolver>());
  }
  if (name == "strategy-qp") {
    if (model_dir.empty()) {
      throw InputError("--model", "strategy-qp needs a model directory (lanechange train)");
    }
    return std::make_shared<StrategyQpPlanner>(config, learn::Model::load(model_dir).strategy());
  }
  if (name == "miqp") {
    return std::make_shared<MiqpPlanner>(config, std::make_shared<expert::FastLaneChangeSolver>());
  }
  if (name == "keep-lane") return std::make_shared<KeepLanePlanner>(config);
  std::string known;
  for (const auto& n : planner_names()) known += (known.empty() ? "" : ", ") + n;
  throw InputError("--planner",
                   "unknown planner \"" + std::string(name) + "\" (known: " + known + ")");
}

}  // namespace lanechange::planner
