#include "sumo/interactive.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <pugixml.hpp>
#include <sstream>

#include "lanechange/error.hpp"
#include "lanechange/sumo/cosim.hpp"

namespace lanechange::sumo::detail {

namespace {

namespace fs = std::filesystem;

std::string required_file(const fs::path& folder, const std::string& name, const char* suffix) {
  const fs::path file = folder / (name + suffix);
  if (!fs::is_regular_file(file)) {
    throw InputError(folder.string(),
                     "has no " + name + suffix +
                         " (a CommonRoad interactive "
                         "scenario holds NAME.cr.xml, NAME.net.xml and NAME.vehicles.rou.xml)");
  }
  return file.string();
}

// "20 20 16" -> "20 16": the recordings' routes may name an edge twice in a
// row where a car stayed on it, which SUMO refuses as a missing connection.
std::string without_repeats(const std::string& edges) {
  std::istringstream in(edges);
  std::string out;
  std::string edge;
  std::string last;
  while (in >> edge) {
    if (edge == last) continue;
    if (!out.empty()) out += ' ';
    out += edge;
    last = edge;
  }
  return out;
}

std::string cleaned_routes(const std::string& path, const std::string& work_dir) {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_file(path.c_str());
  if (!parsed) throw InputError(path, std::string("is not XML: ") + parsed.description());
  bool changed = false;
  for (const pugi::xpath_node& node : doc.select_nodes("//route[@edges]")) {
    pugi::xml_attribute edges = node.node().attribute("edges");
    const std::string clean = without_repeats(edges.value());
    if (clean == edges.value()) continue;
    edges.set_value(clean.c_str());
    changed = true;
  }
  if (!changed) return path;
  const fs::path out = fs::path(work_dir) / fs::path(path).filename();
  if (!doc.save_file(out.c_str())) throw std::runtime_error("cannot write " + out.string());
  return out.string();
}

// NAME of a folder NAME/ (with or without its trailing slash).
std::string scenario_name(const fs::path& dir) {
  std::string name = dir.filename().string();
  return name.empty() ? dir.parent_path().filename().string() : name;
}

// A vType attribute: SUMO's default where absent.
double positive_attribute(const pugi::xml_node& type, const char* name, double fallback,
                          const std::string& file) {
  const pugi::xml_attribute a = type.attribute(name);
  if (!a) return fallback;
  char* end = nullptr;
  const double value = std::strtod(a.value(), &end);
  if (end == a.value() || *end != '\0' || !(value > 0.0) || !std::isfinite(value)) {
    throw InputError(
        file, std::string("vType ") + name + " \"" + a.value() + "\" is not a positive number");
  }
  return value;
}

}  // namespace

InteractiveScenario read_interactive(const std::string& folder, const std::string& work_dir) {
  const fs::path dir(folder);
  if (!fs::is_directory(dir)) throw InputError(folder, "is not a folder");
  InteractiveScenario s;
  s.name = scenario_name(dir);
  const commonroad::Recording cr =
      commonroad::read_recording(required_file(dir, s.name, ".cr.xml"));
  if (cr.planning_problems.empty()) {
    throw InputError(folder, s.name + ".cr.xml has no planning problem (the ego's start)");
  }
  s.start = cr.planning_problems.front().initial;
  s.sumo_files = {"-n", required_file(dir, s.name, ".net.xml"), "-r",
                  cleaned_routes(required_file(dir, s.name, ".vehicles.rou.xml"), work_dir)};
  const fs::path additional = dir / (s.name + ".add.xml");
  if (fs::is_regular_file(additional)) {
    s.sumo_files.push_back("-a");
    s.sumo_files.push_back(additional.string());
  }
  return s;
}

}  // namespace lanechange::sumo::detail

namespace lanechange::sumo {

SumoCarModel commonroad_car_model(const std::string& folder) {
  const std::filesystem::path dir(folder);
  const std::string name = detail::scenario_name(dir);
  SumoCarModel model;
  for (const char* suffix : {".add.xml", ".vehicles.rou.xml"}) {
    const std::filesystem::path file = dir / (name + suffix);
    if (!std::filesystem::is_regular_file(file)) continue;
    pugi::xml_document doc;
    const pugi::xml_parse_result parsed = doc.load_file(file.c_str());
    if (!parsed) {
      throw InputError(file.string(), std::string("is not XML: ") + parsed.description());
    }
    const pugi::xml_node type = doc.select_node("//vType").node();
    if (!type) continue;
    model.decel = detail::positive_attribute(type, "decel", model.decel, file.string());
    model.min_gap = detail::positive_attribute(type, "minGap", model.min_gap, file.string());
    model.tau = detail::positive_attribute(type, "tau", model.tau, file.string());
    break;
  }
  return model;
}

}  // namespace lanechange::sumo
