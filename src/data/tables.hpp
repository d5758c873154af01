#pragma once
// Reading our CSV files back (for the manifest's counts and dataset-info).
#include <map>
#include <string>
#include <vector>

namespace lanechange::data {

struct ScenarioTally {
  long long rows = 0;
  long long samples = 0;  ///< the sum of the rows' sample counts
  std::map<std::string, long long> by_label;
  std::map<std::string, long long> by_behavior;
  std::map<std::string, long long> by_status;
};

/// How long plans keep the ego's centre near the lane line (docs/expert.md,
/// "Lane rule"): the longest stretch of consecutive nodes with
/// |y - line| <= band, from its first node's time to its last's.
struct LineTally {
  double line = 0.0;      ///< m, y of the lane line
  double band = 0.3;      ///< m
  double duration = 1.0;  ///< s: a longer stretch counts as riding the line
  long long reached = 0;  ///< plans that reach the target lane (well- or ill-posed)
  long long riding = 0;   ///< of those, how many ride the line
  long long ill_posed = 0;
  long long ill_posed_riding = 0;
  double longest_s = 0.0;
};

/// Adds a samples file's plans to tally. InputError on a malformed file.
void tally_line_riding(const std::string& path, LineTally& tally);

/// Adds a scenarios file's rows to tally. InputError on a malformed file.
void tally_scenarios(const std::string& path, ScenarioTally& tally);

/// Appends a timing file's solve times to out. InputError on a malformed file.
void read_solve_ms(const std::string& path, std::vector<double>& out);

}  // namespace lanechange::data
