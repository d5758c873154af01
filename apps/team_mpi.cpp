#include <mpi.h>

#include <cstdlib>

#include "team.hpp"

namespace lanechange::app {

namespace {

bool started_by_launcher() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

class MpiTeam final : public run::Team {
 public:
  MpiTeam() {
    // Only the main thread talks to MPI; the workers only plan and write.
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiTeam() override { MPI_Finalize(); }
  MpiTeam(const MpiTeam&) = delete;
  MpiTeam& operator=(const MpiTeam&) = delete;

  [[nodiscard]] int rank() const override { return rank_; }
  [[nodiscard]] int size() const override { return size_; }
  void barrier() override { MPI_Barrier(MPI_COMM_WORLD); }
  int broadcast(int value) override {
    MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return value;
  }

 private:
  int rank_ = 0;
  int size_ = 1;
};

}  // namespace

std::unique_ptr<run::Team> make_team() {
  if (!started_by_launcher()) return std::make_unique<run::Team>();
  return std::make_unique<MpiTeam>();
}

void abort_team(run::Team& team, int code) {
  if (team.size() > 1) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

bool mpi_available() { return true; }

}  // namespace lanechange::app
