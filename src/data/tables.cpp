#include "data/tables.hpp"

// Shards are small; a reader thread per file would cost more than it saves.
#define CSV_IO_NO_THREAD
#include <limits>  // csv.h uses it without including it
// csv.h copies file names with strncpy into a fixed buffer, which GCC 12
// flags; the truncation is intended there.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wstringop-truncation"
#endif
#include <libfccp/csv.h>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

#include <algorithm>
#include <cmath>

#include "lanechange/error.hpp"

namespace lanechange::data {

namespace {

template <unsigned Columns>
using Reader = io::CSVReader<Columns, io::trim_chars<>, io::double_quote_escape<',', '"'>>;

// Runs a reading function and turns the parser's errors into input errors
// that name the file.
template <class Read>
void guarded(const std::string& path, Read&& read) {
  try {
    read();
  } catch (const io::error::base& e) {
    throw InputError("", path + " is malformed (" + e.what() + ")");
  }
}

}  // namespace

void tally_scenarios(const std::string& path, ScenarioTally& tally) {
  guarded(path, [&] {
    Reader<4> in(path);
    in.read_header(io::ignore_extra_column, "behavior", "label", "status", "samples");
    std::string behavior, label, status;
    long long samples = 0;
    while (in.read_row(behavior, label, status, samples)) {
      ++tally.rows;
      tally.samples += samples;
      ++tally.by_label[label];
      ++tally.by_behavior[behavior];
      ++tally.by_status[status];
    }
  });
}

void read_solve_ms(const std::string& path, std::vector<double>& out) {
  guarded(path, [&] {
    Reader<1> in(path);
    in.read_header(io::ignore_extra_column, "solve_ms");
    double ms = 0.0;
    while (in.read_row(ms)) out.push_back(ms);
  });
}

namespace {

// One plan's nodes, in order; closes its stretch into the tally at the end.
struct PlanStretch {
  std::string label;
  double stretch_start = 0.0;
  bool in_band = false;
  double longest = 0.0;

  void add(double t, double distance, double band) {
    if (distance > band) {
      in_band = false;
      return;
    }
    if (!in_band) stretch_start = t;
    in_band = true;
    longest = std::max(longest, t - stretch_start);
  }

  void close_into(LineTally& tally) const {
    if (label != "well_posed" && label != "ill_posed") return;
    const bool riding = longest > tally.duration;
    ++tally.reached;
    tally.riding += riding ? 1 : 0;
    if (label == "ill_posed") {
      ++tally.ill_posed;
      tally.ill_posed_riding += riding ? 1 : 0;
    }
    tally.longest_s = std::max(tally.longest_s, longest);
  }
};

}  // namespace

void tally_line_riding(const std::string& path, LineTally& tally) {
  guarded(path, [&] {
    Reader<4> in(path);
    in.read_header(io::ignore_extra_column, "index", "label", "t", "y");
    long long index = -1;
    long long previous = -1;
    std::string label;
    double t = 0.0;
    double y = 0.0;
    PlanStretch plan;
    while (in.read_row(index, label, t, y)) {
      if (index != previous) {
        if (previous >= 0) plan.close_into(tally);
        plan = PlanStretch{label};
        previous = index;
      }
      plan.add(t, std::abs(y - tally.line), tally.band);
    }
    if (previous >= 0) plan.close_into(tally);
  });
}

}  // namespace lanechange::data
