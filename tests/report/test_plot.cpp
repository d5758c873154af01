#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "../foundation/test_helpers.hpp"
#include "lanechange/error.hpp"
#include "lanechange/plot.hpp"

namespace lanechange {
namespace {

namespace fs = std::filesystem;

constexpr double kLaneWidth = 3.5;

/// 51 nodes over 5 s: the ego moves over by a quintic (zero lateral speed and
/// acceleration at both ends), the others keep their lanes at constant speed.
Trajectory lane_change(int nodes = 51) {
  Trajectory tr;
  tr.planner = "miqp";
  tr.label = Label::WellPosed;
  tr.lane_width = kLaneWidth;
  tr.dt = nodes > 1 ? 5.0 / (nodes - 1) : 0.1;
  tr.others.dt = tr.dt;
  tr.others.cars.resize(3);
  tr.cars = {
      {"leader", Lane::Ego, {}}, {"follower", Lane::Target, {}}, {"target", Lane::Target, {}}};
  const double speed = 8.0;
  for (int k = 0; k < nodes; ++k) {
    const double t = k * tr.dt, s = t / 5.0;
    const double y = kLaneWidth * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
    const double y_rate = kLaneWidth * 30.0 * s * s * (1.0 - s) * (1.0 - s) / 5.0;
    tr.t.push_back(t);
    tr.ego.push_back({speed * t, y, speed, std::atan2(y_rate, speed), 0.0});
    tr.controls.push_back({});
    for (auto [car, x0, v] : {std::tuple{car_of(Role::Leader), 30.0, 7.0},
                              std::tuple{car_of(Role::Follower), -12.0, 9.0},
                              std::tuple{car_of(Role::Target), 20.0, 9.5}}) {
      auto& track = tr.others.cars[static_cast<std::size_t>(car)];
      track.x.push_back(x0 + v * t);
      track.v.push_back(v);
      track.a.push_back(0.0);
    }
  }
  return tr;
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

std::string line_with(const std::string& text, const std::string& what) {
  const auto pos = text.find(what);
  if (pos == std::string::npos) return {};
  const auto begin = text.rfind('\n', pos) + 1;
  return text.substr(begin, text.find('\n', pos) - begin);
}

/// A fresh directory, removed with everything in it.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("lanechange_plot_test_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() { fs::remove_all(path_); }
  [[nodiscard]] std::string file(const std::string& name) const { return (path_ / name).string(); }
  [[nodiscard]] int entries() const {
    return static_cast<int>(std::distance(fs::directory_iterator(path_), fs::directory_iterator()));
  }

 private:
  fs::path path_;
};

/// Sets an environment variable for one test, restoring the old value after.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A stand-in gnuplot that complains and fails, as the real one does on a bad script.
std::string failing_gnuplot(const ScratchDir& dir) {
  const std::string path = dir.file("fake_gnuplot.sh");
  std::ofstream(path) << "#!/bin/sh\necho 'line 3: boom' >&2\nexit 3\n";
  ::chmod(path.c_str(), 0755);
  return path;
}

TEST(PlotScript, DrawsLaneEdgesAndDashedCentreLine) {
  const std::string script = trajectory_plot_script(lane_change(), "out.png");
  const std::string lower = line_with(script, "first -1.75 to graph 1, first -1.75 ");
  const std::string centre = line_with(script, "first 1.75 to graph 1, first 1.75 ");
  const std::string upper = line_with(script, "first 5.25 to graph 1, first 5.25 ");
  ASSERT_FALSE(lower.empty()) << script;
  ASSERT_FALSE(centre.empty()) << script;
  ASSERT_FALSE(upper.empty()) << script;
  EXPECT_NE(centre.find(" dt "), std::string::npos);
  EXPECT_EQ(lower.find(" dt "), std::string::npos);
  EXPECT_EQ(upper.find(" dt "), std::string::npos);
  EXPECT_NE(script.find("set yrange [-3.5:7]"), std::string::npos);
}

// A rollout's take-over and fallback steps are marked where the ego was.
TEST(PlotScript, MarksTheStepsWhereARolloutTookOverOrFellBack) {
  Trajectory tr = lane_change();
  EXPECT_EQ(trajectory_plot_script(tr, "out.png").find("took over"), std::string::npos);
  tr.details["events"] = {{"took_over", {{{"step", 3}, {"reason", "r"}}}},
                          {"fallback", nlohmann::json::array()}};
  const std::string script = trajectory_plot_script(tr, "out.png");
  EXPECT_NE(script.find("title 'expert took over'"), std::string::npos) << script;
  EXPECT_EQ(script.find("title 'fallback'"), std::string::npos);  // no fallback step
  const std::string opening = "$took_over << EOD\n";
  const auto block = script.find(opening);
  ASSERT_NE(block, std::string::npos);
  const auto start = block + opening.size();
  const std::string first_mark = script.substr(start, script.find('\n', start) - start);
  std::istringstream in(first_mark);
  double x = 0.0;
  double y = 0.0;
  in >> x >> y;
  EXPECT_NEAR(x, tr.ego[3].x, 1e-3);  // the script keeps a few digits
  EXPECT_NEAR(y, tr.ego[3].y, 1e-3);
}

TEST(PlotScript, DrawsEveryCarAtEverySnapshot) {
  EXPECT_EQ(count(trajectory_plot_script(lane_change(), "out.png"), " polygon "), 4 * 5);
  PlotOptions three;
  three.snapshots = 3;
  EXPECT_EQ(count(trajectory_plot_script(lane_change(), "out.png", three), " polygon "), 4 * 3);
}

TEST(PlotScript, SnapshotsAreEvenlySpacedAndCarsInTheirLanes) {
  const std::string script = trajectory_plot_script(lane_change(), "out.png");
  for (const char* t : {"'0 s'", "'1.25 s'", "'2.5 s'", "'3.75 s'", "'5 s'"}) {
    EXPECT_EQ(count(script, t), 4) << t;
  }
  // At t = 0 the ego (x = 0, theta = 0) is a 4.4 x 1.7 box centred at the origin,
  // the leader one centred at x = 30 in the ego lane, the follower at x = -12 in the target lane.
  EXPECT_NE(
      script.find("polygon from 2.2,0.85 to -2.2,0.85 to -2.2,-0.85 to 2.2,-0.85 to 2.2,0.85"),
      std::string::npos);
  EXPECT_NE(script.find("polygon from 32.2,0.85 to 27.8,0.85"), std::string::npos);
  EXPECT_NE(script.find("polygon from -9.8,4.35 to -14.2,4.35"), std::string::npos);
  for (const char* name : {"'ego'", "'leader'", "'follower'", "'target'"}) {
    EXPECT_NE(script.find("set label " + std::string(name)), std::string::npos) << name;
  }
}

TEST(PlotScript, TitleNamesPlannerLabelAndReasonSafelyQuoted) {
  Trajectory tr = lane_change();
  tr.label = Label::IllPosed;
  tr.reason = "y drops 0.3 m (driver's \"choice\")\nsecond line";
  const std::string title = line_with(trajectory_plot_script(tr, "it's.png"), "set title");
  EXPECT_EQ(title,
            "set title 'planner: miqp    label: ill_posed    reason: y drops 0.3 m (driver''s "
            "\"choice\") second line' font 'Sans,12'");
  EXPECT_NE(trajectory_plot_script(tr, "it's.png").find("set output 'it''s.png'"),
            std::string::npos);
}

TEST(PlotScript, TitleNamesTheGapAPlanTook) {
  Trajectory tr = lane_change();
  tr.details["gap"] = {{"behind", "target"}, {"ahead", nullptr}};
  const std::string title = line_with(trajectory_plot_script(tr, "p.png"), "set title");
  EXPECT_NE(title.find("gap: target - none"), std::string::npos) << title;
  tr.details.erase("gap");
  EXPECT_EQ(line_with(trajectory_plot_script(tr, "p.png"), "set title").find("gap:"),
            std::string::npos);
}

TEST(PlotScript, PathAndRangesCoverTheWholeTrajectory) {
  const std::string script = trajectory_plot_script(lane_change(), "out.png");
  const auto begin = script.find("$ego_path << EOD\n");
  const auto end = script.find("EOD\n", begin + 16);
  ASSERT_NE(begin, std::string::npos);
  EXPECT_EQ(count(script.substr(begin, end - begin), "\n"), 1 + 51);
  // Follower rear at t = 0 is -14.2; leader front at t = 5 is 67.2.
  const std::string xrange = line_with(script, "set xrange");
  double lo = 0.0, hi = 0.0;
  ASSERT_EQ(std::sscanf(xrange.c_str(), "set xrange [%lf:%lf]", &lo, &hi), 2) << xrange;
  EXPECT_LT(lo, -14.2);
  EXPECT_GT(hi, 67.2);
  EXPECT_LT(hi - lo, 100.0);
}

// A right-hand change, held as its mirror image, is drawn with its target
// lane below: the y axis runs down, labelled with the file's y; the
// animation leaves its scene unflipped.
TEST(PlotScript, ARightHandChangeIsDrawnWithItsTargetLaneBelow) {
  Trajectory tr = lane_change();
  tr.target_side = Side::Right;
  const std::string script = trajectory_plot_script(tr, "out.png");
  EXPECT_NE(script.find("set yrange [7:-3.5]"), std::string::npos) << script;
  EXPECT_NE(script.find("'-3.5' 3.5, '-5.25' 5.25"), std::string::npos)
      << line_with(script, "set ytics");
  EXPECT_NE(script.find("'0' 0,"), std::string::npos) << line_with(script, "set ytics");
  EXPECT_EQ(trajectory_animation_svg(lane_change(11)).find("scale(1,1)"), std::string::npos);
  Trajectory short_right = lane_change(11);
  short_right.target_side = Side::Right;
  EXPECT_NE(trajectory_animation_svg(short_right).find("scale(1,1)"), std::string::npos);
}

TEST(PlotScript, SingleNodeTrajectoryDrawsOneSnapshot) {
  EXPECT_EQ(count(trajectory_plot_script(lane_change(1), "out.png"), " polygon "), 4);
}

TEST(PlotScript, RejectsMalformedInput) {
  Trajectory short_target = lane_change();
  short_target.others.cars[car_of(Role::Target)].x.pop_back();
  EXPECT_THROW((void)trajectory_plot_script(short_target, "out.png"), InputError);
  Trajectory no_lane = lane_change();
  no_lane.lane_width = 0.0;
  EXPECT_THROW((void)trajectory_plot_script(no_lane, "out.png"), InputError);
  Trajectory nan_y = lane_change();
  nan_y.ego[7].y = NAN;
  EXPECT_THROW((void)trajectory_plot_script(nan_y, "out.png"), InputError);
  PlotOptions none;
  none.snapshots = 0;
  EXPECT_THROW((void)trajectory_plot_script(lane_change(), "out.png", none), InputError);
  EXPECT_THROW((void)trajectory_plot_script(lane_change(), "out\n.png"), InputError);
}

TEST(PlotPng, WritesAPngAndNoLeftovers) {
  if (!LANECHANGE_HAVE_GNUPLOT) GTEST_SKIP() << "gnuplot was not found at configure time";
  ScratchDir dir;
  const std::string png = dir.file("lane_change.png");
  plot_trajectory(lane_change(), png);
  const std::string bytes = read_bytes(png);
  ASSERT_GT(bytes.size(), 1000u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(dir.entries(), 1);
}

TEST(PlotPng, BadOutputDirectoryThrows) {
  ScratchDir dir;
  const std::string png = dir.file("no/such/dir/out.png");
  try {
    plot_trajectory(lane_change(), png);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(png));
}

TEST(PlotPng, MissingGnuplotThrowsAndSaysSo) {
  ScratchDir dir;
  const ScopedEnv env("LANECHANGE_GNUPLOT", dir.file("not_there"));
  try {
    plot_trajectory(lane_change(), dir.file("out.png"));
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("gnuplot not found"), std::string::npos) << e.what();
  }
  EXPECT_EQ(dir.entries(), 0);
}

TEST(PlotPng, FailingGnuplotKeepsTheOldFileAndReportsItsError) {
  ScratchDir dir;
  const ScopedEnv env("LANECHANGE_GNUPLOT", failing_gnuplot(dir));
  const std::string png = dir.file("out.png");
  std::ofstream(png) << "previous";
  try {
    plot_trajectory(lane_change(), png);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("exit status 3"), std::string::npos) << message;
    EXPECT_NE(message.find("line 3: boom"), std::string::npos) << message;
  }
  EXPECT_EQ(read_bytes(png), "previous");
  EXPECT_EQ(dir.entries(), 2);  // the fake gnuplot and the old file, no temporary
}

// The values of the first animation of `attribute` ("translate" or "rotate").
std::vector<std::string> animated_values(const std::string& svg, const std::string& type,
                                         std::size_t which = 0) {
  std::size_t at = 0;
  for (std::size_t i = 0; i <= which; ++i) {
    at = svg.find("type=\"" + type + "\" values=\"", at + 1);
    if (at == std::string::npos) return {};
  }
  const auto begin = svg.find("values=\"", at) + 8;
  const std::string list = svg.substr(begin, svg.find('"', begin) - begin);
  std::vector<std::string> out;
  std::stringstream in(list);
  for (std::string v; std::getline(in, v, ';');) out.push_back(v);
  return out;
}

TEST(Animation, EveryCarMovesThroughEveryNodeInRealTime) {
  const Trajectory tr = lane_change(51);
  const std::string svg = trajectory_animation_svg(tr);
  EXPECT_EQ(svg.rfind("<svg", 0), 0U);
  EXPECT_EQ(count(svg, "<g"), count(svg, "</g>"));
  // Three cars, the ego, and the caption that rides with the camera.
  EXPECT_EQ(count(svg, "type=\"translate\""), 5);
  for (std::size_t car = 0; car < 4; ++car) {
    EXPECT_EQ(animated_values(svg, "translate", car).size(), 51U) << car;
  }
  const auto ego = animated_values(svg, "translate", 3);
  EXPECT_EQ(ego.front(), "0,0");
  EXPECT_EQ(ego.back(), "40,3.5");  // 8 m/s for 5 s, into the target lane
  const auto heading = animated_values(svg, "rotate");
  ASSERT_EQ(heading.size(), 51U);
  EXPECT_EQ(heading.front(), "0");
  EXPECT_GT(std::stod(heading[25]), 1.0);  // degrees, turning left mid-way
  EXPECT_NE(svg.find("dur=\"5s\""), std::string::npos);
  AnimationOptions twice;
  twice.speedup = 2.0;
  EXPECT_NE(trajectory_animation_svg(tr, twice).find("dur=\"2.5s\""), std::string::npos);
}

TEST(Animation, MarksEventsEscapesTextAndRefusesBadInput) {
  Trajectory tr = lane_change(11);
  tr.reason = "a <reason> & more";
  tr.details["events"]["took_over"] = nlohmann::json::array({{{"step", 3}}});
  const std::string svg = trajectory_animation_svg(tr);
  EXPECT_NE(svg.find("a &lt;reason&gt; &amp; more"), std::string::npos);
  EXPECT_EQ(count(svg, "<title>took_over</title>"), 1);
  EXPECT_THROW((void)trajectory_animation_svg(lane_change(1)), InputError);
  Trajectory short_cars = lane_change(11);
  short_cars.others.cars[0].x.pop_back();
  EXPECT_THROW((void)trajectory_animation_svg(short_cars), InputError);
  AnimationOptions bad;
  bad.speedup = 0.0;
  EXPECT_THROW((void)trajectory_animation_svg(tr, bad), InputError);
}

}  // namespace
}  // namespace lanechange
