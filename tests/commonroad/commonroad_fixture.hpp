#pragma once
// A small CommonRoad 2020a file written by the tests: a straight two-lane
// road, the ego lane (lanelet 10) centred on y = 0 and lanelet 11 to its left,
// 3.5 m wide, the whole scene turned by `turn` about the origin.
#include <cmath>
#include <sstream>
#include <string>

namespace lanechange::testing {

struct Placed {
  double x;
  double y;
};

inline Placed turned(double x, double y, double turn) {
  return {x * std::cos(turn) - y * std::sin(turn), x * std::sin(turn) + y * std::cos(turn)};
}

inline std::string bound_xml(const char* name, double y, double turn) {
  std::ostringstream out;
  out.precision(12);
  out << "<" << name << ">";
  for (double x = -200.0; x <= 400.0; x += 50.0) {
    const Placed p = turned(x, y, turn);
    out << "<point><x>" << p.x << "</x><y>" << p.y << "</y></point>";
  }
  out << "</" << name << ">";
  return out.str();
}

inline std::string state_xml(const char* tag, int step, double x, double y, double heading,
                             double v, double turn) {
  const Placed p = turned(x, y, turn);
  std::ostringstream out;
  out.precision(12);
  out << "<" << tag << "><position><point><x>" << p.x << "</x><y>" << p.y
      << "</y></point></position><orientation><exact>" << heading + turn
      << "</exact></orientation><time><exact>" << step << "</exact></time><velocity><exact>" << v
      << "</exact></velocity><acceleration><exact>0</exact></acceleration></" << tag << ">";
  return out.str();
}

/// A car driving at speed v for 61 steps from x0; its y after step 10 moves
/// by `drift` per step up to 3.6 m (a change into lanelet 11).
inline std::string obstacle_xml(int id, const char* type, double length, double width, double x0,
                                double y0, double v, double drift, double turn) {
  std::ostringstream out;
  out.precision(12);
  out << "<dynamicObstacle id=\"" << id << "\"><type>" << type
      << "</type><shape><rectangle><length>" << length << "</length><width>" << width
      << "</width></rectangle></shape>";
  out << state_xml("initialState", 0, x0, y0, 0.0, v, turn) << "<trajectory>";
  for (int k = 1; k <= 60; ++k) {
    const double y = std::min(y0 + drift * std::max(0, k - 10), 3.6);
    const double heading = y < 3.6 && drift > 0.0 && k > 10 ? std::atan2(drift, v * 0.1) : 0.0;
    out << state_xml("state", k, x0 + v * 0.1 * k, y, heading, v, turn);
  }
  out << "</trajectory></dynamicObstacle>";
  return out.str();
}

/// The file: a planning problem at the origin at 10 m/s; car 2 ahead in the
/// ego lane, truck 3 and car 4 in lanelet 11, and car 5, which starts 30 m
/// behind the problem's ego and changes into lanelet 11 between them (its
/// centre crosses at step 25).
inline std::string two_lane_commonroad(double turn = 0.0) {
  std::ostringstream out;
  out << R"(<?xml version="1.0" encoding="UTF-8"?>
<commonRoad benchmarkID="TEST_Two-1_1_T-1" commonRoadVersion="2020a" timeStepSize="0.1">
<lanelet id="10">)"
      << bound_xml("leftBound", 1.75, turn) << bound_xml("rightBound", -1.75, turn)
      << R"(<adjacentLeft ref="11" drivingDir="same"/></lanelet>
<lanelet id="11">)"
      << bound_xml("leftBound", 5.25, turn) << bound_xml("rightBound", 1.75, turn)
      << R"(<adjacentRight ref="10" drivingDir="same"/></lanelet>
)";
  out << obstacle_xml(2, "car", 4.5, 1.8, 30.0, 0.0, 8.0, 0.0, turn) << "\n"
      << obstacle_xml(3, "truck", 12.0, 2.5, -60.0, 3.5, 9.0, 0.0, turn) << "\n"
      << obstacle_xml(4, "car", 4.8, 1.9, 25.0, 3.5, 9.0, 0.0, turn) << "\n"
      << obstacle_xml(5, "car", 4.4, 1.7, -30.0, 0.0, 9.0, 0.12, turn) << "\n";
  out << R"(<planningProblem id="100">)" << state_xml("initialState", 0, 0.0, 0.0, 0.0, 10.0, turn)
      << "</planningProblem>\n</commonRoad>\n";
  return out.str();
}

}  // namespace lanechange::testing
