#pragma once
#include <string>

namespace lanechange::run {

/// The file's CRC-32 as 8 hex digits: the manifests record it, so that a
/// shard or model file changed after it was written is refused.
[[nodiscard]] std::string file_crc32(const std::string& path);

}  // namespace lanechange::run
