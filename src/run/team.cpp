#include "lanechange/run/team.hpp"

#include <exception>
#include <stdexcept>

#include "lanechange/error.hpp"

namespace lanechange::run {

Team& team_or_alone(Team* team) {
  // Stateless, so one instance serves every thread.
  static Team alone;
  return team != nullptr ? *team : alone;
}

int decide_on_rank_zero(Team& team, const std::string& field, const std::function<int()>& decide) {
  // Codes below zero: -2 for bad input, -1 for any other error.
  int code = -1;
  std::exception_ptr error;
  if (team.rank() == 0) {
    try {
      code = decide();
    } catch (const InputError&) {
      error = std::current_exception();
      code = -2;
    } catch (...) {
      error = std::current_exception();
    }
  }
  code = team.broadcast(code);
  if (error) std::rethrow_exception(error);
  if (code == -2) throw InputError(field, "refused by rank 0 (see its message)");
  if (code < 0) throw std::runtime_error("rank 0 failed (see its message)");
  return code;
}

}  // namespace lanechange::run
