#pragma once
// The processes of a `generate` or `evaluate` run: the MPI ranks when
// started by mpirun, else this process alone.
#include <functional>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "lanechange/error.hpp"
#include "lanechange/run/team.hpp"

namespace lanechange::app {

/// MPI is initialised only when a launcher started us (it sets
/// OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK): a plain run of the CLI then
/// pays nothing for it. Finalised when the team is destroyed.
[[nodiscard]] std::unique_ptr<run::Team> make_team();

/// Ends every rank with this exit code; a rank that fails alone would
/// leave the others waiting at the barrier forever.
[[noreturn]] void abort_team(run::Team& team, int code);

/// Runs `job` on this rank. Bad input is the same on every rank, so each
/// stops by itself (exit code 2 through the caller); any other error on one
/// rank ends them all, since the others would wait for it forever.
inline void run_on_team(run::Team& team, const std::function<void()>& job) {
  try {
    job();
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    if (team.size() <= 1) throw;
    std::cerr << "error on rank " << team.rank() << ": " << e.what() << "\n";
    abort_team(team, 1);
  }
}

/// Whether this build can use MPI at all.
[[nodiscard]] bool mpi_available();

}  // namespace lanechange::app
