#include "lanechange/expert/gap_slots.hpp"

#include <algorithm>

namespace lanechange::expert {

namespace {

// Two gaps framed by the same cars are the same place, whichever cars
// further out each lists (Eq. 1's gap lists only the follower and target).
bool same_place(const Gap& a, const Gap& b) {
  return a.car_behind() == b.car_behind() && a.car_ahead() == b.car_ahead();
}

// A car relative to the ego; none reads as a car `open_side` x
// kOpenGapDistance away at the ego's speed.
std::array<double, 3> relative(const CarState* car, const EgoState& ego, double open_side) {
  if (car == nullptr) return {open_side * kOpenGapDistance, 0.0, 0.0};
  return {car->x - ego.x, car->v - ego.v, car->a};
}

void put_car(std::vector<double>& out, const Scenario& s, std::optional<CarIndex> car,
             double open_side) {
  const auto view = relative(car ? &s.car(*car) : nullptr, s.ego, open_side);
  out.insert(out.end(), view.begin(), view.end());
}

void add_car_names(std::vector<std::string>& names, const std::string& car) {
  for (const char* q : {"_dx", "_dv", "_a"}) names.push_back(car + q);
}

std::vector<CarState> cars_now(const Scenario& s) {
  std::vector<CarState> now;
  now.reserve(s.cars.size());
  for (const OtherCar& car : s.cars) now.push_back(car.state);
  return now;
}

}  // namespace

int GapSlots::slot_of(const Gap& gap) const {
  for (int slot = 0; slot < kGapSlots; ++slot) {
    const auto& g = gaps[static_cast<std::size_t>(slot)];
    if (g && same_place(*g, gap)) return slot;
  }
  return -1;
}

GapSlots gap_slots(const Scenario& scenario) {
  const std::vector<Gap> lane = target_lane_gaps(scenario, GapChoice::Best);
  // Gap i lies ahead of the lane's i rearmost cars; the ego stands beside
  // the one ahead of every car at or behind its centre.
  long beside = 0;
  for (const OtherCar& car : scenario.cars) {
    beside += car.lane == Lane::Target && car.state.x <= scenario.ego.x ? 1 : 0;
  }
  GapSlots slots;
  for (int slot = 0; slot < kGapSlots; ++slot) {
    const long index = beside + slot - kGapSlotBeside;
    if (index >= 0 && index < static_cast<long>(lane.size())) {
      slots.gaps[static_cast<std::size_t>(slot)] = lane[static_cast<std::size_t>(index)];
    }
  }
  return slots;
}

std::string_view gap_slot_name(int slot) {
  static constexpr std::array<std::string_view, kGapSlots> names = {"m2", "m1", "0", "p1", "p2"};
  return names.at(static_cast<std::size_t>(slot));
}

const std::vector<std::string>& gap_feature_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n = {"ego_v0", "ego_a0"};
    add_car_names(n, "lane_ahead");
    add_car_names(n, "lane_behind");
    for (int slot = 0; slot < kGapSlots; ++slot) {
      const std::string prefix = "gap_" + std::string(gap_slot_name(slot));
      add_car_names(n, prefix + "_behind");
      add_car_names(n, prefix + "_ahead");
    }
    return n;
  }();
  return names;
}

std::vector<double> gap_features(const Scenario& s, const GapSlots& slots) {
  std::vector<double> out = {s.ego.v, s.ego.a};
  out.reserve(gap_feature_names().size());
  const std::vector<CarState> now = cars_now(s);
  put_car(out, s, nearest_in_lane(s, now, Lane::Ego, s.ego.x, true), 1.0);
  put_car(out, s, nearest_in_lane(s, now, Lane::Ego, s.ego.x, false), -1.0);
  for (int slot = 0; slot < kGapSlots; ++slot) {
    const auto& gap = slots.gaps[static_cast<std::size_t>(slot)];
    if (gap) {
      put_car(out, s, gap->car_behind(), -1.0);
      put_car(out, s, gap->car_ahead(), 1.0);
      continue;
    }
    // No such gap: one of no length beyond the lane's end on that side.
    const double side = slot < kGapSlotBeside ? -1.0 : 1.0;
    put_car(out, s, std::nullopt, side);
    put_car(out, s, std::nullopt, side);
  }
  return out;
}

const std::vector<std::string>& gap_view_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const char* car : {"gap_behind", "gap_ahead", "leader"}) add_car_names(n, car);
    return n;
  }();
  return names;
}

std::array<double, kGapViewSize> gap_view(const Scenario& scene, std::span<const CarState> cars,
                                          const EgoState& ego, const GapFrame& frame) {
  const auto car = [cars](std::optional<CarIndex> c) { return c ? &cars[*c] : nullptr; };
  const auto leader = nearest_in_lane(scene, cars, Lane::Ego, ego.x, true);
  std::array<double, kGapViewSize> view{};
  auto at = view.begin();
  for (const auto& part : {relative(car(frame.behind), ego, -1.0),
                           relative(car(frame.ahead), ego, 1.0), relative(car(leader), ego, 1.0)}) {
    at = std::copy(part.begin(), part.end(), at);
  }
  return view;
}

}  // namespace lanechange::expert
