#include "baselines/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

#include "baselines/sampling.hpp"

namespace lanechange::baselines {

namespace {

// Below this speed the heading of a Frenet state is ill-defined (m/s).
constexpr double kMinSpeed = 0.5;

std::vector<double> durations(const LatticeSettings& s) {
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(s.duration_samples));
  for (int i = 0; i < s.duration_samples; ++i) {
    out.push_back(s.duration_samples == 1 ? s.max_duration
                                          : s.min_duration + (s.max_duration - s.min_duration) * i /
                                                                 (s.duration_samples - 1));
  }
  return out;
}

// The ego lane's centre and, while the change is on, the target lane's with
// offsets around it (Apollo samples {0, +-0.5} m).
std::vector<double> end_offsets(const planner::Observation& o, const LatticeSettings& s) {
  const double lane_width = o.scene->lane_width;
  std::vector<double> out{0.0};
  if (!lane_change_on(o)) return out;
  out.push_back(lane_width);
  if (s.offset_spread > 0) {
    out.push_back(lane_width - s.offset_spread);
    out.push_back(lane_width + s.offset_spread);
  }
  return out;
}

std::vector<double> end_speeds(double speed, const Limits& limits, const LatticeSettings& s) {
  std::vector<double> out{std::clamp(s.desired_speed, limits.v.lo, limits.v.hi)};
  for (int i = 0; i < s.speed_samples; ++i) {
    const double v = speed + (i - (s.speed_samples - 1) / 2.0) * s.speed_step;
    out.push_back(std::clamp(v, limits.v.lo, limits.v.hi));
  }
  return out;
}

// The car to follow in the lane of an end offset: the nearest one ahead of
// the ego now, with its safe distance of Eq. 1.
struct Followed {
  CarIndex car;
  SafeDistance distance;
};

std::optional<Followed> followed_car(const planner::Observation& o, double end_offset) {
  const Scenario& scene = *o.scene;
  const bool target_lane = end_offset > scene.lane_width / 2.0;
  const auto ahead = planner::car_ahead(o, target_lane);
  if (!ahead) return std::nullopt;
  const SafeDistance d = scene.centre_safe_distance(
      ahead->car, target_lane ? scene.safe_distance.target : scene.safe_distance.leader);
  return Followed{ahead->car, d};
}

// Werling's cost of each axis: jerk, duration and the end's deviation.
double lateral_cost(const Polynomial& d, double lane_width, const LatticeSettings& s) {
  const double off = d.at(d.duration()).p - lane_width;
  return s.weight_jerk * d.squared_jerk_integral() + s.weight_duration * d.duration() +
         s.weight_offset * off * off;
}

double longitudinal_cost(const Polynomial& x, const LatticeSettings& s) {
  const double dv = x.at(x.duration()).v - s.desired_speed;
  return s.weight_jerk * x.squared_jerk_integral() + s.weight_duration * x.duration() +
         s.weight_speed * dv * dv;
}

}  // namespace

AxisState lateral_start(const EgoState& ego, double last_omega) {
  const double c = std::cos(ego.theta);
  const double s = std::sin(ego.theta);
  return {ego.y, ego.v * s, ego.a * s + ego.v * c * last_omega};
}

AxisState longitudinal_start(const EgoState& ego, double last_omega) {
  const double c = std::cos(ego.theta);
  const double s = std::sin(ego.theta);
  return {ego.x, ego.v * c, ego.a * c - ego.v * s * last_omega};
}

std::vector<FrenetCandidate> lattice_candidates(const planner::Observation& o, double last_omega,
                                                const TrafficPrediction& cars,
                                                const Config& config) {
  const LatticeSettings& s = config.lattice;
  const Scenario& scene = *o.scene;
  const AxisState lat0 = lateral_start(o.ego, last_omega);
  const AxisState lon0 = longitudinal_start(o.ego, last_omega);
  std::vector<FrenetCandidate> out;
  for (const double t : durations(s)) {
    const auto node = std::min(static_cast<std::size_t>(std::lround(t / cars.dt)),
                               static_cast<std::size_t>(cars.nodes() - 1));
    for (const double d1 : end_offsets(o, s)) {
      const Polynomial lat = Polynomial::quintic(lat0, {d1, 0.0, 0.0}, t);
      const double lat_cost = s.weight_lateral * lateral_cost(lat, scene.lane_width, s);
      std::vector<Polynomial> lons;
      for (const double v1 : end_speeds(lon0.v, scene.limits, s)) {
        lons.push_back(Polynomial::quartic(lon0, {0.0, v1, 0.0}, t));
      }
      if (const auto f = followed_car(o, d1)) {
        const double v_car = cars.car(f->car).v[node];
        const double x_end =
            cars.car(f->car).x[node] - f->distance.standstill - f->distance.time_headway * v_car;
        if (x_end > lon0.p) lons.push_back(Polynomial::quintic(lon0, {x_end, v_car, 0.0}, t));
      }
      for (const Polynomial& lon : lons) {
        out.push_back({lat, lon, lat_cost + s.weight_longitudinal * longitudinal_cost(lon, s)});
      }
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const FrenetCandidate& a, const FrenetCandidate& b) {
    return a.cost < b.cost;
  });
  return out;
}

std::vector<EgoState> candidate_path(const FrenetCandidate& c, int steps, double dt) {
  std::vector<EgoState> path;
  path.reserve(static_cast<std::size_t>(steps) + 1);
  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    const AxisState s = c.longitudinal.at(t);
    const AxisState d = c.lateral.at(t);
    const double v = std::hypot(s.v, d.v);
    EgoState e;
    e.x = s.p;
    e.y = d.p;
    e.v = v;
    e.theta = std::atan2(d.v, s.v);
    e.a = v > 0 ? (s.v * s.a + d.v * d.a) / v : 0.0;  // along the path
    path.push_back(e);
  }
  return path;
}

std::string candidate_problem(const std::vector<EgoState>& path, const TrafficPrediction& cars,
                              const Scenario& scene, const LatticeSettings& settings) {
  const Limits& limits = scene.limits;
  const double dt = cars.dt;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const EgoState& e = path[k];
    if (!limits.v.contains(e.v) || e.v < kMinSpeed) return "speed";
    if (!limits.a.contains(e.a)) return "acceleration";
    if (std::abs(e.theta) > settings.max_heading || std::abs(e.theta) >= std::numbers::pi / 2)
      return "heading";
    if (!planner::body_on_road(e.y, scene)) return "road";
    if (k == 0) continue;
    // The unicycle's yaw rate between nodes, and the curvature it means.
    const double omega = (e.theta - path[k - 1].theta) / dt;
    if (!limits.omega.contains(omega)) return "yaw rate";
    if (std::abs(omega) / e.v > settings.max_curvature) return "curvature";
  }
  if (min_separation(path, cars, scene, settings.margin) < settings.margin) return "collision";
  if (settings.keep_safe_distances && !keeps_target_lane_distances(path, cars, scene)) {
    return "safe distance";
  }
  return "";
}

EgoControl first_control(const std::vector<EgoState>& path, double dt) {
  return {(path[1].v - path[0].v) / dt, (path[1].theta - path[0].theta) / dt};
}

namespace {

class LatticeSession final : public planner::PlannerSession {
 public:
  explicit LatticeSession(const Config& config) : config_(config), keeper_(config) {}

  [[nodiscard]] planner::Decision act(const planner::Observation& o) override {
    const LatticeSettings& s = config_.lattice;
    const double dt = o.scene->horizon / o.scene->steps;
    const int steps = std::max(1, static_cast<int>(std::lround(s.max_duration / dt)));
    const TrafficPrediction cars = predict_from(o, config_, steps);
    for (const FrenetCandidate& c : lattice_candidates(o, last_omega_, cars, config_)) {
      const std::vector<EgoState> path = candidate_path(c, steps, dt);
      if (!candidate_problem(path, cars, *o.scene, s).empty()) continue;
      return decide(o, first_control(path, dt), planner::ActStatus::Planned, "");
    }
    return decide(o, planner::fallback_control(keeper_, o), planner::ActStatus::Fallback,
                  "no lattice candidate is valid");
  }

 private:
  planner::Decision decide(const planner::Observation& o, EgoControl u, planner::ActStatus status,
                           std::string reason) {
    (void)planner::clip_to_limits(u, o.ego, o.scene->limits, o.scene->horizon / o.scene->steps);
    last_omega_ = u.omega;
    return {u, status, std::move(reason)};
  }

  const Config& config_;
  planner::LaneKeeper keeper_;
  double last_omega_ = 0.0;  // the observation carries the last a, not the last omega
};

}  // namespace

std::unique_ptr<planner::PlannerSession> LatticePlanner::start(const Scenario& /*scene*/) const {
  return std::make_unique<LatticeSession>(config_);
}

std::shared_ptr<const planner::ClosedLoopPlanner> make_lattice_planner(const Config& config) {
  return std::make_shared<const LatticePlanner>(config);
}

}  // namespace lanechange::baselines
