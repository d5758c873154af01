#pragma once
// The built-in highway's files for SUMO: a straight network and its traffic.
#include <string>

#include "lanechange/config.hpp"
#include "lanechange/sumo/cosim.hpp"

namespace lanechange::sumo::detail {

inline constexpr const char* kHighwayEdge = "road";
inline constexpr const char* kHighwayRoute = "road_route";

struct HighwayFiles {
  std::string network;  ///< .net.xml
  std::string routes;   ///< .rou.xml
};

/// Writes the network (one edge of `lanes` lanes of `lane_width` along +x,
/// lane i centred at y = (i + 1/2) lane_width) and the traffic (cars spread
/// over the road at the density, and an inflow per lane that keeps it) into
/// `dir`, which must exist.
[[nodiscard]] HighwayFiles write_highway(const HighwaySettings& highway, double lane_width,
                                         const std::string& dir);

/// SUMO's lane id of lane `index` of the highway.
[[nodiscard]] std::string highway_lane(int index);

}  // namespace lanechange::sumo::detail
