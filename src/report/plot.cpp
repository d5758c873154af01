#include "lanechange/plot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "lanechange/error.hpp"

namespace lanechange {
namespace {

// ---------------------------------------------------------------- geometry

struct Point {
  double x = 0.0;
  double y = 0.0;
};

struct Pose {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

/// Everything drawn at one instant; the others keep their lanes.
struct Snapshot {
  double time = 0.0;
  Pose ego;
  std::vector<double> car_x;  ///< Trajectory::others' order; kAbsent: not on its lane then
};

constexpr double kAbsent = std::numeric_limits<double>::quiet_NaN();

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void include(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
};

void require(bool ok, const std::string& field, const std::string& problem) {
  if (!ok) throw InputError(field, problem);
}

void require_length(std::size_t size, std::size_t nodes, const std::string& field) {
  require(size == nodes, field,
          "has " + std::to_string(size) + " entries, expected " + std::to_string(nodes));
}

void require_finite(const std::vector<double>& values, const std::string& field) {
  for (double v : values) require(std::isfinite(v), field, "must be finite");
}

void validate(const Trajectory& tr, const PlotOptions& options) {
  require(options.snapshots >= 1, "snapshots", "must be at least 1");
  require(options.width_px >= 200 && options.height_px >= 100, "size",
          "the image must be at least 200 x 100 pixels");
  require(std::isfinite(options.vehicle.length) && options.vehicle.length > 0.0 &&
              std::isfinite(options.vehicle.width) && options.vehicle.width > 0.0,
          "vehicle", "length and width must be positive");
  require(std::isfinite(tr.lane_width) && tr.lane_width > 0.0, "lane_width", "must be positive");
  const std::size_t n = tr.t.size();
  require(n >= 1, "t", "must not be empty");
  require_finite(tr.t, "t");
  for (std::size_t k = 1; k < n; ++k) require(tr.t[k] > tr.t[k - 1], "t", "must increase");
  require_length(tr.ego.size(), n, "ego");
  for (const auto& s : tr.ego) {
    require(std::isfinite(s.x) && std::isfinite(s.y) && std::isfinite(s.theta), "ego",
            "x, y and theta must be finite");
  }
  require(tr.cars.size() == tr.others.cars.size(), "others",
          "names " + std::to_string(tr.cars.size()) + " cars for " +
              std::to_string(tr.others.cars.size()) + " tracks");
  for (std::size_t c = 0; c < tr.cars.size(); ++c) {
    const std::string field = "others." + tr.cars[c].id + ".x";
    require_length(tr.others.car(c).x.size(), n, field);
    require_finite(tr.others.car(c).x, field);
    require(tr.cars[c].size.length > 0.0 && tr.cars[c].size.width > 0.0,
            "others." + tr.cars[c].id + ".length", "a car's body must be positive");
  }
}

double lerp(double a, double b, double s) { return a + (b - a) * s; }

// Interpolating between nodes lets the instants be round numbers (0, 1.25,
// ...) whatever the time step.
Snapshot snapshot_at(const Trajectory& tr, double time) {
  const auto upper = std::upper_bound(tr.t.begin(), tr.t.end(), time);
  const std::size_t hi =
      std::clamp<std::size_t>(static_cast<std::size_t>(upper - tr.t.begin()), 1, tr.t.size() - 1);
  const std::size_t lo = hi - 1;
  const double s = std::clamp((time - tr.t[lo]) / (tr.t[hi] - tr.t[lo]), 0.0, 1.0);
  const EgoState& a = tr.ego[lo];
  const EgoState& b = tr.ego[hi];
  Snapshot snap{time, {lerp(a.x, b.x, s), lerp(a.y, b.y, s), lerp(a.theta, b.theta, s)}, {}};
  for (const CarTrack& car : tr.others.cars) {
    const bool there = car.present_at(s < 0.5 ? lo : hi);
    snap.car_x.push_back(there ? lerp(car.x[lo], car.x[hi], s) : kAbsent);
  }
  return snap;
}

std::vector<Snapshot> snapshots(const Trajectory& tr, int count) {
  if (tr.t.size() == 1) {
    const EgoState& e = tr.ego.front();
    Snapshot only{tr.t.front(), {e.x, e.y, e.theta}, {}};
    for (const CarTrack& car : tr.others.cars) {
      only.car_x.push_back(car.present_at(0) ? car.x.front() : kAbsent);
    }
    return {only};
  }
  const double first = tr.t.front();
  const double span = tr.t.back() - first;
  std::vector<Snapshot> out;
  for (int i = 0; i < count; ++i) {
    const double fraction = count == 1 ? 0.0 : static_cast<double>(i) / (count - 1);
    out.push_back(snapshot_at(tr, first + span * fraction));
  }
  return out;
}

std::array<Point, 4> corners(const Pose& pose, const VehicleSize& size) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const double hl = size.length / 2.0, hw = size.width / 2.0;
  std::array<Point, 4> out;
  const std::array<std::array<double, 2>, 4> signs{{{1, 1}, {-1, 1}, {-1, -1}, {1, -1}}};
  for (std::size_t i = 0; i < 4; ++i) {
    const double along = signs[i][0] * hl, across = signs[i][1] * hw;
    out[i] = {pose.x + along * c - across * s, pose.y + along * s + across * c};
  }
  return out;
}

double lane_center(const TrackedCar& car, double lane_width) {
  return car.lane == Lane::Ego ? 0.0 : lane_width;
}

Pose car_pose(const Snapshot& snap, const Trajectory& tr, std::size_t c) {
  return {snap.car_x[c], lane_center(tr.cars[c], tr.lane_width), 0.0};
}

// ------------------------------------------------------------- formatting

std::string num(double v) {
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
  return std::string(buffer.data(), result.ptr);
}

/// Seconds for a label: "1.25", "2.5", "0", never "2.5000000000000004".
std::string seconds(double t) {
  std::array<char, 32> buffer{};
  std::snprintf(buffer.data(), buffer.size(), "%.2f", t);
  std::string text(buffer.data());
  while (text.back() == '0') text.pop_back();
  if (text.back() == '.') text.pop_back();
  return text == "-0" ? "0" : text;
}

// Single-quoted gnuplot strings have no escapes but '' for a quote, so
// nothing in a planner's reason can break out of the string.
std::string gnuplot_string(std::string_view text) {
  std::string out = "'";
  for (char ch : text) {
    if (ch == '\'') {
      out += "''";
    } else {
      out += (static_cast<unsigned char>(ch) < 0x20) ? ' ' : ch;
    }
  }
  return out + "'";
}

std::string title_of(const Trajectory& tr) {
  std::string title = "planner: " + (tr.planner.empty() ? std::string("?") : tr.planner) +
                      "    label: " + std::string(to_string(tr.label));
  if (!tr.reason.empty()) title += "    reason: " + tr.reason;
  if (tr.collision) title += "    (collision)";
  // The expert's plan names the gap it merges into by the cars around it.
  if (const auto gap = tr.details.find("gap"); gap != tr.details.end() && gap->is_object()) {
    const auto name = [&gap](const char* side) {
      const auto car = gap->find(side);
      return car != gap->end() && car->is_string() ? car->get<std::string>() : std::string("none");
    };
    title += "    gap: " + name("behind") + " - " + name("ahead");
  }
  return title;
}

// --------------------------------------------------------------- the script

struct CarStyle {
  std::string name;
  const char* color;
  /// Where the time label sits across the car, as a fraction of its width:
  /// cars that can overlap get different offsets so their labels do not.
  double label_offset = 0.0;
  double border = 1.0;  ///< thicker for the cars that frame the gap taken
};

const CarStyle& ego_style() {
  static const CarStyle style{"ego", "#1f5fbf", 0.0};
  return style;
}

// The paper's three cars keep their colours; any other car is grey.
const std::array<CarStyle, 3>& role_styles() {
  static const std::array<CarStyle, 3> styles{
      {{"leader", "#2a9d3a", -0.3}, {"follower", "#e07b00", -0.3}, {"target", "#c8202a", 0.3}}};
  return styles;
}
constexpr const char* kOtherColor = "#6e6e6e";

// The ids of the cars around the gap an expert plan took (details.gap).
std::vector<std::string> gap_cars(const Trajectory& tr) {
  std::vector<std::string> ids;
  if (const auto gap = tr.details.find("gap"); gap != tr.details.end() && gap->is_object()) {
    for (const char* side : {"behind", "ahead"}) {
      const auto car = gap->find(side);
      if (car != gap->end() && car->is_string()) ids.push_back(car->get<std::string>());
    }
  }
  return ids;
}

CarStyle style_of(const Trajectory& tr, std::size_t c) {
  const std::string& id = tr.cars[c].id;
  CarStyle style{id, kOtherColor, c % 2 == 0 ? -0.3 : 0.3};
  for (const CarStyle& role : role_styles()) {
    if (role.name == id) style = role;
  }
  const auto framing = gap_cars(tr);
  if (std::find(framing.begin(), framing.end(), id) != framing.end()) style.border = 3.0;
  return style;
}

Range x_range(const Trajectory& tr, const std::vector<Snapshot>& snaps, const VehicleSize& size) {
  Range r;
  for (const auto& s : tr.ego) r.include(s.x);
  for (const auto& snap : snaps) {
    for (const Point& p : corners(snap.ego, size)) r.include(p.x);
    for (std::size_t c = 0; c < tr.cars.size(); ++c) {
      if (std::isnan(snap.car_x[c])) continue;
      for (const Point& p : corners(car_pose(snap, tr, c), tr.cars[c].size)) r.include(p.x);
    }
  }
  const double margin = std::max(2.0, 0.03 * (r.hi - r.lo));
  return {r.lo - margin, r.hi + margin};
}

// The road is a fixed band [-w/2, 3w/2]; the plot shows half a lane more on
// either side for the car names, and grows only if the ego's body would not fit.
Range y_range(const Trajectory& tr, const VehicleSize& size) {
  const double w = tr.lane_width;
  Range r{-w, 2.0 * w};
  for (const auto& s : tr.ego) {
    r.include(s.y - size.length / 2.0);
    r.include(s.y + size.length / 2.0);
  }
  return r;
}

// A right-hand change is held as its mirror image: its axis runs the other
// way, labelled with the file's y, so the target lane is drawn below.
std::string y_axis(const Range& y, double tic, Side side) {
  if (side == Side::Left) {
    return "set yrange [" + num(y.lo) + ":" + num(y.hi) + "]\nset ytics " + num(tic) + "\n";
  }
  std::string tics;
  for (auto i = static_cast<long>(std::ceil(y.lo / tic)); static_cast<double>(i) * tic <= y.hi;
       ++i) {
    const double at = static_cast<double>(i) * tic;
    tics += (tics.empty() ? "" : ", ") + gnuplot_string(num(i == 0 ? 0.0 : -at)) + " " + num(at);
  }
  return "set yrange [" + num(y.hi) + ":" + num(y.lo) + "]\nset ytics (" + tics + ")\n";
}

void write_header(std::ostream& out, const Trajectory& tr, const std::string& png_path,
                  const PlotOptions& options, const std::vector<Snapshot>& snaps) {
  std::string instants;
  for (const auto& snap : snaps) instants += (instants.empty() ? "" : ", ") + seconds(snap.time);
  const Range x = x_range(tr, snaps, options.vehicle);
  const Range y = y_range(tr, options.vehicle);
  out << "# lanechange trajectory plot\n"
      << "set terminal pngcairo size " << options.width_px << "," << options.height_px
      << " noenhanced font 'Sans,10'\n"
      << "set output " << gnuplot_string(png_path) << "\n"
      << "set title " << gnuplot_string(title_of(tr)) << " font 'Sans,12'\n"
      << "set xlabel "
      << gnuplot_string("x [m]    (cars at t = " + instants + " s; darker = later)") << "\n"
      << "set ylabel 'y [m]'\n"
      << "set xrange [" << num(x.lo) << ":" << num(x.hi) << "]\n"
      << y_axis(y, tr.lane_width / 2.0, tr.target_side)
      << "set key outside bottom center horizontal\n"
      << "set tics out nomirror\n";
}

void write_lane_line(std::ostream& out, double y, bool dashed) {
  out << "set arrow from graph 0, first " << num(y) << " to graph 1, first " << num(y)
      << " nohead back lc rgb '#404040' lw " << (dashed ? "1.5 dt (12,8)" : "2.5") << "\n";
}

void write_road(std::ostream& out, double lane_width, int& object) {
  const double w = lane_width;
  out << "# road: ego lane centred at y = 0, target lane at y = w = " << num(w) << "\n"
      << "set object " << object++ << " rect from graph 0, first " << num(-w / 2.0)
      << " to graph 1, first " << num(1.5 * w)
      << " behind fc rgb '#e4e4e4' fs solid 1.0 noborder\n";
  write_lane_line(out, -w / 2.0, false);
  write_lane_line(out, w / 2.0, true);
  write_lane_line(out, 1.5 * w, false);
}

void write_car(std::ostream& out, const Pose& pose, const VehicleSize& size, const CarStyle& style,
               double opacity, int& object) {
  const auto c = corners(pose, size);
  out << "set object " << object++ << " polygon from " << num(c[0].x) << "," << num(c[0].y);
  for (std::size_t i = 1; i <= c.size(); ++i) {
    out << " to " << num(c[i % c.size()].x) << "," << num(c[i % c.size()].y);
  }
  out << " back fc rgb '" << style.color << "' fs transparent solid " << num(opacity)
      << " border lc rgb '" << (style.border > 1.0 ? "#000000" : style.color) << "' lw "
      << num(style.border) << "\n";
}

void write_time_label(std::ostream& out, const Pose& pose, double offset, double time) {
  out << "set label " << gnuplot_string(seconds(time) + " s") << " at " << num(pose.x) << ","
      << num(pose.y + offset) << " center front font 'Sans,7'\n";
}

// Names go outside the road, next to each car's first snapshot: below the
// road for a car starting in the ego lane, above it for the target lane.
void write_name(std::ostream& out, double x, double y, double lane_width, const CarStyle& style) {
  const bool lower = y < lane_width / 2.0;
  const double label_y = lower ? -0.75 * lane_width : 1.75 * lane_width;
  out << "set label " << gnuplot_string(style.name) << " at " << num(x) << "," << num(label_y)
      << " center front tc rgb '" << style.color << "' font 'Sans,10'\n";
}

void write_cars(std::ostream& out, const Trajectory& tr, const std::vector<Snapshot>& snaps,
                const VehicleSize& size, int& object) {
  const double lane_width = tr.lane_width;
  for (std::size_t i = 0; i < snaps.size(); ++i) {
    const Snapshot& snap = snaps[i];
    // Later instants are more opaque, so the order is visible where cars overlap.
    const double progress =
        snaps.size() == 1 ? 1.0 : static_cast<double>(i) / static_cast<double>(snaps.size() - 1);
    const double opacity = 0.2 + 0.55 * progress;
    out << "# t = " << seconds(snap.time) << " s\n";
    write_car(out, snap.ego, size, ego_style(), opacity, object);
    write_time_label(out, snap.ego, 0.0, snap.time);
    for (std::size_t c = 0; c < tr.cars.size(); ++c) {
      if (std::isnan(snap.car_x[c])) continue;
      const Pose pose = car_pose(snap, tr, c);
      const CarStyle style = style_of(tr, c);
      write_car(out, pose, tr.cars[c].size, style, opacity, object);
      write_time_label(out, pose, style.label_offset * tr.cars[c].size.width, snap.time);
    }
  }
  const Snapshot& first = snaps.front();
  write_name(out, first.ego.x, first.ego.y, lane_width, ego_style());
  for (std::size_t c = 0; c < tr.cars.size(); ++c) {
    // Named where it is first seen: traffic may enter after the start.
    const auto seen = std::find_if(snaps.begin(), snaps.end(), [c](const Snapshot& snap) {
      return !std::isnan(snap.car_x[c]);
    });
    if (seen == snaps.end()) continue;
    write_name(out, seen->car_x[c], lane_center(tr.cars[c], lane_width), lane_width,
               style_of(tr, c));
  }
}

// A rollout (docs/closed_loop.md) lists the steps where the planner's own
// method did not act; they are marked on the path. Returns the marks drawn.
int write_event_marks(std::ostream& out, const Trajectory& tr, const char* kind) {
  const auto& details = tr.details;
  if (!details.contains("events") || !details["events"].contains(kind)) return 0;
  out << "$" << kind << " << EOD\n";
  int marks = 0;
  for (const auto& event : details["events"][kind]) {
    if (!event.is_object() || !event.contains("step")) continue;
    const auto k = event["step"].get<std::size_t>();
    if (k >= tr.ego.size()) continue;
    out << num(tr.ego[k].x) << " " << num(tr.ego[k].y) << "\n";
    ++marks;
  }
  out << "EOD\n";
  return marks;
}

void write_path_and_plot(std::ostream& out, const Trajectory& tr) {
  out << "$ego_path << EOD\n";
  for (const auto& s : tr.ego) out << num(s.x) << " " << num(s.y) << "\n";
  out << "EOD\n";
  const int took_over = write_event_marks(out, tr, "took_over");
  const int fell_back = write_event_marks(out, tr, "fallback");
  // keyentry gives the legend a swatch per car without plotting anything.
  out << "plot $ego_path using 1:2 with lines lw 2 lc rgb '" << ego_style().color
      << "' title 'ego path'";
  if (took_over > 0) {
    out << ", \\\n     $took_over using 1:2 with points pt 7 ps 0.8 lc rgb '#000000' "
           "title 'expert took over'";
  }
  if (fell_back > 0) {
    out << ", \\\n     $fallback using 1:2 with points pt 6 ps 0.8 lc rgb '#7f7f7f' "
           "title 'fallback'";
  }
  const auto swatch = [&out](const CarStyle& style) {
    out << ", \\\n     keyentry with boxes fs solid 0.6 fc rgb '" << style.color << "' title "
        << gnuplot_string(style.name);
  };
  swatch(ego_style());
  bool others = false;
  for (const CarStyle& role : role_styles()) {
    const bool present = std::any_of(tr.cars.begin(), tr.cars.end(),
                                     [&role](const TrackedCar& c) { return c.id == role.name; });
    if (present) swatch(role);
  }
  for (std::size_t c = 0; c < tr.cars.size(); ++c) {
    others = others || style_of(tr, c).color == kOtherColor;
  }
  if (others) swatch({"other cars", kOtherColor});
  out << "\nunset output\n";
}

// ---------------------------------------------------------------- running

/// A temporary file that is removed unless released.
class TempFile {
 public:
  /// Creates a fresh, empty file named `prefix` + a unique suffix, or throws
  /// naming `purpose`. Not mkstemp: its mode 0600 would survive the rename,
  /// and a PNG should get the usual permissions of the user's umask.
  TempFile(const std::string& prefix, mode_t mode, const std::string& purpose) {
    static std::atomic<unsigned> counter{0};
    for (int attempt = 0; attempt < 100; ++attempt) {
      std::string name = prefix + std::to_string(::getpid()) + "." + std::to_string(counter++);
      const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
      if (fd >= 0) {
        ::close(fd);
        path_ = std::move(name);
        return;
      }
      const int error = errno;
      if (error != EEXIST) {
        throw std::runtime_error("cannot write " + purpose + ": " + std::strerror(error));
      }
    }
    throw std::runtime_error("cannot write " + purpose + ": no free temporary name");
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    if (!path_.empty()) ::unlink(path_.c_str());
  }
  [[nodiscard]] const std::string& path() const { return path_; }
  void release() { path_.clear(); }

 private:
  std::string path_;
};

bool is_executable_file(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode) &&
         ::access(path.c_str(), X_OK) == 0;
}

std::string search_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path != nullptr ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    std::string candidate = (dir.empty() ? std::string(".") : dir) + "/" + name;
    if (is_executable_file(candidate)) return candidate;
  }
  return {};
}

std::string find_gnuplot() {
  if (const char* chosen = std::getenv("LANECHANGE_GNUPLOT"); chosen != nullptr && *chosen) {
    if (is_executable_file(chosen)) return chosen;
    throw std::runtime_error(std::string("gnuplot not found: LANECHANGE_GNUPLOT=") + chosen +
                             " is not an executable file");
  }
  if (std::string found = search_path("gnuplot"); !found.empty()) return found;
#ifdef LANECHANGE_GNUPLOT_FALLBACK
  if (is_executable_file(LANECHANGE_GNUPLOT_FALLBACK)) return LANECHANGE_GNUPLOT_FALLBACK;
#endif
  throw std::runtime_error(
      "gnuplot not found on PATH (install gnuplot-nox, or set LANECHANGE_GNUPLOT)");
}

std::string read_log(const std::string& path) {
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  constexpr std::size_t kMaxChars = 2000;
  if (text.size() > kMaxChars) text = text.substr(0, kMaxChars) + "...";
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  return text;
}

/// Runs `gnuplot script` without a shell (no quoting of paths), its output
/// into `log`; returns the wait status.
int run_gnuplot(const std::string& exe, const std::string& script, const std::string& log) {
  posix_spawn_file_actions_t actions;
  ::posix_spawn_file_actions_init(&actions);
  ::posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  ::posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0600);
  ::posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::string arg0 = exe, arg1 = script;
  std::array<char*, 3> argv{arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  const int rc = ::posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  ::posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot run gnuplot " + exe + ": " + std::strerror(rc));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    const int error = errno;
    if (error != EINTR) {
      throw std::runtime_error(std::string("waiting for gnuplot: ") + std::strerror(error));
    }
  }
  return status;
}

void check_status(int status, const std::string& exe, const std::string& log) {
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  const std::string how = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                            : "signal " + std::to_string(WTERMSIG(status));
  const std::string output = read_log(log);
  throw std::runtime_error("gnuplot (" + exe + ") failed with " + how +
                           (output.empty() ? "" : ": " + output));
}

void check_png(const std::string& path) {
  static const std::string kSignature("\x89PNG\r\n\x1a\n", 8);
  std::ifstream in(path, std::ios::binary);
  std::string head(kSignature.size(), '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  if (!in || head != kSignature) {
    throw std::runtime_error("gnuplot did not write a PNG to " + path);
  }
}

}  // namespace

std::string trajectory_plot_script(const Trajectory& trajectory, const std::string& png_path,
                                   const PlotOptions& options) {
  validate(trajectory, options);
  // gnuplot_string blanks control characters, which would silently rename the file.
  require(std::none_of(png_path.begin(), png_path.end(),
                       [](char ch) { return static_cast<unsigned char>(ch) < 0x20; }),
          "png_path", "must not contain control characters");
  const std::vector<Snapshot> snaps = snapshots(trajectory, options.snapshots);
  std::ostringstream out;
  write_header(out, trajectory, png_path, options, snaps);
  int object = 1;
  write_road(out, trajectory.lane_width, object);
  write_cars(out, trajectory, snaps, options.vehicle, object);
  write_path_and_plot(out, trajectory);
  return out.str();
}

void plot_trajectory(const Trajectory& trajectory, const std::string& png_path,
                     const PlotOptions& options) {
  render_png(
      [&](const std::string& image) { return trajectory_plot_script(trajectory, image, options); },
      png_path);
}

void render_png(const std::function<std::string(const std::string&)>& script_for,
                const std::string& png_path) {
  require(!png_path.empty(), "png_path", "must not be empty");
  // The PNG is drawn next to its destination, so the final rename is atomic.
  TempFile image(png_path + ".tmp.", 0666, png_path);
  const std::string script_text = script_for(image.path());
  const std::string gnuplot = find_gnuplot();
  const std::string temp_dir = std::filesystem::temp_directory_path().string();
  TempFile script(temp_dir + "/lanechange_plot_", 0600, "a gnuplot script in " + temp_dir);
  TempFile log(temp_dir + "/lanechange_plot_log_", 0600, "a gnuplot log in " + temp_dir);
  {
    std::ofstream file(script.path(), std::ios::binary | std::ios::trunc);
    file << script_text;
    file.close();
    if (!file) throw std::runtime_error("cannot write gnuplot script " + script.path());
  }
  check_status(run_gnuplot(gnuplot, script.path(), log.path()), gnuplot, log.path());
  check_png(image.path());
  std::filesystem::rename(image.path(), png_path);
  image.release();
}

std::string gnuplot_quoted(std::string_view text) { return gnuplot_string(text); }

}  // namespace lanechange
