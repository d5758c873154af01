#pragma once
#include <stdexcept>
#include <string>

namespace lanechange {

/// Bad input from a user: a malformed or non-physical scenario, config or
/// trajectory file. The CLI maps it to exit code 2. `field()` names the JSON
/// path of the offending value (for example "follower.v"), or is empty.
class InputError : public std::runtime_error {
 public:
  InputError(std::string field, const std::string& problem)
      : std::runtime_error(field.empty() ? problem : field + ": " + problem),
        field_(std::move(field)) {}
  [[nodiscard]] const std::string& field() const { return field_; }

 private:
  std::string field_;
};

}  // namespace lanechange
