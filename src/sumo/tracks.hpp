#pragma once
// The rollout's record of SUMO's cars: one track per stay of a car in the
// ego or the target lane, present at the nodes of that stay.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "lanechange/scenario.hpp"
#include "lanechange/traffic.hpp"
#include "sumo/connection.hpp"

namespace lanechange::sumo::detail {

class TrackRecorder {
 public:
  /// Records node k: the cars seen then (any car not among them is absent).
  void record(int node, const std::vector<SumoCar>& cars);
  /// `base` (the ego and the settings) with one car per track, each at its
  /// first recorded state; the roles go to the tracks of the cars that had
  /// them at node 0 (ids in Role order; empty: none).
  [[nodiscard]] Scenario scene(Scenario base, const std::array<std::string, 3>& roles) const;
  /// The tracks over `nodes` nodes, absent nodes holding the nearest stay's values.
  [[nodiscard]] std::vector<CarTrack> take_tracks(std::size_t nodes);

 private:
  struct Stay {
    /// The car at the stay's first node; its id is the car's, a later stay
    /// of the same car adding "~2", "~3", ...
    SumoCar first;
    int last_node = -1;
    CarTrack track;
  };
  std::vector<Stay> stays_;
  std::map<std::string, std::size_t> open_;  ///< a car's id: its stay being recorded
  std::map<std::string, int> count_;         ///< a car's id: its stays so far
};

}  // namespace lanechange::sumo::detail
