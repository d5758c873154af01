#include "lanechange/commonroad/import.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <variant>

#include "commonroad/lanes.hpp"
#include "lanechange/error.hpp"

namespace lanechange::commonroad {
namespace {

using detail::LaneChain;
using detail::LaneNetwork;
using detail::Projection;

// One ego at one moment: a planning problem's initial state, or a recorded
// car's state at a step of its record.
struct StartPoint {
  std::string ego;
  const Obstacle* recorded = nullptr;  ///< none for a planning problem
  State state;
};

double wrapped(double angle) { return std::remainder(angle, 2.0 * std::numbers::pi); }

std::vector<StartPoint> planning_problem_starts(const Recording& rec) {
  std::vector<StartPoint> out;
  for (const PlanningProblem& p : rec.planning_problems)
    out.push_back({std::to_string(p.id), nullptr, p.initial});
  return out;
}

std::vector<const Obstacle*> chosen_cars(const Recording& rec, const ImportSettings& settings) {
  std::vector<const Obstacle*> cars;
  if (settings.cars.empty()) {
    for (const Obstacle& o : rec.obstacles) cars.push_back(&o);
    return cars;
  }
  for (const int id : settings.cars) {
    const auto it = std::find_if(rec.obstacles.begin(), rec.obstacles.end(),
                                 [&](const Obstacle& o) { return o.id == id; });
    if (it == rec.obstacles.end()) {
      throw InputError("--ego",
                       rec.benchmark_id + " has no dynamic obstacle " + std::to_string(id));
    }
    cars.push_back(&*it);
  }
  return cars;
}

std::vector<StartPoint> recorded_car_starts(const Recording& rec, const ImportSettings& settings,
                                            ImportReport& report) {
  const int every = std::max(1, static_cast<int>(std::lround(settings.every / rec.time_step_size)));
  const int after = static_cast<int>(std::ceil(settings.min_record_after / rec.time_step_size));
  std::vector<StartPoint> out;
  for (const Obstacle* o : chosen_cars(rec, settings)) {
    const int last = o->states.back().time_step;
    const std::size_t before = out.size();
    for (int t = o->states.front().time_step; t + after <= last; t += every)
      out.push_back({std::to_string(o->id), o, *o->at(t)});
    if (out.size() == before) {
      char reason[80];
      std::snprintf(reason, sizeof reason, "a car recorded for less than %g s",
                    settings.min_record_after);
      ++report.skipped[reason];
    }
  }
  return out;
}

// The scene's safe distances are stated for a car of the default vehicle's
// length, centre to centre: a recorded ego of another length keeps the same
// clear space, or a truck's centre distance would let its body overlap a car.
void ride_in_recorded_body(Scenario& s, const Obstacle& ego) {
  const double longer_by = ego.length - s.vehicle.length;
  for (SafeDistance* d :
       {&s.safe_distance.leader, &s.safe_distance.follower, &s.safe_distance.target}) {
    d->standstill = std::max(0.0, d->standstill + longer_by);
  }
  s.vehicle = {ego.length, ego.width};
}

class Cutter {
 public:
  Cutter(const Recording& rec, const Config& defaults, const ImportSettings& settings)
      : rec_(rec), net_(rec), defaults_(defaults), settings_(settings) {
    lanelets_.reserve(rec.obstacles.size());
    for (const Obstacle& o : rec.obstacles) {
      std::vector<std::optional<int>> per_step;
      per_step.reserve(o.states.size());
      for (const State& s : o.states) per_step.push_back(net_.lanelet_at(s.position));
      lanelets_.push_back(std::move(per_step));
    }
  }

  // The scene, or why there is none.
  std::variant<Scenario, std::string> cut(const StartPoint& start, Side side) const {
    const bool left = side == Side::Left;
    const auto ego_lanelet = net_.lanelet_at(start.state.position);
    if (!ego_lanelet) return std::string("the ego is not on a lanelet");
    const Lanelet& own = *rec_.lanelet(*ego_lanelet);
    if (!(left ? own.adjacent_left : own.adjacent_right)) {
      return std::string("no lane beside the ego's on the ") + (left ? "left" : "right");
    }
    const LaneChain lane = net_.lane_through(*ego_lanelet);
    const std::set<int> target = net_.neighbours(lane, left);
    const Projection ego = lane.centre.project(start.state.position);

    Scenario s = default_scenario(defaults_);
    s.lane_width = net_.width_near(*ego_lanelet, start.state.position);
    s.target_side = side;
    s.behavior = settings_.behavior;
    s.limits.v.hi = std::max(s.limits.v.hi, settings_.max_speed);
    if (start.recorded) ride_in_recorded_body(s, *start.recorded);
    const double sign = mirror_sign(side);
    s.ego = {0.0, sign * ego.d, start.state.velocity,
             sign * wrapped(start.state.orientation - ego.heading), start.state.acceleration};
    add_cars(s, start, lane, target, ego.s);
    for (const Role role : kRoles)
      s.roles[static_cast<std::size_t>(role)] = nearest_in_role(s, role);
    // IDM cars would brake at once below a desired speed of the paper's city.
    for (const OtherCar& car : s.cars)
      s.idm.desired_speed = std::max(s.idm.desired_speed, car.state.v);
    s.origin = SceneOrigin{rec_.benchmark_id, start.state.time_step * rec_.time_step_size,
                           start.ego, start.recorded == nullptr, std::nullopt};
    if (start.recorded) s.origin->human_change = human_change(start, lane, target);
    try {
      validate_scenario(s);
    } catch (const InputError& e) {
      const std::string what = e.what();
      if (what.find("overlaps") != std::string::npos)
        return std::string("two cars overlap as placed in the two lanes");
      return "the scene is not valid (" + what + ")";
    }
    return s;
  }

 private:
  std::optional<int> lanelet_of(const Obstacle& o, int time_step) const {
    const auto index = static_cast<std::size_t>(&o - rec_.obstacles.data());
    return lanelets_[index][static_cast<std::size_t>(time_step - o.states.front().time_step)];
  }

  void add_cars(Scenario& s, const StartPoint& start, const LaneChain& lane,
                const std::set<int>& target, double ego_s) const {
    const int t = start.state.time_step;
    const std::set<int> own_lane(lane.lanelets.begin(), lane.lanelets.end());
    for (const Obstacle& o : rec_.obstacles) {
      const State* state = o.at(t);
      if (&o == start.recorded || state == nullptr) continue;
      const auto at = lanelet_of(o, t);
      if (!at || !(lane.holds(*at) || target.contains(*at))) continue;
      const Projection p = lane.centre.project(state->position);
      if (std::abs(p.s - ego_s) > settings_.range) continue;
      OtherCar car;
      car.id = std::to_string(o.id);
      car.lane = lane.holds(*at) ? Lane::Ego : Lane::Target;
      car.state = {p.s - ego_s, speed_along(*state, p), state->acceleration};
      car.behavior =
          settings_.reactive_behind && car.state.x < 0.0 ? Behavior::Idm : settings_.behavior;
      car.size = VehicleSize{o.length, o.width};
      if (car.behavior == Behavior::Replay) {
        car.record = track(o, t, lane, car.lane == Lane::Ego ? own_lane : target, ego_s);
      }
      s.cars.push_back(std::move(car));
    }
    std::sort(s.cars.begin(), s.cars.end(), [](const OtherCar& a, const OtherCar& b) {
      return a.lane != b.lane ? a.lane == Lane::Ego : a.state.x < b.state.x;
    });
  }

  static double speed_along(const State& state, const Projection& p) {
    return std::max(state.velocity * std::cos(wrapped(state.orientation - p.heading)), 0.0);
  }

  // The car's record from step t on, along the ego lane's centre line, for
  // as long as its centre stays in `own` (the lanelets of its lane).
  RecordedTrack track(const Obstacle& o, int t, const LaneChain& lane, const std::set<int>& own,
                      double ego_s) const {
    RecordedTrack out;
    out.dt = rec_.time_step_size;
    for (int k = t; k <= o.states.back().time_step; ++k) {
      const auto at = lanelet_of(o, k);
      if (!at || !own.contains(*at)) break;
      const State& state = *o.at(k);
      const Projection p = lane.centre.project(state.position);
      out.x.push_back(p.s - ego_s);
      out.v.push_back(speed_along(state, p));
    }
    return out;
  }

  // The recorded ego's first step with its centre in the target lane, and
  // the cars around it there; none where it left its lane the other way or
  // the record ends first.
  std::optional<HumanLaneChange> human_change(const StartPoint& start, const LaneChain& lane,
                                              const std::set<int>& target) const {
    const Obstacle& ego = *start.recorded;
    for (int k = start.state.time_step + 1; k <= ego.states.back().time_step; ++k) {
      const auto at = lanelet_of(ego, k);
      if (!at || lane.holds(*at)) continue;
      if (!target.contains(*at)) return std::nullopt;
      HumanLaneChange change;
      change.after = (k - start.state.time_step) * rec_.time_step_size;
      const double ego_s = lane.centre.project(ego.at(k)->position).s;
      double behind = -1e300;
      double ahead = 1e300;
      for (const Obstacle& o : rec_.obstacles) {
        const State* state = o.at(k);
        if (&o == &ego || state == nullptr) continue;
        const auto their = lanelet_of(o, k);
        if (!their || !target.contains(*their)) continue;
        const double s = lane.centre.project(state->position).s - ego_s;
        if (s <= 0.0 && s > behind) {
          behind = s;
          change.behind = std::to_string(o.id);
        } else if (s > 0.0 && s < ahead) {
          ahead = s;
          change.ahead = std::to_string(o.id);
        }
      }
      return change;
    }
    return std::nullopt;
  }

  const Recording& rec_;
  LaneNetwork net_;
  const Config& defaults_;
  const ImportSettings& settings_;
  std::vector<std::vector<std::optional<int>>> lanelets_;  ///< per obstacle and state
};

std::string scene_name(const Recording& rec, const StartPoint& start, Side side) {
  std::string name = rec.benchmark_id + "_";
  name += start.recorded
              ? std::string("car") + start.ego + "_t" + std::to_string(start.state.time_step)
              : "problem" + start.ego;
  return name + "_" + std::string(to_string(side));
}

}  // namespace

ImportReport import_scenes(const Recording& recording, const Config& defaults,
                           const ImportSettings& settings) {
  ImportReport report;
  const std::vector<StartPoint> starts = settings.egos == EgoChoice::PlanningProblems
                                             ? planning_problem_starts(recording)
                                             : recorded_car_starts(recording, settings, report);
  const Cutter cutter(recording, defaults, settings);
  std::vector<Side> sides{Side::Left};
  if (settings.right) sides.push_back(Side::Right);
  for (const StartPoint& start : starts) {
    for (const Side side : sides) {
      auto cut = cutter.cut(start, side);
      if (auto* reason = std::get_if<std::string>(&cut)) {
        ++report.skipped[*reason];
      } else {
        report.scenes.push_back(
            {scene_name(recording, start, side), std::move(std::get<Scenario>(cut))});
      }
    }
  }
  return report;
}

}  // namespace lanechange::commonroad
