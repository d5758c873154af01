// Planners beside the recorded drivers: did they change lanes where the
// driver did, how much sooner or later, and through the same gap.
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "common/json_fields.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "run/csv.hpp"
#include "sim/evaluation_files.hpp"

namespace lanechange::sim {

std::vector<HumanComparison> compare_with_humans(std::span<const Scenario> scenes,
                                                 std::span<const RolloutRow> rows,
                                                 const std::vector<std::string>& planners) {
  std::vector<HumanComparison> out;
  for (const std::string& planner : planners) {
    HumanComparison c;
    c.planner = planner;
    std::vector<double> differences;
    for (const RolloutRow& row : rows) {
      if (row.planner != planner || row.index < 0 ||
          static_cast<std::size_t>(row.index) >= scenes.size()) {
        continue;
      }
      const auto& origin = scenes[static_cast<std::size_t>(row.index)].origin;
      if (!origin || !origin->human_change) continue;
      const HumanLaneChange& human = *origin->human_change;
      ++c.scenes;
      c.succeeded += row.success() ? 1 : 0;
      if (!std::isfinite(row.time_to_lane_line)) continue;
      ++c.changed;
      differences.push_back(row.time_to_lane_line - human.after);
      c.same_gap +=
          row.gap_behind == human.behind.value_or("") && row.gap_ahead == human.ahead.value_or("")
              ? 1
              : 0;
    }
    c.time_difference_p50 = differences.empty() ? std::numeric_limits<double>::quiet_NaN()
                                                : run::nearest_rank(differences, 0.5);
    out.push_back(c);
  }
  return out;
}

namespace detail {

void write_human_comparison(const std::string& dir, const std::vector<HumanComparison>& rows) {
  const auto share = [](long long part, long long whole) {
    return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole)
                     : std::numeric_limits<double>::quiet_NaN();
  };
  const auto number = [](double v) { return std::isfinite(v) ? std::to_string(v) : std::string(); };
  std::string text = csv_header({"planner", "human_changes", "changed", "changed_rate", "same_gap",
                                 "same_gap_rate", "success_rate", "time_difference_p50"});
  for (const HumanComparison& c : rows) {
    text += run::csv_field(c.planner) + "," + std::to_string(c.scenes) + "," +
            std::to_string(c.changed) + "," + number(share(c.changed, c.scenes)) + "," +
            std::to_string(c.same_gap) + "," + number(share(c.same_gap, c.changed)) + "," +
            number(share(c.succeeded, c.scenes)) + "," + number(c.time_difference_p50) + "\n";
  }
  lanechange::detail::write_file_atomically((std::filesystem::path(dir) / "human.csv").string(),
                                            text);
}

}  // namespace detail
}  // namespace lanechange::sim
