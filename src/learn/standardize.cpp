#include "lanechange/learn/classifier.hpp"

namespace lanechange::learn {

Standardizer Standardizer::fit(const Eigen::MatrixXd& x) {
  Standardizer s;
  s.mean = x.colwise().mean().transpose();
  const auto n = static_cast<double>(std::max<Eigen::Index>(x.rows() - 1, 1));
  s.scale =
      ((x.rowwise() - s.mean.transpose()).array().square().colwise().sum() / n).sqrt().transpose();
  for (Eigen::Index i = 0; i < s.scale.size(); ++i) {
    if (!(s.scale(i) > 1e-12)) s.scale(i) = 1.0;
  }
  return s;
}

Eigen::MatrixXd Standardizer::apply(const Eigen::MatrixXd& x) const {
  return (x.rowwise() - mean.transpose()).array().rowwise() / scale.transpose().array();
}

nlohmann::json Standardizer::to_json() const {
  return {{"mean", std::vector<double>(mean.begin(), mean.end())},
          {"scale", std::vector<double>(scale.begin(), scale.end())}};
}

Standardizer Standardizer::from_json(const nlohmann::json& j) {
  const auto m = j.at("mean").get<std::vector<double>>();
  const auto s = j.at("scale").get<std::vector<double>>();
  Standardizer out;
  out.mean = Eigen::Map<const Eigen::VectorXd>(m.data(), static_cast<Eigen::Index>(m.size()));
  out.scale = Eigen::Map<const Eigen::VectorXd>(s.data(), static_cast<Eigen::Index>(s.size()));
  return out;
}

}  // namespace lanechange::learn
