#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "data/manifest.hpp"
#include "data/shard.hpp"
#include "data/tables.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "lanechange/run/quantile.hpp"
#include "run/checksum.hpp"

namespace lanechange::data {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Checks one file of a shard against its manifest entry.
void check_file(const std::string& dir, const json& entry, bool has_checksum) {
  const std::string name = entry.at("file").get<std::string>();
  const std::string path = (fs::path(dir) / name).string();
  if (!fs::exists(path)) throw InputError("", path + " is missing");
  if (count_rows(path) != entry.at("rows").get<long long>()) {
    throw InputError("", path + " does not have the rows the manifest lists");
  }
  if (has_checksum && run::file_crc32(path) != entry.at("crc32").get<std::string>()) {
    throw InputError("", path + " does not match the manifest's checksum");
  }
}

void read_shard(const std::string& dir, const json& shard, ScenarioTally& tally, LineTally& line,
                std::vector<double>& solve_ms) {
  check_file(dir, shard.at("scenarios"), true);
  check_file(dir, shard.at("samples"), true);
  check_file(dir, shard.at("timing"), false);
  tally_scenarios((fs::path(dir) / shard["scenarios"]["file"].get<std::string>()).string(), tally);
  tally_line_riding((fs::path(dir) / shard["samples"]["file"].get<std::string>()).string(), line);
  read_solve_ms((fs::path(dir) / shard["timing"]["file"].get<std::string>()).string(), solve_ms);
}

void print_counts(const char* title, const std::map<std::string, long long>& counts,
                  long long total, std::ostream& out) {
  out << title << "\n";
  for (const auto& [name, n] : counts) {
    char line[128];
    std::snprintf(line, sizeof line, "  %-16s %9lld  %5.1f%%\n", name.c_str(), n,
                  total > 0 ? 100.0 * static_cast<double>(n) / static_cast<double>(total) : 0.0);
    out << line;
  }
}

}  // namespace

double DatasetSummary::solve_ms_percentile(double q) const {
  return run::nearest_rank_sorted(solve_ms, q);
}

DatasetSummary summarize_dataset(const std::string& dir) {
  const json manifest = read_manifest(dir);
  if (manifest.value("status", std::string()) != "complete") {
    throw InputError("", dir + " is incomplete; run the same generate command again to finish it");
  }
  DatasetSummary summary;
  ScenarioTally tally;
  LineTally line;
  try {
    summary.parameters = manifest.at("parameters");
    line.line = summary.parameters.at("config").at("lane_width").get<double>() / 2.0;
    line.band = summary.line_band;
    line.duration = summary.line_duration_s;
    for (const json& shard : manifest.at("shards")) {
      read_shard(dir, shard, tally, line, summary.solve_ms);
    }
    summary.shards = static_cast<long long>(manifest.at("shards").size());
    if (tally.rows != summary.parameters.at("count").get<long long>()) {
      throw InputError("", dir + " holds " + std::to_string(tally.rows) +
                               " scenarios, not the manifest's count");
    }
  } catch (const json::exception& e) {
    throw InputError("", dir + "/manifest.json is malformed (" + e.what() + ")");
  }
  summary.scenarios = tally.rows;
  summary.samples = tally.samples;
  summary.by_label = tally.by_label;
  summary.by_behavior = tally.by_behavior;
  summary.by_status = tally.by_status;
  summary.reached = line.reached;
  summary.riding_line = line.riding;
  summary.ill_posed = line.ill_posed;
  summary.ill_posed_riding_line = line.ill_posed_riding;
  summary.longest_on_line_s = line.longest_s;
  std::sort(summary.solve_ms.begin(), summary.solve_ms.end());
  return summary;
}

void print_summary(const DatasetSummary& s, std::ostream& out) {
  const json& p = s.parameters;
  out << s.scenarios << " scenarios in " << s.shards << " shards, " << s.samples
      << " samples; seed " << p.value("seed", json()).dump() << ", behavior "
      << p.value("behavior", std::string("?")) << ", solver " << p.value("solver", std::string("?"))
      << ", version " << p.value("version", std::string("?")) << "\n";
  print_counts("by label", s.by_label, s.scenarios, out);
  print_counts("by behavior", s.by_behavior, s.scenarios, out);
  print_counts("by plan status", s.by_status, s.scenarios, out);
  char line[320];
  std::snprintf(line, sizeof line, "solve time (ms): p50 %.2f, p90 %.2f, p99 %.2f, max %.2f\n",
                s.solve_ms_percentile(0.5), s.solve_ms_percentile(0.9), s.solve_ms_percentile(0.99),
                s.solve_ms_percentile(1.0));
  out << line;
  std::snprintf(line, sizeof line,
                "on the lane line (centre within %.2f m of it for more than %.1f s): %lld of %lld "
                "plans that reach the target lane, %lld of %lld ill-posed; longest %.1f s\n",
                s.line_band, s.line_duration_s, s.riding_line, s.reached, s.ill_posed_riding_line,
                s.ill_posed, s.longest_on_line_s);
  out << line;
}

}  // namespace lanechange::data
