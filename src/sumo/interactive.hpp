#pragma once
// A CommonRoad interactive scenario folder (docs/sumo.md): NAME.cr.xml (the
// planning problem: the ego's start), NAME.net.xml, NAME.vehicles.rou.xml
// and NAME.add.xml for SUMO. The folder is only read; what SUMO needs
// rewritten goes to the run's own directory.
#include <string>
#include <vector>

#include "lanechange/commonroad/recording.hpp"

namespace lanechange::sumo::detail {

struct InteractiveScenario {
  std::string name;
  std::vector<std::string> sumo_files;  ///< SUMO's -n, -r and -a options with their files
  commonroad::State start;              ///< the first planning problem's initial state
};

/// Reads the folder. InputError naming the folder or the file for a missing
/// file, a file that is not XML, or a scenario without a planning problem.
/// A route that repeats an edge (which SUMO refuses) is written to
/// `work_dir` with the repeat dropped.
[[nodiscard]] InteractiveScenario read_interactive(const std::string& folder,
                                                   const std::string& work_dir);

}  // namespace lanechange::sumo::detail
