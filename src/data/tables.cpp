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

#include "lanechange/error.hpp"

namespace lanechange::data::detail {

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

}  // namespace lanechange::data::detail
