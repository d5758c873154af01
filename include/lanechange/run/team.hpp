#pragma once
// The processes that share one run (generate, evaluate, experiments): MPI
// ranks, or one process alone. Every run takes its team the same way: a
// pointer in its run options, where null means this process alone.
#include <functional>
#include <string>

namespace lanechange::run {

/// Shard s belongs to rank s mod size; rank 0 prepares the output directory
/// and writes the final manifest.
class Team {
 public:
  virtual ~Team() = default;
  [[nodiscard]] virtual int rank() const { return 0; }
  [[nodiscard]] virtual int size() const { return 1; }
  virtual void barrier() {}
  /// Rank 0's value, returned on every rank.
  virtual int broadcast(int value) { return value; }
};

/// The team a run uses: `team`, or this process alone where it is null.
[[nodiscard]] Team& team_or_alone(Team* team);

/// Runs `decide` on rank 0 alone and returns its non-negative answer on
/// every rank, so that all ranks stop (or go on) together. Rank 0 rethrows
/// what `decide` threw; the other ranks throw InputError (naming `field`)
/// for an InputError there and std::runtime_error for anything else.
int decide_on_rank_zero(Team& team, const std::string& field, const std::function<int()>& decide);

}  // namespace lanechange::run
