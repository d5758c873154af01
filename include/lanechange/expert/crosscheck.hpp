#pragma once
// The check of our fast solver against the reference: the same linearized
// MIQP (the first round's, at the warm start) solved by both.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/expert/formulation.hpp"
#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::expert {

struct CrossCheckCase {
  std::uint64_t index = 0;
  std::string behavior;
  MiqpStatus fast_status = MiqpStatus::NumericalError;
  MiqpStatus reference_status = MiqpStatus::NumericalError;
  double fast_objective = kInfinity;
  double reference_objective = kInfinity;
  double relative_difference = 0.0;  ///< |fast - reference| / max(1, |reference|)
  double fast_ms = 0.0;
  double reference_ms = 0.0;
  long fast_nodes = 0;
  long reference_nodes = 0;
  bool agree = false;  ///< same verdict and, if solved, objectives within the tolerance
};

/// The first round's MIQP of a scenario (warm start, prediction along it),
/// through Eq. 1's gap.
[[nodiscard]] LaneChangeQp first_round_problem(const Scenario& scenario, const Config& config);
/// The same through `gap`, from the warm start aimed into it, as a plan's
/// first round solves each gap.
[[nodiscard]] LaneChangeQp first_round_problem(const Scenario& scenario, const Config& config,
                                               const Gap& gap);

/// The verdict of a stored reference solve (a line of an earlier cross-check).
struct StoredReference {
  MiqpStatus status = MiqpStatus::NumericalError;
  double objective = kInfinity;
  double ms = 0.0;
  long nodes = 0;
};

/// Compares a fast solve with a reference result, fresh or stored.
[[nodiscard]] CrossCheckCase compare_with_reference(const LaneChangeSolution& fast,
                                                    const StoredReference& reference,
                                                    double tolerance);

/// Parses a MiqpStatus as to_string writes it; throws InputError otherwise.
[[nodiscard]] MiqpStatus parse_miqp_status(std::string_view text);

/// Compares the two solvers on one problem. `tolerance` bounds the relative
/// objective difference.
[[nodiscard]] CrossCheckCase cross_check(const LaneChangeQp& qp, const LaneChangeSolver& fast,
                                         const LaneChangeSolver& reference,
                                         const MiqpSettings& settings, double tolerance);

}  // namespace lanechange::expert
