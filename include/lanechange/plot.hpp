#pragma once
// A picture of a plan or rollout: the two-lane road, the ego's path, and all
// cars at a few evenly spaced instants, drawn by gnuplot (pngcairo).
//
// gnuplot (5.4 or later, with the pngcairo terminal: Debian's gnuplot-nox) is
// found at run time: $LANECHANGE_GNUPLOT if set and not empty, else `gnuplot`
// on PATH, else the one found when the project was configured.
#include <functional>
#include <string>
#include <string_view>

#include "lanechange/config.hpp"
#include "lanechange/trajectory.hpp"

namespace lanechange {

struct PlotOptions {
  /// The ego's body, which a trajectory does not store (it does the others').
  VehicleSize vehicle;
  int snapshots = 5;  ///< instants at which the cars are drawn, from the first to the last node
  int width_px = 1400;
  int height_px = 450;
};

/// Writes a PNG (atomically: a failure leaves no partial file). Throws
/// InputError for a malformed trajectory or options, std::runtime_error if
/// the file cannot be created or gnuplot is missing or fails (the message
/// says which, with gnuplot's own error output).
void plot_trajectory(const Trajectory& trajectory, const std::string& png_path,
                     const PlotOptions& options = {});

/// The gnuplot script that plot_trajectory runs (testable without gnuplot).
/// Throws InputError as plot_trajectory does.
[[nodiscard]] std::string trajectory_plot_script(const Trajectory& trajectory,
                                                 const std::string& png_path,
                                                 const PlotOptions& options = {});

/// Runs the gnuplot script that script_for(png) makes for a PNG at the given
/// path, and moves the picture to png_path atomically; errors as
/// plot_trajectory's. The script must set the pngcairo terminal and output.
void render_png(const std::function<std::string(const std::string&)>& script_for,
                const std::string& png_path);

/// text as a single-quoted gnuplot string.
[[nodiscard]] std::string gnuplot_quoted(std::string_view text);

}  // namespace lanechange

namespace lanechange {

struct AnimationOptions {
  VehicleSize vehicle;        ///< the ego's body: a trajectory stores only the others'
  double view_length = 90.0;  ///< m of road in view; the view follows the ego
  double speedup = 1.0;       ///< playback speed against real time
  int width_px = 1200;
};

/// An animated SVG of a plan or rollout: the road, every car moving as
/// recorded (the ego turning with its heading), the ego's path, take-over
/// and fallback steps marked, and a clock bar. Plays in any web browser
/// (SMIL animation); needs no program to make. InputError for a malformed
/// trajectory or options.
[[nodiscard]] std::string trajectory_animation_svg(const Trajectory& trajectory,
                                                   const AnimationOptions& options = {});

/// Text made safe inside XML and HTML elements and attributes (control
/// characters become spaces).
[[nodiscard]] std::string xml_escaped(std::string_view text);

/// Writes trajectory_animation_svg atomically.
void animate_trajectory(const Trajectory& trajectory, const std::string& svg_path,
                        const AnimationOptions& options = {});

}  // namespace lanechange
