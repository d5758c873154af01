// Built when CMake found no MPI: every run is one process.
#include <cstdlib>

#include "team.hpp"

namespace lanechange::app {

std::unique_ptr<run::Team> make_team() { return std::make_unique<run::Team>(); }

void abort_team(run::Team&, int code) { std::exit(code); }

bool mpi_available() { return false; }

}  // namespace lanechange::app
