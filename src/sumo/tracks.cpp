#include "sumo/tracks.hpp"

#include <utility>

namespace lanechange::sumo::detail {

namespace {

void grow(CarTrack& track, std::size_t nodes) {
  track.x.resize(nodes, 0.0);
  track.v.resize(nodes, 0.0);
  track.a.resize(nodes, 0.0);
  track.present.resize(nodes, 0);
}

// An absent node holds the values of the nearest present one: the stay's
// first before it, its last after it.
void fill_absent(CarTrack& t) {
  std::size_t first = 0;
  while (first < t.present.size() && t.present[first] == 0) ++first;
  if (first == t.present.size()) return;
  std::size_t from = first;
  for (std::size_t k = 0; k < t.present.size(); ++k) {
    if (t.present[k] != 0) {
      from = k;
      continue;
    }
    const std::size_t src = k < first ? first : from;
    t.x[k] = t.x[src];
    t.v[k] = t.v[src];
    t.a[k] = t.a[src];
  }
}

}  // namespace

void TrackRecorder::record(int node, const std::vector<SumoCar>& cars) {
  const auto at = static_cast<std::size_t>(node);
  for (const SumoCar& car : cars) {
    const auto open = open_.find(car.id);
    const bool continues = open != open_.end() && stays_[open->second].first.lane == car.lane &&
                           stays_[open->second].last_node == node - 1;
    if (!continues) {
      const int n = ++count_[car.id];
      Stay stay{car, node, {}};
      if (n > 1) {
        stay.first.id += '~';
        stay.first.id += std::to_string(n);
      }
      open_[car.id] = stays_.size();
      stays_.push_back(std::move(stay));
    }
    Stay& stay = stays_[open_[car.id]];
    grow(stay.track, at + 1);
    stay.track.x[at] = car.state.x;
    stay.track.v[at] = car.state.v;
    stay.track.a[at] = car.state.a;
    stay.track.present[at] = 1;
    stay.last_node = node;
  }
}

Scenario TrackRecorder::scene(Scenario base, const std::array<std::string, 3>& roles) const {
  for (const Stay& stay : stays_) base.cars.push_back(as_other_car(stay.first, base.behavior));
  for (const Role role : kRoles) {
    const std::string& id = roles[static_cast<std::size_t>(role)];
    base.roles[static_cast<std::size_t>(role)] = id.empty() ? std::nullopt : base.find(id);
  }
  return base;
}

std::vector<CarTrack> TrackRecorder::take_tracks(std::size_t nodes) {
  std::vector<CarTrack> out;
  out.reserve(stays_.size());
  for (Stay& stay : stays_) {
    grow(stay.track, nodes);
    fill_absent(stay.track);
    out.push_back(std::move(stay.track));
  }
  return out;
}

}  // namespace lanechange::sumo::detail
