#pragma once
// `lanechange crosscheck`: our fast MIQP solver against the reference
// (Bonmin B-BB) on the first-round MIQPs of sampled scenes (Eq. 1's gap, or
// every gap of the target lane), or a replay of
// stored reference verdicts (docs/expert_results.md). Each case is written
// with its scene and config, so that a replay depends on neither the sampler
// nor today's defaults.
#include <cstdint>
#include <ostream>
#include <string>

#include "lanechange/config.hpp"

namespace lanechange::studies {

struct CrossCheckOptions {
  Config config;  ///< for sampled cases; a replayed case uses its own
  long long count = 20;
  long long first = 0;  ///< index of the first sampled scene
  std::uint64_t seed = 1;
  int steps = 0;  ///< N for every case; 0: the config's
  /// One case per gap of each sampled scene's target lane (each from the warm
  /// start aimed into it, as a plan's first round solves it); false: Eq. 1's gap.
  bool every_gap = false;
  double tolerance = 1e-6;           ///< largest relative objective difference
  std::string replay_path;           ///< an earlier output: re-solve only the fast side
  std::ostream* cases = nullptr;     ///< one JSON line per case (the --out file)
  std::ostream* progress = nullptr;  ///< the same lines, as they are made
};

struct CrossCheckReport {
  long long agreed = 0;
  long long total = 0;  ///< cases that count (a replayed reference limit decides nothing)
};

/// Runs the check. InputError for a malformed replay file (naming the line).
[[nodiscard]] CrossCheckReport run_crosscheck(const CrossCheckOptions& options);

}  // namespace lanechange::studies
