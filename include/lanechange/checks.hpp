#pragma once
// Checks on an ego trajectory: collisions with the other cars, and the label
// of NOTES.md. Both are pure functions, safe to call from many threads.
#include <cmath>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange {

struct Collision {
  int node = 0;       ///< first node (or the node before the first sub-sample) in contact
  double time = 0.0;  ///< s
  CarIndex car = 0;
};

/// The first contact between the ego (poses at the nodes, oriented boxes) and
/// the predicted or simulated cars, or none. Between nodes, `substeps`
/// linear interpolations are checked too, so a fast pass is not missed.
[[nodiscard]] std::optional<Collision> first_collision(std::span<const EgoState> ego,
                                                       const TrafficPrediction& others,
                                                       const Scenario& scenario, int substeps = 4);

enum class Label { WellPosed, IllPosed, Failure };

[[nodiscard]] std::string_view to_string(Label label);
/// Throws InputError for an unknown name.
[[nodiscard]] Label label_from_string(std::string_view name);

struct Labelled {
  Label label = Label::Failure;
  std::string reason;  ///< why, in words; empty for well-posed
};

/// The label of a solved plan or a rollout (NOTES.md, Sec. III):
/// - failure: y(t_f) is not within `reach` of the target-lane centre;
/// - ill-posed: it is, but y drops more than `reversal` (measured as
///   `reference` says), or |theta(t_f)| exceeds `max_final_heading`;
/// - well-posed: otherwise.
[[nodiscard]] Labelled label_trajectory(std::span<const double> y, double final_theta,
                                        double lane_width, const LabelTolerances& tol);

/// The largest drop of y below its running maximum (0 when y never
/// decreases). With a finite `cap`, the running maximum is capped there, so
/// settling back from above the cap does not count.
[[nodiscard]] double largest_lateral_reversal(std::span<const double> y, double cap = INFINITY);

}  // namespace lanechange
