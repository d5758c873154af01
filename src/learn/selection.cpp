#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <random>
#include <thread>

#include "lanechange/learn/evaluation.hpp"
#include "lanechange/learn/learn_data.hpp"

namespace lanechange::learn {

namespace {

Eigen::MatrixXd rows_of(const Eigen::MatrixXd& x, const std::vector<int>& rows) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), x.cols());
  for (std::size_t i = 0; i < rows.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = x.row(rows[i]);
  return out;
}

std::vector<int> labels_of(const std::vector<int>& y, const std::vector<int>& rows) {
  std::vector<int> out;
  for (int r : rows) out.push_back(y[static_cast<std::size_t>(r)]);
  return out;
}

double fold_accuracy(ClassifierKind kind, const nlohmann::json& hyper, const Eigen::MatrixXd& x,
                     const std::vector<int>& y, const std::vector<std::vector<int>>& folds,
                     std::size_t held_out) {
  std::vector<int> train;
  for (std::size_t f = 0; f < folds.size(); ++f) {
    if (f != held_out) train.insert(train.end(), folds[f].begin(), folds[f].end());
  }
  auto model = make_classifier(kind, hyper);
  model->fit(rows_of(x, train), labels_of(y, train));
  const std::vector<int> truth = labels_of(y, folds[held_out]);
  const std::vector<int> predicted = model->predict(rows_of(x, folds[held_out]));
  long long right = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) right += truth[i] == predicted[i] ? 1 : 0;
  return static_cast<double>(right) / static_cast<double>(std::max<std::size_t>(truth.size(), 1));
}

}  // namespace

double CandidateScore::mean() const {
  double s = 0.0;
  for (double a : fold_accuracy) s += a;
  return fold_accuracy.empty() ? 0.0 : s / static_cast<double>(fold_accuracy.size());
}

double CandidateScore::sd() const {
  if (fold_accuracy.size() < 2) return 0.0;
  const double m = mean();
  double s = 0.0;
  for (double a : fold_accuracy) s += (a - m) * (a - m);
  return std::sqrt(s / static_cast<double>(fold_accuracy.size() - 1));
}

std::vector<std::vector<int>> make_folds(int n, int k, std::uint64_t seed) {
  std::vector<int> order(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  std::mt19937_64 rng(seed);
  seeded_shuffle(order, rng);
  std::vector<std::vector<int>> folds(static_cast<std::size_t>(std::max(k, 1)));
  for (std::size_t i = 0; i < order.size(); ++i) folds[i % folds.size()].push_back(order[i]);
  return folds;
}

void parallel_for(int n, int jobs, const std::function<void(int)>& task) {
  const int threads = std::max(
      1,
      std::min(n, jobs > 0 ? jobs
                           : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))));
  std::atomic<int> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto work = [&] {
    for (int i = next++; i < n; i = next++) {
      try {
        task(i);
      } catch (...) {
        const std::lock_guard lock(failure_mutex);
        if (!failure) failure = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

Selection select_hyperparameters(ClassifierKind kind, const Eigen::MatrixXd& x,
                                 const std::vector<int>& y, const SearchSettings& settings,
                                 std::uint64_t seed, int jobs) {
  const auto folds = make_folds(static_cast<int>(y.size()), settings.folds, seed);
  Selection s;
  for (const auto& hyper : hyperparameter_grid(kind, settings)) {
    s.candidates.push_back({hyper, std::vector<double>(folds.size(), 0.0)});
  }
  const int n_folds = static_cast<int>(folds.size());
  parallel_for(static_cast<int>(s.candidates.size()) * n_folds, jobs, [&](int task) {
    auto& candidate = s.candidates[static_cast<std::size_t>(task / n_folds)];
    const auto fold = static_cast<std::size_t>(task % n_folds);
    candidate.fold_accuracy[fold] = fold_accuracy(kind, candidate.hyper, x, y, folds, fold);
  });
  for (std::size_t i = 1; i < s.candidates.size(); ++i) {
    if (s.candidates[i].mean() > s.candidates[s.best].mean()) s.best = i;
  }
  return s;
}

}  // namespace lanechange::learn
