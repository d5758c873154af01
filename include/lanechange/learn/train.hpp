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

}  // namespace lanechange::learn
