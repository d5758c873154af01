// Built when CMake found no MPI: every run is one process.
#include <cstdlib>

#include "team.hpp"

namespace lanechange::app {

std::unique_ptr<data::Team> make_team() { return std::make_unique<data::Team>(); }

void abort_team(data::Team&, int code) { std::exit(code); }

bool mpi_available() { return false; }

}  // namespace lanechange::app
