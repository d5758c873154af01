#include "sumo/highway.hpp"

#include <algorithm>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace lanechange::sumo::detail {

namespace {

// SUMO's passenger car with its defaults written out, so the traffic does
// not change with SUMO's defaults: Krauss car following (sigma: driver
// imperfection, tau: reaction time), speed factor drawn per car.
constexpr const char* kCarType =
    R"x(  <vType id="car" vClass="passenger" length="5" width="1.8" minGap="2.5" accel="2.6" )x"
    R"x(decel="4.5" emergencyDecel="9" sigma="0.5" tau="1" speedFactor="normc(1,0.1,0.2,2)" )x"
    R"x(carFollowModel="Krauss" laneChangeModel="SL2015"/>)x";

constexpr double kCarLength = 5.0;                // m, as kCarType
constexpr double kMinSpacing = kCarLength + 2.5;  // m: length plus minGap

void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path);
}

std::string network(const HighwaySettings& h, double w) {
  std::ostringstream o;
  const double top = h.lanes * w;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<net version=\"1.9\" junctionCornerDetail=\"5\" limitTurnSpeed=\"5.50\">\n"
    << "  <location netOffset=\"0.00,0.00\" convBoundary=\"0.00,0.00," << h.length << ',' << top
    << "\" origBoundary=\"0.00,0.00," << h.length << ',' << top << "\" projParameter=\"!\"/>\n"
    << "  <edge id=\"" << kHighwayEdge << "\" from=\"start\" to=\"end\" priority=\"-1\">\n";
  for (int i = 0; i < h.lanes; ++i) {
    const double y = (i + 0.5) * w;
    o << "    <lane id=\"" << highway_lane(i) << "\" index=\"" << i << "\" speed=\""
      << h.speed_limit << "\" length=\"" << h.length << "\" width=\"" << w << "\" shape=\"0.00,"
      << y << ' ' << h.length << ',' << y << "\"/>\n";
  }
  std::string lanes;
  for (int i = 0; i < h.lanes; ++i) {
    if (i > 0) lanes += ' ';
    lanes += highway_lane(i);
  }
  o << "  </edge>\n"
    << "  <junction id=\"start\" type=\"dead_end\" x=\"0.00\" y=\"" << top
    << "\" incLanes=\"\" intLanes=\"\" shape=\"0.00," << top << " 0.00,0.00\"/>\n"
    << "  <junction id=\"end\" type=\"dead_end\" x=\"" << h.length << "\" y=\"" << top
    << "\" incLanes=\"" << lanes << "\" intLanes=\"\" shape=\"" << h.length << ",0.00 " << h.length
    << ',' << top << "\"/>\n"
    << "</net>\n";
  return o.str();
}

// Cars spread evenly over each lane with a random offset each, all at their
// desired speed; an inflow per lane of density x speed limit keeps the
// density once the first cars have left the road.
std::string traffic(const HighwaySettings& h) {
  std::mt19937 rng(static_cast<std::mt19937::result_type>(h.seed));
  std::ostringstream o;
  o << "<routes>\n" << kCarType << "\n";
  o << "  <route id=\"" << kHighwayRoute << "\" edges=\"" << kHighwayEdge << "\"/>\n";
  const int per_lane = static_cast<int>(h.density * h.length / 1000.0);
  const double spacing = h.length / std::max(1, per_lane);
  std::uniform_real_distribution<double> jitter(0.0, std::max(0.0, spacing - kMinSpacing));
  for (int k = 0; k < per_lane; ++k) {
    for (int lane = 0; lane < h.lanes; ++lane) {
      const double front = k * spacing + kCarLength + jitter(rng);
      if (front > h.length) continue;
      o << "  <vehicle id=\"c" << lane << '_' << k << "\" type=\"car\" route=\"" << kHighwayRoute
        << "\" depart=\"0\" departLane=\"" << lane << "\" departPos=\"" << front
        << "\" departSpeed=\"desired\"/>\n";
    }
  }
  const double per_hour = h.density * h.speed_limit * 3.6;
  for (int lane = 0; lane < h.lanes; ++lane) {
    o << "  <flow id=\"in" << lane << "\" type=\"car\" route=\"" << kHighwayRoute
      << "\" begin=\"0\" end=\"86400\" departLane=\"" << lane
      << "\" departSpeed=\"max\" vehsPerHour=\"" << per_hour << "\"/>\n";
  }
  o << "</routes>\n";
  return o.str();
}

}  // namespace

std::string highway_lane(int index) {
  std::string id = kHighwayEdge;
  id += '_';
  id += std::to_string(index);
  return id;
}

HighwayFiles write_highway(const HighwaySettings& highway, double lane_width,
                           const std::string& dir) {
  HighwayFiles files{dir + "/highway.net.xml", dir + "/highway.rou.xml"};
  write_file(files.network, network(highway, lane_width));
  write_file(files.routes, traffic(highway));
  return files;
}

}  // namespace lanechange::sumo::detail
