#pragma once
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lanechange/expert/gap_slots.hpp"
#include "lanechange/learn/model.hpp"
#include "lanechange/traffic.hpp"
#include "planner/miqp_planner.hpp"

namespace lanechange::planner {

/// Reads the network's input columns (by their data-set names) out of an
/// observation and the gap the network drives to (docs/learning.md).
/// InputError for a column an observation does not give.
class PolicyInputs {
 public:
  explicit PolicyInputs(const std::vector<std::string>& names);
  [[nodiscard]] learn::Observation read(const Observation& observation,
                                        const expert::GapFrame& gap = {}) const;
  /// Whether some input is relative to the chosen gap (expert::gap_view).
  [[nodiscard]] bool reads_gap() const { return reads_gap_; }

 private:
  struct Source {
    const std::function<double(const Observation&)>* getter = nullptr;
    std::size_t view = 0;  ///< the index in expert::gap_view without a getter
  };
  std::vector<Source> sources_;
  bool reads_gap_ = false;
};

class MlpMiqpPlanner final : public ClosedLoopPlanner {
 public:
  /// What the classifier makes of a scene at the start: whether a lane
  /// change is worth trying, and through which gap.
  struct SceneChoice {
    bool tries = false;
    expert::GapFrame gap;
  };
  /// The learned parts: the scene's choice and the network's raw control
  /// towards the chosen gap. Const and safe to call from many threads.
  using SceneClassifier = std::function<SceneChoice(const Scenario&)>;
  using Network = std::function<EgoControl(const Observation&, const expert::GapFrame&)>;

  MlpMiqpPlanner(Config config, SceneClassifier classify, Network network,
                 std::shared_ptr<const expert::LaneChangeSolver> solver,
                 std::string name = "mlp-miqp", bool reads_roles = true);
  /// A trained model: for a network that reads the paper's three cars, the
  /// SVM (13 features) and the gap between follower and target; for one
  /// that drives to a chosen gap, the gap classifier that names the slot
  /// (the one that named a completable gap most often on held-out scenes).
  MlpMiqpPlanner(Config config, const std::shared_ptr<const learn::Model>& model,
                 std::shared_ptr<const expert::LaneChangeSolver> solver);
  [[nodiscard]] std::string_view name() const override { return name_; }
  [[nodiscard]] std::unique_ptr<PlannerSession> start(const Scenario& scene) const override;

  [[nodiscard]] const Config& config() const { return config_; }
  /// Whether the classifier lets the network try `scene` (Algorithm 1's
  /// first test); a refused scene is left to the fallback.
  [[nodiscard]] bool tries(const Scenario& scene) const;
  [[nodiscard]] SceneChoice choose(const Scenario& scene) const { return classify_(scene); }
  [[nodiscard]] EgoControl network(const Observation& o, const expert::GapFrame& gap) const {
    return network_(o, gap);
  }
  /// Whether the network reads the paper's three cars by role (a scene
  /// without one of them is the expert's alone).
  [[nodiscard]] bool reads_roles() const { return reads_roles_; }
  [[nodiscard]] const expert::ExpertPlanner& expert() const { return expert_; }

 private:
  Config config_;
  SceneClassifier classify_;
  Network network_;
  expert::ExpertPlanner expert_;
  std::string name_;
  bool reads_roles_ = true;
};

/// `mlp-miqp-oracle`: mlp-miqp with the model's classifier, its check and
/// its take-over, whose "network" is the closed-loop expert itself, planning
/// from every state it is asked about (the keeper's control where it finds
/// no plan). A perfect imitation of the expert, so its take-overs are the
/// ones no training of the network removes (docs/dagger.md). Slow:
/// an exact plan for every step of every look-ahead.
[[nodiscard]] std::shared_ptr<const MlpMiqpPlanner> make_oracle_mlp_miqp(
    const Config& config, const std::shared_ptr<const learn::Model>& model);

class MlpMiqpSession final : public PlannerSession {
 public:
  /// `expert_only`: the expert drives every step (a scene the network cannot read).
  MlpMiqpSession(const MlpMiqpPlanner& planner, MlpMiqpPlanner::SceneChoice choice,
                 bool expert_only);
  [[nodiscard]] Decision act(const Observation& observation) override;
  /// The look-ahead's predicted observations, one step ahead onwards: the
  /// states the network would drive to. After a check that failed, they end
  /// at the node that failed it (DAgger labels them).
  [[nodiscard]] const std::vector<Observation>& lookahead() const { return window_.ahead; }

 private:
  /// The look-ahead's predicted path, kept from one step to the next: while
  /// the real state stays within closed_loop.lookahead_tolerance of its
  /// node 1, the next check only adds one node at its end.
  struct Window {
    int step = -1;                        ///< the observation step of node 0; -1: none
    std::vector<EgoState> ego;            ///< nodes 0..n
    TrafficPrediction cars;               ///< nodes 0..n
    std::optional<Scenario> scene;        ///< the scene of the last full roll-out
    std::optional<TrafficModel> traffic;  ///< the cars at node n
    Observation last;                     ///< the observation at node n
    std::vector<Observation> ahead;       ///< nodes 1..n
    EgoControl next;                      ///< the network's control at node n
  };

  /// The network's control where the look-ahead passes, else the take-over.
  [[nodiscard]] Decision network_decision(const Observation& observation);
  [[nodiscard]] EgoControl network_control(const Observation& observation) const;
  [[nodiscard]] std::string check_ahead(const Observation& now, EgoControl first);
  [[nodiscard]] std::string roll_out(const Observation& now, EgoControl first);
  [[nodiscard]] bool window_fits(const Observation& now) const;
  [[nodiscard]] std::string extend_window();
  /// Applies window_.next at node n and records node n + 1.
  void advance_window(double dt);
  [[nodiscard]] std::string check_node(int ahead);
  [[nodiscard]] Decision expert_decision(const Observation& observation, const std::string& why);
  [[nodiscard]] Decision refused(const Observation& observation);

  const MlpMiqpPlanner& planner_;
  expert::GapFrame gap_;  ///< the gap the network drives to
  LaneKeeper keeper_;
  MiqpSession expert_;
  bool refused_ = false;
  int next_check_ = 0;  ///< the step of the expert's next check of a refusal
  /// The highest y of the ego so far (capped as the judge caps it), so the
  /// look-ahead sees a move back towards the ego lane that has begun.
  double y_peak_ = -INFINITY;
  Window window_;
  Observation recycled_;         ///< a look-ahead node's buffer between its two uses
  TrafficPrediction segment_;    ///< the window's last step, for the collision test
  std::vector<double> lateral_;  ///< the window's y, for the reversal test
  bool expert_in_charge_ = false;
  bool expert_only_ = false;
};

}  // namespace lanechange::planner
