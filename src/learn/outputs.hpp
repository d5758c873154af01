#pragma once
// The human-facing files of a model directory: confusion matrices and loss
// curves as CSV and PNG, and report.md with every table of metrics.json.
#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lanechange/learn/network.hpp"

namespace lanechange::learn::detail {

/// Row-normalised confusion matrix as CSV (true class per row).
void write_confusion_csv(const Eigen::MatrixXd& normalised, const std::string& path);
/// The same as a heat map with percentages, like the paper's Fig. 3.
void plot_confusion(const Eigen::MatrixXd& normalised, const std::string& title,
                    const std::string& png_path);
void write_loss_csv(const std::vector<LossPoint>& curve, const std::string& path);
void plot_loss(const std::vector<LossPoint>& curve, int best_epoch, const std::string& png_path);
/// Markdown tables of metrics.json.
[[nodiscard]] std::string report_markdown(const nlohmann::json& metrics);

}  // namespace lanechange::learn::detail
