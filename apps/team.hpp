#pragma once
// The processes of a `generate` run: the MPI ranks when started by mpirun,
// else this process alone.
#include <memory>

#include "lanechange/data/dataset.hpp"

namespace lanechange::app {

/// MPI is initialised only when a launcher started us (it sets
/// OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK): a plain run of the CLI then
/// pays nothing for it. Finalised when the team is destroyed.
[[nodiscard]] std::unique_ptr<data::Team> make_team();

/// Ends every rank with this exit code; a rank that fails alone would
/// leave the others waiting at the barrier forever.
[[noreturn]] void abort_team(data::Team& team, int code);

/// Whether this build can use MPI at all.
[[nodiscard]] bool mpi_available();

}  // namespace lanechange::app
