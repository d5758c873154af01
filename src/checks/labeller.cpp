#include <algorithm>
#include <cmath>
#include <cstdio>

#include "lanechange/checks.hpp"
#include "lanechange/error.hpp"

namespace lanechange {

std::string_view to_string(Label label) {
  switch (label) {
    case Label::WellPosed: return "well_posed";
    case Label::IllPosed: return "ill_posed";
    case Label::Failure: return "failure";
  }
  return "?";
}

Label label_from_string(std::string_view name) {
  for (Label l : {Label::WellPosed, Label::IllPosed, Label::Failure}) {
    if (to_string(l) == name) return l;
  }
  throw InputError("label", "unknown label \"" + std::string(name) +
                                "\" (expected well_posed, ill_posed or failure)");
}

double largest_lateral_reversal(std::span<const double> y, double cap) {
  double running_max = -INFINITY;
  double largest = 0.0;
  for (double value : y) {
    running_max = std::min(std::max(running_max, value), cap);
    largest = std::max(largest, running_max - value);
  }
  return largest;
}

namespace {

std::string format(const char* pattern, double a, double b) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, pattern, a, b);
  return buffer;
}

}  // namespace

Labelled label_trajectory(std::span<const double> y, double final_theta, double lane_width,
                          const LabelTolerances& tol) {
  if (y.empty()) return {Label::Failure, "empty trajectory"};
  const double miss = std::abs(y.back() - lane_width);
  if (!(miss <= tol.reach)) {
    return {Label::Failure, format("did not reach the target lane: |y(t_f) - w| = %.3f m > %.3f m",
                                   miss, tol.reach)};
  }
  const double cap = tol.reference == ReversalReference::TargetCenter ? lane_width : INFINITY;
  const double reversal = largest_lateral_reversal(y, cap);
  if (reversal > tol.reversal) {
    return {Label::IllPosed,
            format(tol.reference == ReversalReference::TargetCenter
                       ? "y moves back %.3f m towards the ego lane (tolerance %.3f m)"
                       : "y drops %.3f m below its running maximum (tolerance %.3f m)",
                   reversal, tol.reversal)};
  }
  if (!(std::abs(final_theta) <= tol.max_final_heading)) {
    return {Label::IllPosed,
            format("|theta(t_f)| = %.2f deg exceeds %.2f deg", std::abs(final_theta) * 180.0 / M_PI,
                   tol.max_final_heading * 180.0 / M_PI)};
  }
  return {Label::WellPosed, ""};
}

}  // namespace lanechange
