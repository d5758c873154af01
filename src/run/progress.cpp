#include "lanechange/run/progress.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace lanechange::run {

namespace {

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds)) return "?";
  const long long s = std::llround(std::max(0.0, seconds));
  char text[32];
  std::snprintf(text, sizeof text, "%lld:%02lld:%02lld", s / 3600, (s / 60) % 60, s % 60);
  return text;
}

}  // namespace

std::string format_progress(long long done, long long total, double elapsed_s, bool terminal,
                            std::string_view label, std::string_view unit) {
  const double rate = elapsed_s > 0.0 ? static_cast<double>(done) / elapsed_s : 0.0;
  const double eta = rate > 0.0 ? static_cast<double>(total - done) / rate : INFINITY;
  const double fraction = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
  char tail[200];
  std::snprintf(tail, sizeof tail, "%lld/%lld %.*s (%.1f%%), %.1f/s, elapsed %s, ETA %s", done,
                total, static_cast<int>(unit.size()), unit.data(), 100.0 * fraction, rate,
                format_duration(elapsed_s).c_str(), format_duration(eta).c_str());
  if (!terminal) return std::string(label) + ": " + tail;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(std::floor(fraction * kWidth));
  std::string line = "[";
  line.append(static_cast<std::size_t>(filled), '#');
  line.append(static_cast<std::size_t>(kWidth - filled), '.');
  line.append("] ");
  line.append(tail);
  return line;
}

Progress::Progress(std::ostream* out, bool terminal, long long total, double interval_s,
                   std::string label, std::string unit)
    : out_(out),
      terminal_(terminal),
      total_(total),
      interval_s_(interval_s >= 0.0 ? interval_s : (terminal ? 0.2 : 5.0)),
      label_(std::move(label)),
      unit_(std::move(unit)) {}

void Progress::add(long long done) {
  const std::lock_guard lock(mutex_);
  done_ += done;
  const auto now = Clock::now();
  if (std::chrono::duration<double>(now - last_print_).count() >= interval_s_) {
    print_locked(now);
  }
}

void Progress::finish() {
  const std::lock_guard lock(mutex_);
  print_locked(Clock::now());
  if (out_ != nullptr && terminal_) *out_ << "\n" << std::flush;
}

void Progress::print_locked(Clock::time_point now) {
  last_print_ = now;
  if (out_ == nullptr) return;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  // "\r" and the erase-line code redraw the bar in place.
  if (terminal_) *out_ << "\r\033[K";
  *out_ << format_progress(done_, total_, elapsed, terminal_, label_, unit_);
  if (!terminal_) *out_ << "\n";
  *out_ << std::flush;
}

}  // namespace lanechange::run
