#include "experiments/figures.hpp"

#include <algorithm>
#include <sstream>

#include "lanechange/plot.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange::experiments {

namespace {

std::string header(const std::string& png, const std::string& title) {
  return "set terminal pngcairo size 1000,520 font 'Sans,11'\nset output " + gnuplot_quoted(png) +
         "\nset title " + gnuplot_quoted(title) + "\nset key outside right top\nset grid ytics\n";
}

}  // namespace

void plot_success_bars(const std::vector<sim::RolloutRow>& rows,
                       const std::vector<std::string>& planners, const std::string& png_path) {
  std::ostringstream data;
  data << "$success << EOD\n";
  for (const Behavior sampled : kSampledBehaviors) {
    const std::string behavior(to_string(sampled));
    data << behavior;
    for (const auto& planner : planners) {
      long long n = 0;
      long long ok = 0;
      for (const auto& r : rows) {
        if (r.planner != planner || r.behavior != behavior) continue;
        ++n;
        ok += r.success() ? 1 : 0;
      }
      data << ' ' << (n > 0 ? 100.0 * static_cast<double>(ok) / static_cast<double>(n) : 0.0);
    }
    data << "\n";
  }
  data << "EOD\n";
  std::string plot = "plot ";
  for (std::size_t i = 0; i < planners.size(); ++i) {
    if (i > 0) plot += ", ";
    plot += "$success using " + std::to_string(i + 2);
    plot += (i == 0 ? ":xtic(1)" : "");
    plot += " title " + gnuplot_quoted(planners[i]);
  }
  render_png(
      [&](const std::string& png) {
        return header(png, "Success (well-posed, no collision) per planner and behavior") +
               data.str() +
               "set style data histograms\nset style histogram cluster gap 1\n"
               "set style fill solid 0.8 border -1\nset boxwidth 0.9\nset yrange [0:100]\n"
               "set ylabel 'success [%]'\nset xtics noenhanced\nset key noenhanced\n" +
               plot + "\n";
      },
      png_path);
}

void plot_step_times(const std::vector<sim::RolloutRow>& rows,
                     const std::vector<std::string>& planners, const std::string& png_path) {
  std::ostringstream data;
  std::string plot = "plot ";
  bool first = true;
  for (std::size_t i = 0; i < planners.size(); ++i) {
    std::vector<double> ms;
    for (const auto& r : rows) {
      // A planner that never acted (keep-lane's steps are the fallback's) has no time to show.
      if (r.planner == planners[i] && r.median_step_ms > 0) ms.push_back(r.median_step_ms);
    }
    if (ms.empty()) continue;
    std::sort(ms.begin(), ms.end());
    data << "$p" << i << " << EOD\n";
    for (std::size_t k = 0; k < ms.size(); ++k) {
      data << ms[k] << ' ' << 100.0 * static_cast<double>(k + 1) / static_cast<double>(ms.size())
           << "\n";
    }
    data << "EOD\n";
    if (!first) plot += ", ";
    first = false;
    plot += "$p" + std::to_string(i) + " using 1:2 with steps lw 2 title " +
            gnuplot_quoted(planners[i]);
  }
  if (first) plot = "set label 'no timed steps' at graph 0.4,0.5\nplot [1e-3:1] 1/0 notitle";
  render_png(
      [&](const std::string& png) {
        return header(png, "Compute time per step: each rollout's median") + data.str() +
               "set logscale x\nset format x '%g'\nset xlabel 'median step time [ms] (log scale)'\n"
               "set ylabel 'rollouts at or below [%]'\nset yrange [0:100]\nset key noenhanced\n" +
               plot + "\n";
      },
      png_path);
}

void plot_dagger(const dagger::DaggerReport& report, const std::string& png_path) {
  std::ostringstream data;
  data << "$rounds << EOD\n";
  for (const auto& r : report.rounds) {
    data << r.round << ' ' << 100.0 * r.success_rate << ' ' << r.takeovers_per_rollout << "\n";
  }
  data << "EOD\n";
  const double expert = 100.0 * report.expert.success_rate;
  const int last = report.rounds.empty() ? 1 : std::max(1, report.rounds.back().round);
  render_png(
      [&](const std::string& png) {
        return header(png, "DAgger: mlp-miqp on held-out scenes after each round") + data.str() +
               "set xrange [-0.2:" + std::to_string(last) +
               ".2]\nset xtics 1\n"
               "set xlabel 'DAgger round (0: before DAgger)'\nset yrange [0:100]\n"
               "set ylabel 'success [%]'\nset y2range [0:*]\nset y2tics\n"
               "set y2label 'take-overs per rollout'\n"
               "plot $rounds using 1:2 with linespoints lw 2 pt 7 title 'mlp-miqp success', " +
               std::to_string(expert) +
               " with lines dt 2 lw 2 title 'miqp success', "
               "$rounds using 1:3 axes x1y2 with linespoints lw 2 pt 5 title 'take-overs per "
               "rollout'\n";
      },
      png_path);
}

}  // namespace lanechange::experiments
