#pragma once
// Progress of a long run. On a terminal a bar redrawn in place; in a log one
// plain line every few seconds, so a log file does not fill with redraws.
#include <chrono>
#include <mutex>
#include <ostream>
#include <string>
#include <string_view>

namespace lanechange::run {

/// One progress line: done/total, rate and ETA (a bar on a terminal).
/// `label` starts a log line ("generate: ..."); `unit` names what is counted.
[[nodiscard]] std::string format_progress(long long done, long long total, double elapsed_s,
                                          bool terminal, std::string_view label = "generate",
                                          std::string_view unit = "scenarios");

class Progress {
 public:
  /// `out` may be null (no output). Thread-safe.
  Progress(std::ostream* out, bool terminal, long long total, double interval_s = -1.0,
           std::string label = "generate", std::string unit = "scenarios");
  void add(long long done);
  /// Prints the last line (and ends the bar's line on a terminal).
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  void print_locked(Clock::time_point now);

  std::ostream* out_;
  bool terminal_;
  long long total_;
  long long done_ = 0;
  double interval_s_;
  std::string label_;
  std::string unit_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point last_print_ = start_;
  std::mutex mutex_;
};

}  // namespace lanechange::run
