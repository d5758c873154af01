#pragma once
// The manifest: written first (parameters, status "incomplete") so that a
// resume can check it runs the same job, and rewritten at the end with the
// shard list, row counts, checksums and counts.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lanechange::data {

enum class DirectoryState { Fresh, Resumable, Complete };

/// Makes dir ready for a run with these parameters: creates it and writes
/// the first manifest, or checks the manifest there. Throws InputError (and
/// touches nothing) for a directory that holds something else.
[[nodiscard]] DirectoryState prepare_directory(const std::string& dir,
                                               const nlohmann::json& parameters);

/// Temporary files a killed run left behind.
void remove_stale_temporaries(const std::string& dir);

/// Reads every shard back, checks its row counts, and writes the complete
/// manifest. `run` describes this run (host, ranks, ...).
void write_final_manifest(const std::string& dir, const nlohmann::json& parameters,
                          const nlohmann::json& run);

struct ShardRange;

/// The same for shards of any sizes (DAgger's rounds, one shard each), in
/// the order given; readers take the shard list from the manifest.
void write_manifest_of_shards(const std::string& dir, const nlohmann::json& parameters,
                              const nlohmann::json& run, const std::vector<ShardRange>& shards);

/// The manifest of dir; InputError when missing or not one of ours.
[[nodiscard]] nlohmann::json read_manifest(const std::string& dir);

}  // namespace lanechange::data
