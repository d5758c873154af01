#pragma once
// `lanechange train`: one call reads the data sets, splits them by scenario,
// trains and scores the five classifiers (with and without the behavior
// input) and the action network, and writes the model directory.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "lanechange/learn/classifier.hpp"
#include "lanechange/learn/network.hpp"
#include "lanechange/learn/strategy.hpp"

namespace lanechange::learn {

struct TrainOptions {
  std::vector<std::string> data_dirs;
  std::string out_dir;
  std::uint64_t seed = 1;
  double test_share = 0.2;  ///< the paper's 1000 of 5000
  int jobs = 0;             ///< threads for cross-validation; 0: one per core
  SearchSettings search;
  NetworkSettings network;  ///< its seed is derived from `seed`
  StrategySettings strategy;
  bool plots = true;  ///< PNGs (needs gnuplot)
  std::ostream* progress = nullptr;
  /// The settings that shape the models (recorded in model.json).
  [[nodiscard]] nlohmann::json config() const;
};

struct TrainReport {
  nlohmann::json metrics;  ///< what metrics.json holds
  double wall_s = 0.0;
};

/// Trains everything and writes out_dir atomically (a new directory is
/// swapped in only when complete). InputError for bad options or data, or an
/// out_dir that exists and is not a model; an existing model is replaced
/// only by a complete new one.
TrainReport train_models(const TrainOptions& options);

/// A new action network for an existing model (DAgger, docs/strategy.md):
/// the base model's other parts (classifiers, strategy model, split) are
/// kept; the network is trained afresh, with the base model's seed, on the
/// well-posed plans of every data set given. Rows of the data sets the base
/// was trained on keep its train/test split and, by default, its validation
/// rows (early stopping); rows of any other data set all train. The data
/// sets must share the base model's expert config.
// The implicit noexcept move sees nlohmann::json's invariant check
// (JSON_ASSERT) as a possible throw.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct RetrainOptions {
  std::string base_model;
  std::vector<std::string> data_dirs;
  std::string out_dir;  ///< written atomically, as train_models does
  NetworkSettings network;
  /// Draw validation rows from the other data sets too (DAgger's first
  /// version): their rows then stop the training early, unlike the base's.
  bool validate_on_added = false;
  /// A model directory whose network the retrain starts from, keeping its
  /// standardizers (DAgger's rounds fine-tune the last round's network);
  /// empty: fresh weights and standardizers fitted on all training rows.
  std::string warm_start;
  /// A model directory whose policy's networks (one, or the several it
  /// averages) the new network joins: the published policy is the mean
  /// action of them all (DAgger's --dagger-average); empty: the new network
  /// alone. network.dlib stays the new network.
  std::string average_with;
  /// Offset added to the network's seed (its initial weights, or a
  /// fine-tune's batch order); the splits stay the base's. 0: the base's own.
  std::uint64_t network_seed_offset = 0;
  bool plots = true;
  std::ostream* progress = nullptr;
  nlohmann::json note;  ///< recorded in model.json ("retrained_network")
};

/// InputError for a missing or damaged base model or data set, data of
/// another expert config, or an out_dir that is not a model.
TrainReport retrain_network(const RetrainOptions& options);

}  // namespace lanechange::learn
