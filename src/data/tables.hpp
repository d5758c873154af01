#pragma once
// Reading our CSV files back (for the manifest's counts and dataset-info).
#include <map>
#include <string>
#include <vector>

namespace lanechange::data::detail {

struct ScenarioTally {
  long long rows = 0;
  long long samples = 0;  ///< the sum of the rows' sample counts
  std::map<std::string, long long> by_label;
  std::map<std::string, long long> by_behavior;
  std::map<std::string, long long> by_status;
};

/// Adds a scenarios file's rows to tally. InputError on a malformed file.
void tally_scenarios(const std::string& path, ScenarioTally& tally);

/// Appends a timing file's solve times to out. InputError on a malformed file.
void read_solve_ms(const std::string& path, std::vector<double>& out);

}  // namespace lanechange::data::detail
