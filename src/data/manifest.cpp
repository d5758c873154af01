#include "data/manifest.hpp"

#include <filesystem>
#include <fstream>
#include <vector>

#include "common/json_fields.hpp"
#include "data/rows.hpp"
#include "data/shard.hpp"
#include "data/tables.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "run/checksum.hpp"

namespace lanechange::data {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string manifest_path(const std::string& dir) {
  return (fs::path(dir) / kManifestName).string();
}

json columns_block() {
  return {{"scenarios", scenario_columns()},
          {"samples", sample_columns()},
          {"timing", timing_columns()},
          {"classifier_features", classifier_features()},
          {"gap_classifier_features", gap_classifier_features()},
          {"action_inputs", action_inputs()},
          {"gap_action_inputs", gap_action_inputs()},
          {"action_targets", action_targets()}};
}

void write_manifest(const std::string& dir, const json& manifest) {
  lanechange::detail::write_file_atomically(manifest_path(dir), manifest.dump(2) + "\n");
}

// Names the first parameter that differs, so the user sees what to fix.
std::string first_difference(const json& existing, const json& requested) {
  const json patch = json::diff(existing, requested);
  if (patch.empty()) return "";
  const json& op = patch.front();
  std::string text = "parameters" + op.value("path", std::string()) + " is ";
  const auto where = json::json_pointer(op.value("path", std::string()));
  text += existing.contains(where) ? existing.at(where).dump() : std::string("absent");
  text += " in the data set but ";
  text += requested.contains(where) ? requested.at(where).dump() : std::string("absent");
  return text + " in this run";
}

DirectoryState check_existing(const std::string& dir, const json& parameters) {
  const json manifest = read_manifest(dir);
  // Shards of another format have other columns: they cannot be continued.
  if (manifest.at("format").get<std::string>() != kDatasetFormat) {
    throw InputError("--out", dir + " holds a data set of format " + manifest.at("format").dump() +
                                  ", which this version reads but does not continue; use a "
                                  "new directory");
  }
  const std::string difference = first_difference(manifest.at("parameters"), parameters);
  if (!difference.empty()) {
    throw InputError("--out", dir + " holds another data set (" + difference +
                                  "); use a new directory or the same parameters");
  }
  return manifest.value("status", std::string()) == "complete" ? DirectoryState::Complete
                                                               : DirectoryState::Resumable;
}

void create_directory(const std::string& dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error || !fs::is_directory(dir)) {
    throw InputError(
        "--out", "cannot create directory " + dir + (error ? " (" + error.message() + ")" : ""));
  }
}

json shard_entry(const std::string& dir, const ShardRange& range, ScenarioTally& tally) {
  const fs::path d(dir);
  const std::string scenarios = (d / scenarios_file(range.shard)).string();
  const std::string samples = (d / samples_file(range.shard)).string();
  const long long before_samples = tally.samples;
  const long long before_rows = tally.rows;
  tally_scenarios(scenarios, tally);
  const long long sample_rows = count_rows(samples);
  const long long timing_rows = count_rows((d / timing_file(range.shard)).string());
  if (tally.rows - before_rows != range.count || timing_rows != range.count ||
      sample_rows != tally.samples - before_samples) {
    throw std::runtime_error("shard " + std::to_string(range.shard) +
                             " is missing or incomplete; run the same command again");
  }
  return {{"index", range.shard},
          {"first", range.first},
          {"count", range.count},
          {"scenarios",
           {{"file", scenarios_file(range.shard)},
            {"rows", range.count},
            {"crc32", run::file_crc32(scenarios)}}},
          {"samples",
           {{"file", samples_file(range.shard)},
            {"rows", sample_rows},
            {"crc32", run::file_crc32(samples)}}},
          {"timing", {{"file", timing_file(range.shard)}, {"rows", timing_rows}}}};
}

}  // namespace

json read_manifest(const std::string& dir) {
  if (!fs::exists(manifest_path(dir))) {
    throw InputError("", dir + " has no " + std::string(kManifestName) + ": not a data set");
  }
  json manifest = lanechange::detail::read_json_file(manifest_path(dir));
  // Formats 2 and 3 lack only gap columns, which only the models that use
  // them require: they still read.
  const std::string format = manifest.is_object() ? manifest.value("format", std::string()) : "";
  if ((format != kDatasetFormat && format != "lanechange.dataset/2" &&
       format != "lanechange.dataset/3") ||
      !manifest.contains("parameters") || !manifest["parameters"].is_object()) {
    throw InputError("",
                     manifest_path(dir) + " is not a " + std::string(kDatasetFormat) + " manifest");
  }
  return manifest;
}

DirectoryState prepare_directory(const std::string& dir, const json& parameters) {
  if (fs::exists(manifest_path(dir))) return check_existing(dir, parameters);
  if (fs::exists(dir) && !fs::is_directory(dir)) {
    throw InputError("--out", dir + " exists and is not a directory");
  }
  if (fs::exists(dir) && !fs::is_empty(dir)) {
    throw InputError("--out", dir + " is not empty and holds no data set (no " +
                                  std::string(kManifestName) + "); choose a new directory");
  }
  create_directory(dir);
  const json manifest = {{"format", kDatasetFormat},
                         {"status", "incomplete"},
                         {"parameters", parameters},
                         {"columns", columns_block()}};
  try {
    write_manifest(dir, manifest);
  } catch (const std::exception& e) {
    throw InputError("--out", "cannot write into " + dir + " (" + e.what() + ")");
  }
  return DirectoryState::Fresh;
}

void remove_stale_temporaries(const std::string& dir) {
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().find(".tmp.") != std::string::npos) {
      fs::remove(entry.path());
    }
  }
}

void write_final_manifest(const std::string& dir, const json& parameters, const json& run) {
  const long long count = parameters.at("count").get<long long>();
  const long long shard_size = parameters.at("shard_size").get<long long>();
  std::vector<ShardRange> ranges;
  for (long long s = 0; s < shard_count(count, shard_size); ++s) {
    ranges.push_back(shard_range(s, count, shard_size));
  }
  write_manifest_of_shards(dir, parameters, run, ranges);
}

void write_manifest_of_shards(const std::string& dir, const json& parameters, const json& run,
                              const std::vector<ShardRange>& ranges) {
  ScenarioTally tally;
  json shards = json::array();
  for (const ShardRange& range : ranges) shards.push_back(shard_entry(dir, range, tally));
  const json manifest = {{"format", kDatasetFormat},
                         {"status", "complete"},
                         {"parameters", parameters},
                         {"columns", columns_block()},
                         {"counts",
                          {{"scenarios", tally.rows},
                           {"samples", tally.samples},
                           {"by_label", tally.by_label},
                           {"by_behavior", tally.by_behavior},
                           {"by_status", tally.by_status}}},
                         {"shards", shards},
                         {"run", run}};
  write_manifest(dir, manifest);
}

}  // namespace lanechange::data
