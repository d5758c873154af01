#include "lanechange/commonroad/recording.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <pugixml.hpp>
#include <set>
#include <sstream>
#include <string>
#include <string_view>

#include "lanechange/error.hpp"

namespace lanechange::commonroad {

const State* Obstacle::at(int time_step) const {
  if (states.empty()) return nullptr;
  const int offset = time_step - states.front().time_step;
  if (offset < 0 || offset >= static_cast<int>(states.size())) return nullptr;
  return &states[static_cast<std::size_t>(offset)];
}

const Lanelet* Recording::lanelet(int id) const {
  const auto it =
      std::find_if(lanelets.begin(), lanelets.end(), [&](const Lanelet& l) { return l.id == id; });
  return it == lanelets.end() ? nullptr : &*it;
}

namespace {

// Names elements in messages by file, line and path, as a user finds them
// in an editor.
class Reader {
 public:
  Reader(const std::string& text, std::string name) : text_(text), name_(std::move(name)) {}

  [[noreturn]] void fail(const pugi::xml_node& node, const std::string& problem) const {
    throw InputError(where(node), problem);
  }

  pugi::xml_node child(const pugi::xml_node& node, const char* name) const {
    const pugi::xml_node c = node.child(name);
    if (!c) fail(node, std::string("has no <") + name + ">");
    return c;
  }

  double number(const pugi::xml_node& node) const {
    const std::string_view text = trimmed(node.child_value());
    double value = 0.0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
      fail(node, std::string("\"").append(text) + "\" is not a finite number");
    }
    return value;
  }

  int integer_attribute(const pugi::xml_node& node, const char* name) const {
    const pugi::xml_attribute a = node.attribute(name);
    if (!a) fail(node, std::string("has no attribute ") + name);
    const std::string_view text = trimmed(a.value());
    int value = 0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size()) {
      fail(node, std::string("attribute ") + name + " \"" + a.value() + "\" is not an integer");
    }
    return value;
  }

  // CommonRoad writes a value as <exact> or as an interval; the states this
  // reader takes must be exact.
  double exact(const pugi::xml_node& quantity) const {
    const pugi::xml_node e = quantity.child("exact");
    if (!e) fail(quantity, "needs an <exact> value (intervals are not supported here)");
    return number(e);
  }

  Point point(const pugi::xml_node& node) const {
    return {number(child(node, "x")), number(child(node, "y"))};
  }

  std::string where(const pugi::xml_node& node) const {
    return name_ + ":" + std::to_string(line_of(node)) + ": " + path_of(node);
  }

 private:
  static std::string_view trimmed(std::string_view s) {
    const auto first = s.find_first_not_of(" \t\r\n");
    if (first == std::string_view::npos) return {};
    return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
  }

  int line_of(const pugi::xml_node& node) const {
    const auto offset = static_cast<std::size_t>(std::max<std::ptrdiff_t>(node.offset_debug(), 0));
    const auto end = text_.begin() + static_cast<std::ptrdiff_t>(std::min(offset, text_.size()));
    return 1 + static_cast<int>(std::count(text_.begin(), end, '\n'));
  }

  // <commonRoad>/<dynamicObstacle id="12">/<shape>: the ids say which one.
  static std::string path_of(const pugi::xml_node& node) {
    std::string path;
    for (pugi::xml_node n = node; n && n.type() == pugi::node_element; n = n.parent()) {
      std::string step = std::string("<") + n.name();
      if (const pugi::xml_attribute id = n.attribute("id")) step.append(" id=").append(id.value());
      step += '>';
      if (!path.empty()) step.append("/").append(path);
      path = std::move(step);
    }
    return path;
  }

  const std::string& text_;
  std::string name_;
};

std::vector<Point> bound(const Reader& r, const pugi::xml_node& lanelet, const char* name) {
  const pugi::xml_node b = r.child(lanelet, name);
  std::vector<Point> points;
  for (const pugi::xml_node p : b.children("point")) points.push_back(r.point(p));
  if (points.size() < 2) r.fail(b, "needs at least two points");
  return points;
}

std::optional<int> same_direction_neighbour(const Reader& r, const pugi::xml_node& lanelet,
                                            const char* name) {
  const pugi::xml_node n = lanelet.child(name);
  if (!n) return std::nullopt;
  const std::string_view direction = n.attribute("drivingDir").value();
  if (direction != "same" && direction != "opposite") {
    r.fail(n, "drivingDir must be \"same\" or \"opposite\"");
  }
  if (direction == "opposite") return std::nullopt;
  return r.integer_attribute(n, "ref");
}

Lanelet read_lanelet(const Reader& r, const pugi::xml_node& node) {
  Lanelet l;
  l.id = r.integer_attribute(node, "id");
  l.left = bound(r, node, "leftBound");
  l.right = bound(r, node, "rightBound");
  if (l.left.size() != l.right.size()) {
    r.fail(node, std::string("leftBound has ") + std::to_string(l.left.size()) +
                     " points, rightBound " + std::to_string(l.right.size()) +
                     " (they must pair up)");
  }
  l.adjacent_left = same_direction_neighbour(r, node, "adjacentLeft");
  l.adjacent_right = same_direction_neighbour(r, node, "adjacentRight");
  for (const pugi::xml_node p : node.children("predecessor"))
    l.predecessors.push_back(r.integer_attribute(p, "ref"));
  for (const pugi::xml_node s : node.children("successor"))
    l.successors.push_back(r.integer_attribute(s, "ref"));
  return l;
}

State read_state(const Reader& r, const pugi::xml_node& node) {
  State s;
  const pugi::xml_node position = r.child(node, "position");
  const pugi::xml_node point = position.child("point");
  if (!point) r.fail(position, "must be a <point> (a shape or lanelet is not supported here)");
  s.position = r.point(point);
  s.orientation = r.exact(r.child(node, "orientation"));
  s.velocity = r.exact(r.child(node, "velocity"));
  if (const pugi::xml_node a = node.child("acceleration")) s.acceleration = r.exact(a);
  const pugi::xml_node time = r.child(node, "time");
  const double t = r.exact(time);
  if (t != std::floor(t) || t < 0.0 || t > 1e9)
    r.fail(time, "must be a time step (an integer >= 0)");
  s.time_step = static_cast<int>(t);
  return s;
}

Obstacle read_obstacle(const Reader& r, const pugi::xml_node& node) {
  Obstacle o;
  o.id = r.integer_attribute(node, "id");
  o.type = r.child(node, "type").child_value();
  const pugi::xml_node shape = r.child(node, "shape");
  const pugi::xml_node rectangle = shape.child("rectangle");
  if (!rectangle) r.fail(shape, "must be a <rectangle> (other shapes are not supported)");
  o.length = r.number(r.child(rectangle, "length"));
  o.width = r.number(r.child(rectangle, "width"));
  if (o.length <= 0.0 || o.width <= 0.0) r.fail(rectangle, "length and width must be positive");
  if (const pugi::xml_node occupancy = node.child("occupancySet")) {
    r.fail(occupancy, "a prediction as an occupancy set is not supported (a <trajectory> is)");
  }
  o.states.push_back(read_state(r, r.child(node, "initialState")));
  if (const pugi::xml_node trajectory = node.child("trajectory")) {
    for (const pugi::xml_node state : trajectory.children("state")) {
      o.states.push_back(read_state(r, state));
      if (o.states.back().time_step != o.states[o.states.size() - 2].time_step + 1) {
        r.fail(state, std::string("time step ") + std::to_string(o.states.back().time_step) +
                          " does not follow " +
                          std::to_string(o.states[o.states.size() - 2].time_step));
      }
    }
  }
  return o;
}

PlanningProblem read_planning_problem(const Reader& r, const pugi::xml_node& node) {
  return {r.integer_attribute(node, "id"), read_state(r, r.child(node, "initialState"))};
}

// Every lanelet a lanelet names must be in the file, and ids unique.
void check_references(const Reader& r, const pugi::xml_node& root, const Recording& rec) {
  std::set<int> ids;
  for (const pugi::xml_node node : root.children("lanelet")) {
    if (!ids.insert(r.integer_attribute(node, "id")).second) r.fail(node, "duplicate lanelet id");
  }
  for (const pugi::xml_node node : root.children("lanelet")) {
    for (const pugi::xml_node ref : node.children()) {
      if (!ref.attribute("ref")) continue;
      if (!ids.contains(r.integer_attribute(ref, "ref"))) {
        r.fail(ref, std::string("names lanelet ") + ref.attribute("ref").value() +
                        ", which the file does not have");
      }
    }
  }
  std::set<int> obstacles;
  for (const Obstacle& o : rec.obstacles) {
    if (!obstacles.insert(o.id).second) {
      throw InputError(r.where(root),
                       std::string("two dynamic obstacles have id ") + std::to_string(o.id));
    }
  }
}

}  // namespace

Recording recording_from_text(const std::string& xml, const std::string& name) {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(xml.data(), xml.size());
  Reader r(xml, name);
  if (!parsed) {
    const auto end = xml.begin() + std::clamp<std::ptrdiff_t>(
                                       parsed.offset, 0, static_cast<std::ptrdiff_t>(xml.size()));
    const int line = 1 + static_cast<int>(std::count(xml.begin(), end, '\n'));
    throw InputError(name + ":" + std::to_string(line),
                     std::string("not well-formed XML: ") + parsed.description());
  }
  const pugi::xml_node root = doc.child("commonRoad");
  if (!root) throw InputError(name, "has no <commonRoad> root element: not a CommonRoad file");
  const std::string_view version = root.attribute("commonRoadVersion").value();
  if (version != "2020a") {
    r.fail(root,
           std::string("commonRoadVersion \"").append(version) + "\" is not supported (2020a is)");
  }
  Recording rec;
  rec.benchmark_id = root.attribute("benchmarkID").value();
  const pugi::xml_attribute dt = root.attribute("timeStepSize");
  if (!dt) r.fail(root, "has no timeStepSize");
  rec.time_step_size = dt.as_double(-1.0);
  if (!(rec.time_step_size > 0.0) || !std::isfinite(rec.time_step_size)) {
    r.fail(root, "timeStepSize must be a positive number");
  }
  for (const pugi::xml_node node : root.children("lanelet"))
    rec.lanelets.push_back(read_lanelet(r, node));
  for (const pugi::xml_node node : root.children("dynamicObstacle"))
    rec.obstacles.push_back(read_obstacle(r, node));
  for (const pugi::xml_node node : root.children("planningProblem"))
    rec.planning_problems.push_back(read_planning_problem(r, node));
  check_references(r, root, rec);
  return rec;
}

Recording read_recording(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  return recording_from_text(text.str(), path);
}

}  // namespace lanechange::commonroad
