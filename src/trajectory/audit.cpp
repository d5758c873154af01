#include "lanechange/audit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace lanechange {
namespace {

std::string describe(const char* pattern, int k, double value) {
  char buffer[200];
  std::snprintf(buffer, sizeof buffer, pattern, k, value);
  return buffer;
}

void check_dynamics(const Trajectory& tr, const Scenario& s, double tol,
                    std::vector<std::string>& problems) {
  const EgoState& first = tr.ego.front();
  if (std::abs(first.x - s.ego.x) > tol || std::abs(first.y - s.ego.y) > tol ||
      std::abs(first.v - s.ego.v) > tol || std::abs(first.theta - s.ego.theta) > tol) {
    problems.emplace_back("the first state is not the scenario's ego state");
  }
  for (int k = 0; k + 1 < tr.nodes(); ++k) {
    const EgoState next = step_trapezoidal(tr.ego[k], tr.controls[k], tr.dt);
    const double gap =
        std::max({std::abs(next.x - tr.ego[k + 1].x), std::abs(next.y - tr.ego[k + 1].y),
                  std::abs(next.v - tr.ego[k + 1].v), std::abs(next.theta - tr.ego[k + 1].theta)});
    if (gap > tol) {
      problems.push_back(
          describe("state %d does not follow from the controls (off by %.3g)", k + 1, gap));
      return;
    }
  }
}

void check_bounds(const Trajectory& tr, const Scenario& s, const Config& config,
                  const AuditTolerances& tol, std::vector<std::string>& problems) {
  const Limits& lim = s.limits;
  const double radius = config.expert.min_turn_radius;
  for (int k = 0; k + 1 < tr.nodes(); ++k) {
    const EgoControl& u = tr.controls[k];
    if (radius > 0.0 && std::abs(u.omega) > tr.ego[k].v / radius + tol.controls) {
      problems.push_back(
          describe("omega[%d] = %.4f turns tighter than min_turn_radius", k, u.omega));
    }
    if (u.a < lim.a.lo - tol.controls || u.a > lim.a.hi + tol.controls) {
      problems.push_back(describe("a[%d] = %.4f is out of its bounds", k, u.a));
    }
    if (u.omega < lim.omega.lo - tol.controls || u.omega > lim.omega.hi + tol.controls) {
      problems.push_back(describe("omega[%d] = %.4f is out of its bounds", k, u.omega));
    }
  }
  for (int k = 1; k < tr.nodes(); ++k) {
    const EgoState& z = tr.ego[k];
    const Interval speed = s.speed_bounds_at(tr.t[k]);
    if (z.v < speed.lo - tol.states || z.v > speed.hi + tol.states) {
      problems.push_back(describe("v[%d] = %.4f is out of its bounds", k, z.v));
    }
    if (z.y < -lim.lateral_margin - tol.states ||
        z.y > s.lane_width + lim.lateral_margin + tol.states) {
      problems.push_back(describe("y[%d] = %.4f leaves the road band", k, z.y));
    }
  }
}

void check_label(const Trajectory& tr, const Scenario& s, const Config& config,
                 std::vector<std::string>& problems) {
  const auto collision = first_collision(tr.ego, tr.others, s);
  if (collision.has_value() != tr.collision) {
    problems.emplace_back("the collision flag disagrees with the collision check");
  }
  if (tr.label == Label::Failure) {
    if (tr.reason.empty()) problems.emplace_back("a failure without a reason");
    return;
  }
  if (collision) problems.emplace_back("labelled a success, but the ego collides");
  const Labelled expected =
      label_trajectory(tr.ys(), tr.ego.back().theta, s.lane_width, config.labels);
  if (expected.label != tr.label) {
    problems.push_back("labelled " + std::string(to_string(tr.label)) + ", but the labeller says " +
                       std::string(to_string(expected.label)) + " (" + expected.reason + ")");
  }
}

}  // namespace

std::vector<std::string> audit_trajectory(const Trajectory& tr, const Scenario& s,
                                          const Config& config, const AuditTolerances& tol) {
  std::vector<std::string> problems;
  const int n = tr.nodes();
  if (n == 0 || static_cast<int>(tr.ego.size()) != n || static_cast<int>(tr.controls.size()) != n ||
      std::any_of(tr.others.cars.begin(), tr.others.cars.end(),
                  [n](const CarTrack& c) { return static_cast<int>(c.x.size()) != n; })) {
    problems.emplace_back("the arrays do not all have the same, non-zero length");
    return problems;
  }
  for (int k = 0; k < n; ++k) {
    if (std::abs(tr.t[k] - k * tr.dt) > 1e-9) {
      problems.push_back(describe("t[%d] = %.6f is off the grid", k, tr.t[k]));
      break;
    }
  }
  check_dynamics(tr, s, tol.dynamics, problems);
  check_bounds(tr, s, config, tol, problems);
  check_label(tr, s, config, problems);
  return problems;
}

}  // namespace lanechange
