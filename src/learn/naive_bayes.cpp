#include "lanechange/learn/naive_bayes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "lanechange/error.hpp"

namespace lanechange::learn {

namespace {

constexpr double kReach = 8.0;  // kernels beyond kReach h are negligible (exp(-32))
constexpr double kMinBandwidth = 1e-6;
const double kLogSqrt2Pi = 0.5 * std::log(2.0 * std::numbers::pi);
constexpr double kMinusInf = -std::numeric_limits<double>::infinity();

double log_normal(double x, double mean, double sd) {
  const double z = (x - mean) / sd;
  return -0.5 * z * z - std::log(sd) - kLogSqrt2Pi;
}

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double sd_of(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = mean_of(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

std::vector<double> column_of_class(const Eigen::MatrixXd& x, const std::vector<int>& y, int c,
                                    Eigen::Index f) {
  std::vector<double> out;
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    if (y[static_cast<std::size_t>(r)] == c) out.push_back(x(r, f));
  }
  return out;
}

}  // namespace

KernelDensity::KernelDensity(std::vector<double> samples, double bandwidth)
    : samples_(std::move(samples)), h_(bandwidth) {
  if (samples_.empty() || !(h_ > 0.0)) {
    throw InputError("", "a kernel density needs samples and a positive bandwidth");
  }
  std::sort(samples_.begin(), samples_.end());
}

double KernelDensity::log_density(double x) const {
  auto lo = std::lower_bound(samples_.begin(), samples_.end(), x - kReach * h_);
  auto hi = std::upper_bound(lo, samples_.end(), x + kReach * h_);
  if (lo == hi) {  // no kernel within reach: the nearest one dominates
    const auto right = std::lower_bound(samples_.begin(), samples_.end(), x);
    lo = (right == samples_.end() || (right != samples_.begin() && x - *(right - 1) < *right - x))
             ? right - 1
             : right;
    hi = lo + 1;
  }
  // log-sum-exp around the largest term (the nearest kernel) keeps far
  // points from underflowing to log 0.
  double best = kMinusInf;
  for (auto it = lo; it != hi; ++it) best = std::max(best, -0.5 * std::pow((x - *it) / h_, 2));
  double sum = 0.0;
  for (auto it = lo; it != hi; ++it) sum += std::exp(-0.5 * std::pow((x - *it) / h_, 2) - best);
  return best + std::log(sum) - std::log(static_cast<double>(samples_.size()) * h_) - kLogSqrt2Pi;
}

double silverman_bandwidth(std::vector<double> samples) {
  if (samples.size() < 2) return 1.0;
  std::sort(samples.begin(), samples.end());
  const auto quantile = [&](double q) {
    return samples[static_cast<std::size_t>(q * static_cast<double>(samples.size() - 1))];
  };
  const double iqr = quantile(0.75) - quantile(0.25);
  double spread = sd_of(samples);
  if (iqr > 0.0) spread = std::min(spread, iqr / 1.34);
  const double h = 0.9 * spread * std::pow(static_cast<double>(samples.size()), -0.2);
  return std::max(h, kMinBandwidth);
}

void NaiveBayes::fit(const Eigen::MatrixXd& x, const std::vector<int>& y, int classes) {
  const Eigen::Index features = x.cols();
  log_prior_ = Eigen::VectorXd::Constant(classes, kMinusInf);
  density_.assign(static_cast<std::size_t>(classes), {});
  mean_ = Eigen::MatrixXd::Zero(classes, features);
  sd_ = Eigen::MatrixXd::Ones(classes, features);
  for (int c = 0; c < classes; ++c) {
    const auto n = std::count(y.begin(), y.end(), c);
    if (n == 0) continue;  // an absent class is never predicted
    log_prior_(c) = std::log(static_cast<double>(n) / static_cast<double>(y.size()));
    for (Eigen::Index f = 0; f < features; ++f) {
      std::vector<double> v = column_of_class(x, y, c, f);
      mean_(c, f) = mean_of(v);
      sd_(c, f) = std::max(sd_of(v), kMinBandwidth);
      if (settings_.kernel) {
        const double h = settings_.bandwidth_scale * silverman_bandwidth(v);
        density_[static_cast<std::size_t>(c)].emplace_back(std::move(v), h);
      }
    }
  }
}

Eigen::VectorXd NaiveBayes::log_posterior(const Eigen::RowVectorXd& x) const {
  Eigen::VectorXd out = log_prior_;
  for (Eigen::Index c = 0; c < out.size(); ++c) {
    if (!std::isfinite(out(c))) continue;
    for (Eigen::Index f = 0; f < x.size(); ++f) {
      out(c) +=
          settings_.kernel
              ? density_[static_cast<std::size_t>(c)][static_cast<std::size_t>(f)].log_density(x(f))
              : log_normal(x(f), mean_(c, f), sd_(c, f));
    }
  }
  return out;
}

int NaiveBayes::predict(const Eigen::RowVectorXd& x) const {
  Eigen::Index best = 0;
  log_posterior(x).maxCoeff(&best);
  return static_cast<int>(best);
}

nlohmann::json NaiveBayes::to_json() const {
  nlohmann::json j = {{"kernel", settings_.kernel},
                      {"bandwidth_scale", settings_.bandwidth_scale},
                      {"log_prior", std::vector<double>(log_prior_.begin(), log_prior_.end())}};
  // -inf is not JSON: an absent class is written as null.
  for (auto& p : j["log_prior"]) {
    if (!std::isfinite(p.get<double>())) p = nullptr;
  }
  for (Eigen::Index c = 0; c < log_prior_.size(); ++c) {
    nlohmann::json cls = nlohmann::json::array();
    for (Eigen::Index f = 0; f < mean_.cols(); ++f) {
      nlohmann::json feature = {{"mean", mean_(c, f)}, {"sd", sd_(c, f)}};
      if (settings_.kernel && !density_[static_cast<std::size_t>(c)].empty()) {
        const KernelDensity& d = density_[static_cast<std::size_t>(c)][static_cast<std::size_t>(f)];
        feature["bandwidth"] = d.bandwidth();
        feature["samples"] = d.samples();
      }
      cls.push_back(feature);
    }
    j["classes"].push_back(cls);
  }
  return j;
}

NaiveBayes NaiveBayes::from_json(const nlohmann::json& j) {
  NaiveBayes nb({j.at("kernel").get<bool>(), j.at("bandwidth_scale").get<double>()});
  const auto& priors = j.at("log_prior");
  const auto classes = static_cast<Eigen::Index>(priors.size());
  const auto features = static_cast<Eigen::Index>(j.at("classes").at(0).size());
  nb.log_prior_.resize(classes);
  nb.mean_.resize(classes, features);
  nb.sd_.resize(classes, features);
  nb.density_.assign(static_cast<std::size_t>(classes), {});
  for (Eigen::Index c = 0; c < classes; ++c) {
    const auto& p = priors.at(static_cast<std::size_t>(c));
    nb.log_prior_(c) = p.is_null() ? kMinusInf : p.get<double>();
    for (Eigen::Index f = 0; f < features; ++f) {
      const auto& feature =
          j.at("classes").at(static_cast<std::size_t>(c)).at(static_cast<std::size_t>(f));
      nb.mean_(c, f) = feature.at("mean").get<double>();
      nb.sd_(c, f) = feature.at("sd").get<double>();
      if (nb.settings_.kernel && !p.is_null()) {
        nb.density_[static_cast<std::size_t>(c)].emplace_back(
            feature.at("samples").get<std::vector<double>>(),
            feature.at("bandwidth").get<double>());
      }
    }
  }
  return nb;
}

}  // namespace lanechange::learn
