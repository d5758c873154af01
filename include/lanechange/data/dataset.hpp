#pragma once
// Expert data at scale (docs/dataset.md): sampled scenarios planned by the
// expert, labelled, and written as CSV shards with a JSON manifest. A run can
// be spread over threads and processes (MPI ranks), and resumed after a kill:
// the content depends only on the parameters, never on who planned what.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/run/team.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::data {

inline constexpr std::string_view kDatasetFormat = "lanechange.dataset/4";
inline constexpr std::string_view kManifestName = "manifest.json";

/// Everything that fixes a data set's content. Two runs with equal options
/// (the thread count aside) write byte-identical deterministic files.
struct GenerateOptions {
  long long count = 0;
  std::uint64_t seed = 0;
  std::optional<Behavior> behavior;  ///< none: each scenario's own draw ("all")
  std::string out_dir;
  std::string solver = "fast";  ///< "fast" or "reference"
  long long shard_size = 200;
  double time_limit_s = 60.0;  ///< per plan
  /// Also plan each gap slot's gap alone and record its label (one more plan
  /// per gap around the ego; docs/dataset.md, "Gaps").
  bool gap_labels = false;
  Config config;
};

/// How a run is carried out; none of it changes the files' content.
struct RunOptions {
  int jobs = 0;                      ///< worker threads; 0 means one per core
  std::ostream* progress = nullptr;  ///< where progress goes (none if null)
  bool progress_on_terminal = false;
  /// A back-end to use instead of the one named in GenerateOptions (tests
  /// inject failing solvers here). It must be const and thread-safe.
  std::shared_ptr<const expert::LaneChangeSolver> solver_override;
  /// The MPI ranks sharing the run (shard s on rank s mod size); none: alone.
  run::Team* team = nullptr;
};

struct GenerateReport {
  long long shards_total = 0;
  long long shards_skipped = 0;  ///< finished by an earlier run (resume)
  long long shards_written = 0;  ///< by this process
  long long scenarios_planned = 0;
  bool already_complete = false;  ///< the manifest said so; nothing was touched
  double wall_s = 0.0;
};

/// Generates (or resumes) the data set. Throws InputError for bad options or
/// for a directory that holds another data set (leaving it untouched).
GenerateReport generate(const GenerateOptions& options, const RunOptions& run);

/// The parameters block of the manifest; a resume must match it exactly.
[[nodiscard]] nlohmann::json dataset_parameters(const GenerateOptions& options);

/// File names of shard s.
[[nodiscard]] std::string scenarios_file(long long shard);
[[nodiscard]] std::string samples_file(long long shard);
[[nodiscard]] std::string timing_file(long long shard);

/// What `dataset-info` prints, read back from the files.
struct DatasetSummary {
  long long scenarios = 0;
  long long samples = 0;
  long long shards = 0;
  nlohmann::json parameters;
  std::map<std::string, long long> by_label;
  std::map<std::string, long long> by_behavior;
  std::map<std::string, long long> by_status;
  std::vector<double> solve_ms;  ///< sorted
  /// Plans that keep the ego's centre within `line_band` of the lane line
  /// for longer than `line_duration_s` (docs/expert.md, "Lane rule").
  double line_band = 0.3;        ///< m
  double line_duration_s = 1.0;  ///< s
  long long reached = 0;         ///< plans that reach the target lane
  long long riding_line = 0;     ///< of those, how many ride the line
  long long ill_posed = 0;
  long long ill_posed_riding_line = 0;
  double longest_on_line_s = 0.0;
  /// Nearest-rank percentile of the solve times (q in [0, 1]).
  [[nodiscard]] double solve_ms_percentile(double q) const;
};

/// Reads a complete data set and checks it against its manifest (row counts,
/// checksums). Throws InputError when it is missing, incomplete or malformed.
[[nodiscard]] DatasetSummary summarize_dataset(const std::string& dir);
void print_summary(const DatasetSummary& summary, std::ostream& out);

}  // namespace lanechange::data
