#pragma once
// Helpers for the data-stage tests: running `generate`, reading our CSV files
// back without the library's reader, and snapshotting a directory.
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "../foundation/test_helpers.hpp"

namespace lanechange::testing {

/// The options every small test run shares: N = 8 keeps a plan to ~2 ms.
inline std::string small_run(const std::string& dir, long long count, std::uint64_t seed,
                             const std::string& extra = "") {
  return "generate --count " + std::to_string(count) + " --seed " + std::to_string(seed) +
         " --steps 8 --shard-size 3 --out " + dir + " " + extra;
}

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  [[nodiscard]] std::size_t column(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) return i;
    }
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
};

/// Splits on commas; the last column takes the rest of the line (only the
/// reason, which is last, may hold quoted commas).
inline std::vector<std::string> split_line(const std::string& line, std::size_t columns) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (out.size() + 1 < columns) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string::npos) break;
    out.push_back(line.substr(start, comma - start));
    start = comma + 1;
  }
  out.push_back(line.substr(start));
  return out;
}

inline Table read_table(const std::string& path) {
  std::ifstream in(path);
  Table t;
  std::string line;
  if (!std::getline(in, line)) return t;
  t.header = split_line(line, 1000);
  while (std::getline(in, line)) t.rows.push_back(split_line(line, t.header.size()));
  return t;
}

/// Every file of a kind ("scenarios", "samples", "timing") of a data set,
/// concatenated in shard order, as one table.
inline Table read_all(const std::filesystem::path& dir, const std::string& kind) {
  Table all;
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(kind + "-", 0) == 0) files[name] = e.path().string();
  }
  for (const auto& [name, path] : files) {
    Table t = read_table(path);
    all.header = t.header;
    all.rows.insert(all.rows.end(), t.rows.begin(), t.rows.end());
  }
  return all;
}

/// Name -> content of the files whose content must not depend on how the run
/// went (jobs, ranks, interruptions): the scenarios and samples shards.
inline std::map<std::string, std::string> deterministic_files(const std::filesystem::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("scenarios-", 0) == 0 || name.rfind("samples-", 0) == 0) {
      out[name] = read_text(e.path().string());
    }
  }
  return out;
}

/// Name -> content of every file.
inline std::map<std::string, std::string> all_files(const std::filesystem::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    out[e.path().filename().string()] = read_text(e.path().string());
  }
  return out;
}

inline nlohmann::json read_manifest(const std::filesystem::path& dir) {
  return nlohmann::json::parse(read_text((dir / "manifest.json").string()));
}

}  // namespace lanechange::testing
