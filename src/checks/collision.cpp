#include "lanechange/checks.hpp"
#include "lanechange/geometry.hpp"

namespace lanechange {

namespace {

double lerp(double a, double b, double s) { return a + s * (b - a); }

}  // namespace

std::optional<Collision> first_collision(std::span<const EgoState> ego,
                                         const TrafficPrediction& others, const Scenario& scenario,
                                         int substeps) {
  const int nodes = std::min(static_cast<int>(ego.size()), others.nodes());
  const double length = scenario.vehicle.length;
  const double width = scenario.vehicle.width;
  for (int k = 0; k < nodes; ++k) {
    const int pieces = k + 1 < nodes ? substeps : 1;
    for (int piece = 0; piece < pieces; ++piece) {
      const double s = static_cast<double>(piece) / pieces;
      const EgoState& a = ego[k];
      const EgoState& b = ego[std::min(k + 1, nodes - 1)];
      const OrientedBox ego_box{lerp(a.x, b.x, s), lerp(a.y, b.y, s), lerp(a.theta, b.theta, s),
                                length, width};
      for (CarIndex car = 0; car < others.car_count(); ++car) {
        const CarTrack& track = others.car(car);
        const auto next = static_cast<std::size_t>(std::min(k + 1, nodes - 1));
        if (!track.present_at(static_cast<std::size_t>(k)) || !track.present_at(next)) continue;
        const double x = lerp(track.x[k], track.x[std::min(k + 1, nodes - 1)], s);
        const VehicleSize size = scenario.size_of(car);
        if (boxes_collide(ego_box, {x, scenario.lane_center(car), 0.0, size.length, size.width})) {
          return Collision{k, (k + s) * others.dt, car};
        }
      }
    }
  }
  return std::nullopt;
}

}  // namespace lanechange
