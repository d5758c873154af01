#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "lanechange/learn/naive_bayes.hpp"

namespace lanechange::learn {
namespace {

double normal_pdf(double x, double mean, double sd) {
  const double z = (x - mean) / sd;
  return std::exp(-0.5 * z * z) / (sd * std::sqrt(2.0 * std::numbers::pi));
}

TEST(KernelDensity, OneSampleIsTheNormalDensityOfTheBandwidth) {
  const KernelDensity d({1.5}, 0.7);
  for (double x : {-3.0, 0.0, 1.5, 2.2, 6.0}) {
    EXPECT_NEAR(std::exp(d.log_density(x)), normal_pdf(x, 1.5, 0.7), 1e-12) << x;
  }
}

TEST(KernelDensity, TwoSamplesAverageTheirKernels) {
  const KernelDensity d({-1.0, 2.0}, 0.5);
  for (double x : {-1.0, 0.3, 2.0}) {
    const double want = 0.5 * (normal_pdf(x, -1.0, 0.5) + normal_pdf(x, 2.0, 0.5));
    EXPECT_NEAR(std::exp(d.log_density(x)), want, 1e-12) << x;
  }
}

TEST(KernelDensity, FarPointsKeepAFiniteLogDensity) {
  const KernelDensity d({0.0, 0.1}, 0.01);
  const double far = d.log_density(50.0);
  EXPECT_TRUE(std::isfinite(far));
  // Only the nearest kernel (at 0.1) counts: log(phi(49.9/0.01)/(2*0.01)).
  const double z = 49.9 / 0.01;
  EXPECT_NEAR(far, -0.5 * z * z - std::log(2 * 0.01) - 0.5 * std::log(2 * std::numbers::pi), 1e-6);
}

TEST(KernelDensity, EstimatesAStandardNormalFromItsSamples) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> s(4000);
  for (double& v : s) v = normal(rng);
  const double h = silverman_bandwidth(s);
  EXPECT_NEAR(h, 0.9 * std::pow(4000.0, -0.2), 0.03);  // sd 1, IQR/1.34 about 1
  const KernelDensity d(s, h);
  for (double x : {-2.0, -1.0, 0.0, 0.5, 1.5}) {
    EXPECT_NEAR(std::exp(d.log_density(x)), normal_pdf(x, 0.0, 1.0), 0.02) << x;
  }
}

Eigen::MatrixXd two_blobs(std::vector<int>& y, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd x(n, 2);
  y.assign(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    const int c = i % 2;
    y[static_cast<std::size_t>(i)] = c;
    // Class 0 sits tightly at -3 and +3, class 1 spreads over both with the
    // same mean and about the same spread: one normal per class and feature
    // cannot tell them apart, kernel densities can.
    x(i, 0) = c == 0 ? (i % 4 == 0 ? -3.0 : 3.0) + 0.3 * normal(rng) : 3.0 * normal(rng);
    x(i, 1) = normal(rng);
  }
  return x;
}

double accuracy(const NaiveBayes& nb, const Eigen::MatrixXd& x, const std::vector<int>& y) {
  int right = 0;
  for (Eigen::Index r = 0; r < x.rows(); ++r)
    right += nb.predict(x.row(r)) == y[static_cast<std::size_t>(r)];
  return static_cast<double>(right) / static_cast<double>(x.rows());
}

TEST(NaiveBayes, KernelDensitiesSeparateABimodalClassThePlainOneCannot) {
  std::vector<int> y, y_test;
  const Eigen::MatrixXd x = two_blobs(y, 600, 1), x_test = two_blobs(y_test, 400, 2);
  NaiveBayes kernel({true, 1.0}), plain({false, 1.0});
  kernel.fit(x, y, 3);
  plain.fit(x, y, 3);
  const double with_kernels = accuracy(kernel, x_test, y_test);
  EXPECT_GT(with_kernels, 0.75);
  EXPECT_GT(with_kernels, accuracy(plain, x_test, y_test) + 0.15);
  // The absent third class is never chosen.
  EXPECT_FALSE(std::isfinite(kernel.log_posterior(x_test.row(0))(2)));
}

TEST(NaiveBayes, JsonRoundTripKeepsThePosteriors) {
  std::vector<int> y;
  const Eigen::MatrixXd x = two_blobs(y, 200, 5);
  NaiveBayes nb({true, 0.5});
  nb.fit(x, y, 3);
  const NaiveBayes back = NaiveBayes::from_json(nlohmann::json::parse(nb.to_json().dump()));
  for (Eigen::Index r = 0; r < 20; ++r) {
    EXPECT_NEAR(back.log_posterior(x.row(r))(0), nb.log_posterior(x.row(r))(0), 1e-12);
    EXPECT_NEAR(back.log_posterior(x.row(r))(1), nb.log_posterior(x.row(r))(1), 1e-12);
  }
}

}  // namespace
}  // namespace lanechange::learn
