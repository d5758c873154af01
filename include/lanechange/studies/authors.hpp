#pragma once
// The reference records of the authors' MATLAB code (reference/README.md,
// authors_idm.jsonl) and the comparison of our `authors` preset with them.
//
// Each record holds a scenario and what the authors' code made of it: a
// solution and its objective, or no solution. compare_with_authors plans the
// scenario with our planner and sets the two side by side. To say why they
// differ, it also evaluates their path under our problems:
//  - our last round's QP (linearized about our second-to-last iterate, with
//    the cars predicted along it): if their path is feasible there and
//    cheaper than ours, our round solve slipped;
//  - the round QP linearized about THEIR path ("their last problem as we
//    read it"), once with their stored prediction of the cars and once with
//    ours along their path, each solved by our solver: if the first optimum
//    is well below their objective, their solve was not optimal; a gap
//    between the two optima is the effect of the prediction.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lanechange/checks.hpp"
#include "lanechange/config.hpp"
#include "lanechange/expert/formulation.hpp"
#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::studies {

using expert::ExpertPlanner;
using expert::Iterate;
using expert::kInfinity;
using expert::LaneChangeQp;
using expert::MiqpStatus;
using expert::PlanLimits;
using expert::PlanStatus;

inline constexpr double kNotANumber = std::numeric_limits<double>::quiet_NaN();

/// The cost terms in the order of the records' `objective_terms`.
enum AuthorsTerm { kTermAccel = 0, kTermLateral = 1, kTermTerminalX = 2, kTermJerk = 3 };
using AuthorsTerms = std::array<double, 4>;

struct AuthorsRecord {
  std::string id;  ///< source file and cell, e.g. "data2.mat{1}"
  int line = 0;    ///< 1-based line in the file
  Scenario scenario;
  bool solved = false;  ///< status "solved"; false for "no_solution"
  double objective = kNotANumber;
  AuthorsTerms objective_terms{kNotANumber, kNotANumber, kNotANumber, kNotANumber};
  /// steps + 1 states and steps controls; empty unless solved.
  Iterate solution;
  /// x and v of the cars as their last round used them, one entry per node:
  /// entry k is the prediction after k + 1 steps (their off-by-one), so it
  /// lines up with our prediction index k + prediction_lead_steps. The
  /// accelerations are not stored (left empty). Empty unless solved.
  TrafficPrediction predicted_others;
};

/// One record from one JSON object. Throws InputError naming the field.
[[nodiscard]] AuthorsRecord authors_record_from_json(const nlohmann::json& in,
                                                     const Config& config);

/// Every record of a JSON-lines file (blank lines are skipped). Scenarios take
/// their optional fields from `config`. Throws InputError whose field() is
/// "<path>, line <n>" and whose message names the line and the bad field.
[[nodiscard]] std::vector<AuthorsRecord> load_authors_records(const std::string& path,
                                                              const Config& config);

/// The authors' cost (README) of a path, term by term: 0.5 dt sum a^2,
/// dt sum_{k < N} (y_k - w)^2, 0.005 (x_N - target_end_x)^2, 100 dt sum (da)^2,
/// with the weights of `config.expert` (the authors' preset gives theirs).
[[nodiscard]] AuthorsTerms authors_objective_terms(const Iterate& path, const Config& config,
                                                   double lane_width, double target_end_x);
[[nodiscard]] double sum_of(const AuthorsTerms& terms);

/// Their stored prediction on our grid: entry j is the cars after j steps
/// (entry 0 the scenario's initial state), as predict_traffic indexes it, so
/// build_lane_change_qp reads it with the config's prediction_lead_steps.
/// Accelerations are not stored; they are set to 0.
[[nodiscard]] TrafficPrediction their_prediction_on_our_grid(const AuthorsRecord& record);

/// How our plan and theirs relate, per record.
enum class AuthorsAgreement {
  Match,       ///< both solved; ours within the tolerance above or below theirs
  OursLower,   ///< both solved; ours lower by more than the tolerance
  OursHigher,  ///< both solved; ours higher by more than the tolerance
  OnlyTheySolve,
  OnlyWeSolve,
  NeitherSolves,
};
[[nodiscard]] std::string_view to_string(AuthorsAgreement agreement);

/// Why, for a record where the two disagree (see the file comment).
enum class AuthorsCause {
  None,               ///< they agree
  TheirsNotOptimal,   ///< their path is feasible for their last problem as we read it,
                      ///< whose optimum is lower by more than the tolerance
  OursSlip,           ///< their path is feasible for our last round's QP and cheaper
  DifferentProblem,   ///< their path violates our constraints (lanes, bounds)
  DifferentFixpoint,  ///< both paths are feasible for their own last problem and optimal
                      ///< there: the successive linearization settled elsewhere
  OurFailure,         ///< we did not converge or found no solution where they did
  Unexplained,        ///< none of the above fits
};
[[nodiscard]] std::string_view to_string(AuthorsCause cause);

/// Largest violation of a path under a round QP, split by kind (metres, m/s,
/// rad, as the rows are written).
struct PathViolation {
  double dynamics = kNotANumber;  ///< linearized dynamics and the initial state
  double bounds = kNotANumber;    ///< state and control bounds, terminal y
  double lanes = kNotANumber;     ///< lane logic (the best mode at each node)
  [[nodiscard]] double constraints() const { return std::max(bounds, lanes); }
};
[[nodiscard]] PathViolation path_violation(const LaneChangeQp& qp, const Iterate& path);

/// A round QP built about their path, their path evaluated in it, and the
/// QP solved (by the planner's solver).
struct TheirProblemCheck {
  double their_objective = kNotANumber;  ///< their path's cost in this QP
  PathViolation violation;               ///< of their path
  MiqpStatus status = MiqpStatus::NumericalError;
  double optimum = kNotANumber;
  double relative = kNotANumber;  ///< (optimum - their stored objective) / their stored objective
};

struct AuthorsComparison {
  std::string id;
  int line = 0;
  bool theirs_solved = false;
  PlanStatus our_status = PlanStatus::SolverError;
  std::string our_reason;
  Label our_label = Label::Failure;
  int iterations = 0;
  double ms = 0.0;  ///< our plan

  double our_objective = kNotANumber;  ///< the last round's MIQP objective
  AuthorsTerms our_terms{kNotANumber, kNotANumber, kNotANumber, kNotANumber};
  double their_objective = kNotANumber;
  AuthorsTerms their_terms{kNotANumber, kNotANumber, kNotANumber, kNotANumber};
  double relative_difference = kNotANumber;  ///< (ours - theirs) / theirs
  double max_dx = kNotANumber;               ///< max over nodes of |x_ours - x_theirs|, m
  double max_dy = kNotANumber;
  double max_dv = kNotANumber;
  /// First node whose body touches the target lane (y >= w/2 - half width).
  int our_first_cross_node = -1;
  int their_first_cross_node = -1;

  // Their path under our last round's QP.
  double their_objective_in_our_qp = kNotANumber;
  PathViolation their_violation_in_our_qp;
  /// Our last round rebuilt (planner rerun one round short): its objective on
  /// our path minus our reported objective; ~0 when the rebuild is right.
  double our_qp_rebuild_error = kNotANumber;

  /// Their last problem as we read it, linearized about their path, with
  /// the cars as THEY predicted them (their stored predicted_others), and
  /// with the cars as WE predict them along their path.
  TheirProblemCheck with_their_prediction;
  TheirProblemCheck with_our_prediction;
  /// The relative difference split in three (they add up to it):
  /// their_gap = (optimum with their prediction - theirs) / theirs: below 0,
  /// their solve was not optimal; prediction_effect = (optimum with our
  /// prediction - optimum with theirs) / theirs; fixpoint_effect = (ours -
  /// optimum with our prediction) / theirs: where our successive
  /// linearization settled against one round at their path.
  double their_gap = kNotANumber;
  double prediction_effect = kNotANumber;
  double fixpoint_effect = kNotANumber;

  // Our IDM prediction along their path against their stored predicted_others.
  std::array<double, 3> prediction_max_dx{kNotANumber, kNotANumber, kNotANumber};  ///< by Car
  std::array<double, 3> prediction_max_dv{kNotANumber, kNotANumber, kNotANumber};
  /// Their target's end position minus ours (enters the terminal x term).
  double target_end_dx = kNotANumber;

  AuthorsAgreement agreement = AuthorsAgreement::NeitherSolves;
  AuthorsCause cause = AuthorsCause::None;
};

struct AuthorsComparisonSettings {
  double tolerance = 0.01;  ///< relative objective difference that still agrees
  /// A path whose lane and bound rows are violated by no more than this (m)
  /// counts as feasible; their stored numbers have 7 significant digits.
  double feasibility_tolerance = 1e-3;
  /// Linearized dynamics of a QP built about another path are violated by
  /// the linearization error; up to this (m) still counts as feasible.
  double dynamics_tolerance = 2e-2;
  PlanLimits limits{};
  /// Evaluate their path under our problems and re-solve their last problem
  /// (one MIQP more per record).
  bool diagnose = true;
  /// Rebuild our last round's QP (one plan more) also where the objectives
  /// agree; by default only where they differ by more than the tolerance.
  bool diagnose_agreeing = false;
  int threads = 1;
};

/// Plans one record and compares (see AuthorsComparison).
[[nodiscard]] AuthorsComparison compare_with_authors(const AuthorsRecord& record,
                                                     const ExpertPlanner& planner,
                                                     const AuthorsComparisonSettings& settings);

/// All records, on settings.threads threads; the results keep the records' order.
/// `progress` (may be null) is called after each record with the count done.
using AuthorsProgress = void (*)(std::size_t done, std::size_t total);
[[nodiscard]] std::vector<AuthorsComparison> compare_with_authors(
    const std::vector<AuthorsRecord>& records, const ExpertPlanner& planner,
    const AuthorsComparisonSettings& settings, AuthorsProgress progress = nullptr);

/// The planner of the acceptance test: the `authors` preset with our fast solver.
[[nodiscard]] ExpertPlanner authors_planner(const Config& config = make_preset("authors"));

struct Quantile {
  double q = 0.0;
  double value = kNotANumber;
};
/// The quantiles (linear interpolation between order statistics) of the finite values.
[[nodiscard]] std::vector<Quantile> quantiles(std::vector<double> values,
                                              const std::vector<double>& qs);

struct AuthorsSummary {
  double tolerance = 0.01;
  int records = 0;
  int theirs_solved = 0;
  int theirs_no_solution = 0;
  int both_solved = 0;
  int only_they_solve = 0;
  int only_we_solve = 0;
  int neither_solves = 0;
  int match = 0;
  int ours_lower = 0;
  int ours_higher = 0;
  /// Of their solved records: ours solved and at most `tolerance` above theirs.
  int at_most_tolerance_above = 0;
  double share_at_most_tolerance_above = 0.0;
  double share_within_tolerance = 0.0;  ///< |relative difference| <= tolerance
  double share_no_solution_agreed = 0.0;
  bool acceptance_met = false;  ///< >= 90% at most 1% above, and most no-solution agreed
  std::vector<std::pair<AuthorsCause, int>> causes;
  std::vector<std::pair<std::string, int>> our_statuses;  ///< of their solved records
  std::vector<double> qs;
  std::vector<Quantile> relative_difference, abs_relative_difference, max_dx, max_dy, their_gap,
      prediction_effect, fixpoint_effect, prediction_follower_dx, prediction_leader_dx,
      prediction_target_dx, target_end_dx, plan_ms;
  double total_plan_s = 0.0;
};

[[nodiscard]] AuthorsSummary summarize(const std::vector<AuthorsComparison>& comparisons,
                                       double tolerance = 0.01);

void to_json(nlohmann::json& out, const AuthorsComparison& comparison);
void to_json(nlohmann::json& out, const AuthorsSummary& summary);
/// The summary as Markdown tables.
[[nodiscard]] std::string to_markdown(const AuthorsSummary& summary);

/// `lanechange authors-study`: every record compared, written to out_dir as
/// comparisons.jsonl (one comparison a line), summary.json and summary.md.
struct AuthorsStudyOptions {
  std::string records_path;  ///< the authors' records (JSON lines)
  std::string out_dir;
  Config config = make_preset("authors");
  AuthorsComparisonSettings settings;
  AuthorsProgress progress = nullptr;
};

/// Runs the study and returns summary.md's text (with the wall time).
/// InputError for unreadable records or an output that cannot be written.
[[nodiscard]] std::string run_authors_study(const AuthorsStudyOptions& options);

}  // namespace lanechange::studies
