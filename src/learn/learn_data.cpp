#include "lanechange/learn/learn_data.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <unordered_map>

#include "data/manifest.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "run/checksum.hpp"

namespace lanechange::learn {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Our CSV files quote only their last column (`reason`), so a line splits on
// its first columns-1 commas.
std::vector<std::string_view> split_fields(std::string_view line, std::size_t columns) {
  std::vector<std::string_view> out;
  while (out.size() + 1 < columns) {
    const std::size_t comma = line.find(',');
    if (comma == std::string_view::npos) break;
    out.push_back(line.substr(0, comma));
    line.remove_prefix(comma + 1);
  }
  out.push_back(line);
  return out;
}

// A CSV file read line by line, its columns found by name.
class CsvFile {
 public:
  explicit CsvFile(std::string path) : path_(std::move(path)), in_(path_) {
    std::string header;
    if (!in_ || !std::getline(in_, header)) throw InputError("", path_ + " cannot be read");
    for (std::string_view f : split_fields(header, std::string::npos)) header_.emplace_back(f);
  }
  [[nodiscard]] std::size_t column(const std::string& name) const {
    const auto it = std::find(header_.begin(), header_.end(), name);
    if (it == header_.end()) throw InputError("", path_ + " has no column " + name);
    return static_cast<std::size_t>(it - header_.begin());
  }
  [[nodiscard]] std::vector<std::size_t> columns(const std::vector<std::string>& names) const {
    std::vector<std::size_t> out;
    out.reserve(names.size());
    for (const std::string& n : names) out.push_back(column(n));
    return out;
  }
  bool next(std::vector<std::string_view>& fields) {
    if (!std::getline(in_, line_)) return false;
    fields = split_fields(line_, header_.size());
    if (fields.size() != header_.size()) throw InputError("", path_ + " has a short row");
    return true;
  }
  [[nodiscard]] double number(std::string_view field) const {
    double value = NAN;
    const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
    if (error != std::errc() || end != field.data() + field.size() || !std::isfinite(value)) {
      throw InputError("", path_ + " holds a missing or bad number '" + std::string(field) + "'");
    }
    return value;
  }
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ifstream in_;
  std::vector<std::string> header_;
  std::string line_;
};

template <std::size_t N>
int index_in(const std::array<std::string_view, N>& names, std::string_view value,
             const std::string& where) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == value) return static_cast<int>(i);
  }
  throw InputError("", where + " holds an unknown value '" + std::string(value) + "'");
}

std::vector<std::string> names_at(const json& columns, const char* key, const std::string& dir) {
  if (!columns.contains(key)) {
    throw InputError("", dir + "/manifest.json lists no " + key +
                             " (a data set of an older format lacks some: generate it again)");
  }
  return columns.at(key).get<std::vector<std::string>>();
}

// Growable row-major buffers, turned into matrices once all files are read.
struct Rows {
  std::vector<double> values;
  std::size_t width = 0;
  [[nodiscard]] Eigen::MatrixXd matrix() const {
    const auto n = static_cast<Eigen::Index>(width == 0 ? 0 : values.size() / width);
    return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        values.data(), n, static_cast<Eigen::Index>(width));
  }
};

// The lane mode column: empty at k = 0, where no lane rule applies.
int lane_mode_of(const CsvFile& csv, std::string_view field) {
  if (field.empty()) return -1;
  const double mode = csv.number(field);
  if (mode != 0.0 && mode != 1.0 && mode != 2.0) {
    throw InputError("", csv.path() + " holds a lane_mode other than 0, 1 or 2");
  }
  return static_cast<int>(mode);
}

// The slot named in a gap_slot column (empty: none), as expert::gap_slot_name spells it.
int slot_named(std::string_view name, const std::string& where) {
  if (name.empty()) return kNoGap;
  for (int slot = 0; slot < expert::kGapSlots; ++slot) {
    if (expert::gap_slot_name(slot) == name) return slot;
  }
  throw InputError("", where + " holds an unknown gap slot '" + std::string(name) + "'");
}

struct Loader {
  LearningData& data;
  Rows features, inputs, targets, plan_states, gap_features, gap_view;
  // Per data set: scenario index -> row of the scenario table.
  std::vector<int> row_of_index;

  void read_scenarios(const std::string& path, int dataset) {
    CsvFile csv(path);
    const auto cols = csv.columns(data.classifier_features);
    const std::size_t c_index = csv.column("index"), c_label = csv.column("label"),
                      c_behavior = csv.column("behavior");
    const GapColumns gaps = gap_columns(csv);
    std::vector<std::string_view> f;
    while (csv.next(f)) {
      for (std::size_t c : cols) features.values.push_back(csv.number(f[c]));
      ScenarioTable& t = data.scenarios;
      const auto index = static_cast<long long>(csv.number(f[c_index]));
      if (index < 0 || index >= static_cast<long long>(row_of_index.size())) {
        throw InputError("", path + " holds a scenario index outside the data set");
      }
      row_of_index[static_cast<std::size_t>(index)] = t.rows();
      t.index.push_back(index);
      t.dataset.push_back(dataset);
      t.label.push_back(index_in(kLabelNames, f[c_label], path));
      t.behavior.push_back(index_in(kBehaviorNames, f[c_behavior], path));
      if (!gaps.features.empty()) read_gaps(csv, gaps, f);
    }
  }

  // Where a scenarios file keeps the gap features and targets.
  struct GapColumns {
    std::vector<std::size_t> features;
    std::size_t slot = 0;
    std::array<std::size_t, expert::kGapSlots> labels{};
  };
  [[nodiscard]] GapColumns gap_columns(const CsvFile& csv) const {
    GapColumns g;
    if (data.gap_classifier_features.empty()) return g;
    g.features = csv.columns(data.gap_classifier_features);
    g.slot = csv.column("gap_slot");
    for (int s = 0; s < expert::kGapSlots; ++s) {
      g.labels[static_cast<std::size_t>(s)] =
          csv.column("gap_" + std::string(expert::gap_slot_name(s)) + "_label");
    }
    return g;
  }

  // The gap features and targets of one scenario row.
  void read_gaps(const CsvFile& csv, const GapColumns& g, const std::vector<std::string_view>& f) {
    ScenarioTable& t = data.scenarios;
    for (std::size_t c : g.features) gap_features.values.push_back(csv.number(f[c]));
    const int slot = slot_named(f[g.slot], csv.path());
    const bool well_posed = t.label.back() == kWellPosed;
    t.gap_class.push_back(well_posed ? slot : kNoGap);
    unsigned completable = well_posed && slot != kNoGap ? 1U << slot : 0U;
    for (int s = 0; s < expert::kGapSlots; ++s) {
      if (f[g.labels[static_cast<std::size_t>(s)]] == kLabelNames[kWellPosed])
        completable |= 1U << s;
    }
    t.completable_slots.push_back(completable);
  }

  void read_samples(const std::string& path) {
    CsvFile csv(path);
    const auto in_cols = csv.columns(data.action_inputs);
    const auto out_cols = csv.columns(data.action_targets);
    const auto node_cols = csv.columns(PlanNodeTable::columns());
    // Format 4 sees each node through the plan's own gap.
    const auto view_cols = data.dataset_format == data::kDatasetFormat
                               ? csv.columns(expert::gap_view_names())
                               : std::vector<std::size_t>{};
    const std::size_t c_index = csv.column("index"), c_label = csv.column("label"),
                      c_k = csv.column("k"), c_mode = csv.column("lane_mode");
    std::vector<std::string_view> f;
    while (csv.next(f)) {
      if (f[c_label] == kLabelNames[kFailure]) continue;
      const auto index = static_cast<long long>(csv.number(f[c_index]));
      if (index < 0 || index >= static_cast<long long>(row_of_index.size()) ||
          row_of_index[static_cast<std::size_t>(index)] < 0) {
        throw InputError("", path + " holds a sample of an unknown scenario");
      }
      const int scenario = row_of_index[static_cast<std::size_t>(index)];
      PlanNodeTable& nodes = data.plan_nodes;
      for (std::size_t c : node_cols) plan_states.values.push_back(csv.number(f[c]));
      for (std::size_t c : view_cols) gap_view.values.push_back(csv.number(f[c]));
      nodes.lane_mode.push_back(lane_mode_of(csv, f[c_mode]));
      nodes.node.push_back(static_cast<int>(csv.number(f[c_k])));
      nodes.scenario.push_back(scenario);
      if (f[c_label] != kLabelNames[kWellPosed]) continue;
      for (std::size_t c : in_cols) inputs.values.push_back(csv.number(f[c]));
      for (std::size_t c : out_cols) targets.values.push_back(csv.number(f[c]));
      data.samples.scenario.push_back(scenario);
    }
  }

  void read_dataset(const std::string& dir, const json& manifest, int dataset) {
    const long long count = manifest.at("parameters").at("count").get<long long>();
    row_of_index.assign(static_cast<std::size_t>(count), -1);
    for (const json& shard : manifest.at("shards")) {
      read_scenarios((fs::path(dir) / shard.at("scenarios").at("file").get<std::string>()).string(),
                     dataset);
    }
    for (const json& shard : manifest.at("shards")) {
      read_samples((fs::path(dir) / shard.at("samples").at("file").get<std::string>()).string());
    }
  }
};

// The first data set fixes the columns and config; the others must agree.
void adopt_or_compare(LearningData& data, const json& manifest, const std::string& dir,
                      const char* network_inputs) {
  const json& columns = manifest.at("columns");
  const auto features = names_at(columns, "classifier_features", dir);
  const auto inputs = names_at(columns, network_inputs, dir);
  const auto targets = names_at(columns, "action_targets", dir);
  const auto gap_features = columns.value("gap_classifier_features", std::vector<std::string>{});
  const json& config = manifest.at("parameters").at("config");
  const std::string format = manifest.at("format").get<std::string>();
  if (data.datasets.empty()) {
    data.classifier_features = features;
    data.gap_classifier_features = gap_features;
    data.action_inputs = inputs;
    data.action_targets = targets;
    data.config = config;
    data.dataset_format = format;
    return;
  }
  if (features != data.classifier_features || gap_features != data.gap_classifier_features ||
      inputs != data.action_inputs || targets != data.action_targets ||
      format != data.dataset_format) {
    throw InputError("", dir + " has other columns or format than " + data.datasets[0].dir);
  }
  if (expert_data_config(config) != expert_data_config(data.config)) {
    throw InputError("", dir + " was made with another expert config than " + data.datasets[0].dir);
  }
}

}  // namespace

LearningData load_learning_data(const std::vector<std::string>& dirs, const char* network_inputs) {
  if (dirs.empty()) throw InputError("--data", "at least one data set is needed");
  LearningData data;
  Loader loader{data, {}, {}, {}, {}, {}, {}, {}};
  for (const std::string& dir : dirs) {
    const data::DatasetSummary summary = data::summarize_dataset(dir);  // checks checksums
    const json manifest = data::read_manifest(dir);
    try {
      adopt_or_compare(data, manifest, dir, network_inputs);
      loader.features.width = data.classifier_features.size();
      loader.inputs.width = data.action_inputs.size();
      loader.targets.width = data.action_targets.size();
      loader.plan_states.width = PlanNodeTable::columns().size();
      loader.gap_view.width = expert::gap_view_names().size();
      loader.gap_features.width = data.gap_classifier_features.size();
      loader.read_dataset(dir, manifest, static_cast<int>(data.datasets.size()));
    } catch (const json::exception& e) {
      throw InputError("", dir + "/manifest.json is malformed (" + e.what() + ")");
    }
    const bool labelled = manifest["parameters"].value("gap_labels", false);
    data.gap_labels = (data.datasets.empty() || data.gap_labels) && labelled;
    data.datasets.push_back({dir, run::file_crc32((fs::path(dir) / "manifest.json").string()),
                             summary.scenarios,
                             manifest["parameters"].value("seed", std::uint64_t{0})});
  }
  data.scenarios.features = loader.features.matrix();
  data.samples.inputs = loader.inputs.matrix();
  data.samples.targets = loader.targets.matrix();
  data.plan_nodes.states = loader.plan_states.matrix();
  data.plan_nodes.gap_view = loader.gap_view.matrix();
  data.scenarios.gap_features = loader.gap_features.matrix();
  return data;
}

const std::vector<std::string>& PlanNodeTable::columns() {
  static const std::vector<std::string> names = {
      "t",          "ego_a0",   "x",        "y",        "v",          "theta",
      "a",          "leader_x", "leader_v", "leader_a", "follower_x", "follower_v",
      "follower_a", "target_x", "target_v", "target_a"};
  return names;
}

Split split_scenarios(int n, double test_share, std::uint64_t seed) {
  if (!(test_share > 0.0 && test_share < 1.0)) {
    throw InputError("--test-share", "must lie strictly between 0 and 1");
  }
  std::vector<int> order(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  std::mt19937_64 rng(seed);
  seeded_shuffle(order, rng);
  const auto n_test = static_cast<std::size_t>(std::lround(test_share * n));
  Split split;
  split.test.assign(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n_test));
  split.train.assign(order.begin() + static_cast<std::ptrdiff_t>(n_test), order.end());
  std::sort(split.test.begin(), split.test.end());
  std::sort(split.train.begin(), split.train.end());
  if (split.test.empty() || split.train.empty()) {
    throw InputError("--test-share", "leaves one side of the split empty");
  }
  return split;
}

void seeded_shuffle(std::vector<int>& values, std::mt19937_64& rng) {
  for (std::size_t i = values.size(); i > 1; --i) {
    std::swap(values[i - 1], values[static_cast<std::size_t>(rng() % i)]);
  }
}

std::vector<char> mask_of(const std::vector<int>& rows, int n) {
  std::vector<char> mask(static_cast<std::size_t>(n), 0);
  for (int r : rows) mask[static_cast<std::size_t>(r)] = 1;
  return mask;
}

std::vector<int> sample_rows_of(const SampleTable& samples, const std::vector<char>& member) {
  std::vector<int> rows;
  for (int r = 0; r < samples.rows(); ++r) {
    if (member[static_cast<std::size_t>(samples.scenario[static_cast<std::size_t>(r)])]) {
      rows.push_back(r);
    }
  }
  return rows;
}

Eigen::MatrixXd classifier_inputs(const ScenarioTable& table, const std::vector<int>& rows,
                                  bool with_behavior) {
  const auto n = static_cast<Eigen::Index>(rows.size());
  const Eigen::Index f = table.features.cols();
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(n, f + (with_behavior ? kBehaviors : 0));
  for (Eigen::Index i = 0; i < n; ++i) {
    const int r = rows[static_cast<std::size_t>(i)];
    x.row(i).head(f) = table.features.row(r);
    if (with_behavior) x(i, f + table.behavior[static_cast<std::size_t>(r)]) = 1.0;
  }
  return x;
}

std::vector<std::string> classifier_input_names(const LearningData& data, bool with_behavior) {
  std::vector<std::string> names = data.classifier_features;
  if (with_behavior) {
    for (std::string_view b : kBehaviorNames) names.push_back("behavior_" + std::string(b));
  }
  return names;
}

}  // namespace lanechange::learn
