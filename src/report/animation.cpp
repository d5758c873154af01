// Animated SVG of a trajectory (plot.hpp). The scene is drawn in metres with
// the y axis up; the view box moves with the ego, so a 100 m manoeuvre stays
// readable at the size of a screen.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>

#include "common/json_fields.hpp"
#include "lanechange/error.hpp"
#include "lanechange/plot.hpp"

namespace lanechange {

namespace {

struct Colors {
  const char* fill;
  const char* name;
};
// The same colours as the PNG plots, so the two read alike.
constexpr Colors kEgo{"#d62728", "ego"};
constexpr std::array<Colors, 3> kRoleCars{
    {{"#1f77b4", "leader"}, {"#2ca02c", "follower"}, {"#9467bd", "target"}}};
constexpr const char* kOtherFill = "#8c8c8c";

const char* fill_of(const std::string& id) {
  for (const Colors& role : kRoleCars) {
    if (id == role.name) return role.fill;
  }
  return kOtherFill;
}

// The cars around the gap an expert plan took get a heavier outline.
bool frames_gap(const Trajectory& tr, const std::string& id) {
  const auto gap = tr.details.find("gap");
  if (gap == tr.details.end() || !gap->is_object()) return false;
  return std::any_of(gap->begin(), gap->end(),
                     [&id](const nlohmann::json& car) { return car.is_string() && car == id; });
}

std::string num(double v) {
  std::ostringstream out;
  out.precision(4);
  out << std::fixed << v;
  std::string text = out.str();
  while (text.back() == '0') text.pop_back();
  if (text.back() == '.') text.pop_back();
  return text == "-0" ? "0" : text;
}

void check(const Trajectory& tr, const AnimationOptions& o) {
  if (tr.nodes() < 2) throw InputError("trajectory", "needs at least two nodes to animate");
  if (tr.ego.size() != tr.t.size()) throw InputError("ego", "needs one state per node");
  if (!(tr.lane_width > 0)) throw InputError("lane_width", "must be positive");
  if (tr.cars.size() != tr.others.cars.size()) {
    throw InputError("others", "needs the id, lane and body of every track");
  }
  for (const auto& car : tr.others.cars) {
    if (car.x.size() < tr.t.size()) throw InputError("others", "needs one position per node");
  }
  if (!(o.view_length > 0) || !(o.speedup > 0) || o.width_px < 100) {
    throw InputError("animation", "view_length and speedup must be positive, width_px >= 100");
  }
  if (!(o.vehicle.length > 0) || !(o.vehicle.width > 0)) {
    throw InputError("vehicle", "length and width must be positive");
  }
}

// The semicolon-separated values of an animation, one per node.
template <class Value>
std::string values(int nodes, Value value) {
  std::string out;
  for (int k = 0; k < nodes; ++k) {
    if (k > 0) out += ';';
    out += value(k);
  }
  return out;
}

std::string animate_transform(const std::string& type, const std::string& vals,
                              const std::string& dur) {
  return "<animateTransform attributeName=\"transform\" type=\"" + type + "\" values=\"" + vals +
         "\" dur=\"" + dur + "\" calcMode=\"linear\" repeatCount=\"indefinite\"/>";
}

// A car that enters, leaves or changes lanes is shown only while it is on
// its track's lane.
std::string presence(const CarTrack& car, int nodes, const std::string& dur) {
  if (car.present.empty()) return "";
  return "<animate attributeName=\"visibility\" values=\"" +
         values(nodes,
                [&](int k) {
                  return car.present_at(static_cast<std::size_t>(k)) ? "visible" : "hidden";
                }) +
         "\" dur=\"" + dur + "\" calcMode=\"discrete\" repeatCount=\"indefinite\"/>";
}

std::string car_body(const VehicleSize& v, const char* fill, const std::string& name,
                     double stroke = 0.08) {
  std::ostringstream out;
  out << "<rect x=\"" << num(-v.length / 2) << "\" y=\"" << num(-v.width / 2) << "\" width=\""
      << num(v.length) << "\" height=\"" << num(v.width) << "\" rx=\"0.3\" fill=\"" << fill
      << "\" stroke=\"#000\" stroke-width=\"" << num(stroke) << "\"><title>" << name
      << "</title></rect>";
  return out.str();
}

void draw_road(std::ostream& out, const Trajectory& tr, double x_lo, double x_hi) {
  const double w = tr.lane_width;
  out << "<rect x=\"" << num(x_lo) << "\" y=\"" << num(-w / 2) << "\" width=\"" << num(x_hi - x_lo)
      << "\" height=\"" << num(2 * w) << "\" fill=\"#e8e8e8\"/>\n";
  for (double y : {-w / 2, 1.5 * w}) {
    out << "<line x1=\"" << num(x_lo) << "\" y1=\"" << num(y) << "\" x2=\"" << num(x_hi)
        << "\" y2=\"" << num(y) << "\" stroke=\"#333\" stroke-width=\"0.15\"/>\n";
  }
  out << "<line x1=\"" << num(x_lo) << "\" y1=\"" << num(w / 2) << "\" x2=\"" << num(x_hi)
      << "\" y2=\"" << num(w / 2)
      << "\" stroke=\"#fff\" stroke-width=\"0.15\" stroke-dasharray=\"3 3\"/>\n";
}

void draw_path_and_events(std::ostream& out, const Trajectory& tr) {
  out << "<polyline fill=\"none\" stroke=\"" << kEgo.fill
      << "\" stroke-width=\"0.12\" stroke-opacity=\"0.6\" points=\"";
  for (const auto& s : tr.ego) out << num(s.x) << ',' << num(s.y) << ' ';
  out << "\"/>\n";
  if (!tr.details.contains("events")) return;
  for (const auto& [kind, color] : {std::pair{"took_over", "#000"}, {"fallback", "#7f7f7f"}}) {
    if (!tr.details["events"].contains(kind)) continue;
    for (const auto& event : tr.details["events"][kind]) {
      if (!event.is_object() || !event.contains("step")) continue;
      const auto k = event["step"].get<std::size_t>();
      if (k >= tr.ego.size()) continue;
      out << "<circle cx=\"" << num(tr.ego[k].x) << "\" cy=\"" << num(tr.ego[k].y)
          << "\" r=\"0.25\" fill=\"" << color << "\"><title>" << kind << "</title></circle>\n";
    }
  }
}

}  // namespace

std::string trajectory_animation_svg(const Trajectory& tr, const AnimationOptions& o) {
  check(tr, o);
  const int n = tr.nodes();
  const double duration = (tr.t.back() - tr.t.front()) / o.speedup;
  const std::string dur = num(duration) + "s";
  const double w = tr.lane_width;
  const double view_height = o.view_length * 0.22;
  const int height_px = static_cast<int>(std::lround(o.width_px * view_height / o.view_length));
  double x_lo = tr.ego.front().x;
  double x_hi = x_lo;
  for (const auto& s : tr.ego) x_hi = std::max(x_hi, s.x);
  for (const auto& car : tr.others.cars) {
    for (int k = 0; k < n; ++k) {
      x_lo = std::min(x_lo, car.x[static_cast<std::size_t>(k)]);
      x_hi = std::max(x_hi, car.x[static_cast<std::size_t>(k)]);
    }
  }
  x_lo -= o.view_length;
  x_hi += o.view_length;
  // The camera keeps the ego a third of the way into the view.
  auto camera = [&](int k) { return tr.ego[static_cast<std::size_t>(k)].x - o.view_length / 3; };
  // The view is centred on the lane line, in metres with y up; a right-hand
  // change, held as its mirror image, is drawn unflipped, so its target lane
  // lies below.
  const bool flip = tr.target_side == Side::Left;
  const double y_top = flip ? -(w * 0.5 + view_height / 2) : w * 0.5 - view_height / 2;
  std::ostringstream out;
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << o.width_px << "\" height=\""
      << height_px << "\" viewBox=\"" << num(camera(0)) << ' ' << num(y_top) << ' '
      << num(o.view_length) << ' ' << num(view_height) << "\">\n";
  out << "<animate attributeName=\"viewBox\" values=\""
      << values(n,
                [&](int k) {
                  return num(camera(k)) + " " + num(y_top) + " " + num(o.view_length) + " " +
                         num(view_height);
                })
      << "\" dur=\"" << dur << "\" calcMode=\"linear\" repeatCount=\"indefinite\"/>\n";
  out << "<g transform=\"scale(1," << (flip ? "-1" : "1") << ")\">\n";
  draw_road(out, tr, x_lo, x_hi);
  draw_path_and_events(out, tr);
  for (std::size_t c = 0; c < tr.cars.size(); ++c) {
    const auto& car = tr.others.cars[c];
    const TrackedCar& who = tr.cars[c];
    const double lane_y = who.lane == Lane::Ego ? 0.0 : w;
    out << "<g>"
        << animate_transform("translate",
                             values(n,
                                    [&](int k) {
                                      return num(car.x[static_cast<std::size_t>(k)]) + "," +
                                             num(lane_y);
                                    }),
                             dur)
        << presence(car, n, dur)
        << car_body(who.size, fill_of(who.id), who.id, frames_gap(tr, who.id) ? 0.3 : 0.08)
        << "</g>\n";
  }
  out << "<g>"
      << animate_transform("translate",
                           values(n,
                                  [&](int k) {
                                    const auto& s = tr.ego[static_cast<std::size_t>(k)];
                                    return num(s.x) + "," + num(s.y);
                                  }),
                           dur)
      << "<g>"
      << animate_transform("rotate",
                           values(n,
                                  [&](int k) {
                                    return num(tr.ego[static_cast<std::size_t>(k)].theta * 180.0 /
                                               std::numbers::pi);
                                  }),
                           dur)
      << car_body(o.vehicle, kEgo.fill, kEgo.name) << "</g></g>\n</g>\n";
  // The caption and a clock bar ride with the camera.
  std::string title = "planner: " + (tr.planner.empty() ? std::string("?") : tr.planner);
  title += "   label: ";
  title += to_string(tr.label);
  if (tr.collision) title += "   (collision)";
  if (!tr.reason.empty()) title += "   " + tr.reason;
  out << "<g>"
      << animate_transform("translate", values(n, [&](int k) { return num(camera(k)) + ",0"; }),
                           dur)
      << "<text x=\"1\" y=\"" << num(y_top + view_height * 0.09) << "\" font-size=\""
      << num(view_height * 0.06) << "\" font-family=\"sans-serif\">" << xml_escaped(title)
      << " (t = " << num(tr.t.front()) << " to " << num(tr.t.back()) << " s)</text>"
      << "<rect x=\"1\" y=\"" << num(y_top + view_height * 0.92) << "\" height=\""
      << num(view_height * 0.03) << "\" width=\"0\" fill=\"#555\"><animate attributeName=\"width\" "
      << "values=\"0;" << num(o.view_length - 2) << "\" dur=\"" << dur
      << "\" repeatCount=\"indefinite\"/></rect></g>\n";
  out << "</svg>\n";
  return out.str();
}

std::string xml_escaped(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
    }
  }
  return out;
}

void animate_trajectory(const Trajectory& trajectory, const std::string& svg_path,
                        const AnimationOptions& options) {
  detail::write_file_atomically(svg_path, trajectory_animation_svg(trajectory, options));
}

}  // namespace lanechange
