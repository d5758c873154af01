#pragma once
// `lanechange label-study`: the label shares of expert plans of sampled
// scenes under several reversal tolerances and both readings of "y never
// decreases" (docs/expert.md, "Labels").
#include <cstdint>
#include <string>

#include "lanechange/config.hpp"

namespace lanechange::studies {

struct LabelStudyOptions {
  Config config;
  long long count = 100;
  std::uint64_t seed = 1;
};

/// Plans each scene once and returns the shares as a Markdown table.
[[nodiscard]] std::string run_label_study(const LabelStudyOptions& options);

}  // namespace lanechange::studies
