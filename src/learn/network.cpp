// The only file that includes dlib: its dnn headers are slow to compile and
// stay out of every other translation unit.
#include "lanechange/learn/network.hpp"

#include <dlib/dnn.h>

#include <chrono>
#include <cstdlib>
#include <mutex>
#include <random>

#include "lanechange/error.hpp"
#include "lanechange/learn/learn_data.hpp"

namespace lanechange::learn {

namespace {

template <class Sub>
using Tanh10 = dlib::htan<dlib::fc<kHiddenWidth, Sub>>;
using Net = dlib::loss_mean_squared_multioutput<
    dlib::fc<kActions, Tanh10<Tanh10<Tanh10<Tanh10<Tanh10<Tanh10<
                           Tanh10<Tanh10<Tanh10<Tanh10<dlib::input<dlib::matrix<float>>>>>>>>>>>>>>;
static_assert(kHiddenLayers == 10, "Net spells out ten hidden layers");

template <class T>
struct IsFc : std::false_type {};
template <unsigned long N, dlib::fc_bias_mode B>
struct IsFc<dlib::fc_<N, B>> : std::true_type {};

// The hidden layers' width: their fc layers in the net's own order, the
// output layer (visited first) left out.
template <class Visit>
void visit_hidden_fc(Net& net, Visit visit) {
  bool output_layer = true;
  dlib::visit_computational_layers(net, [&](auto& layer) {
    if constexpr (IsFc<std::decay_t<decltype(layer)>>::value) {
      if (!output_layer) visit(layer);
      output_layer = false;
    }
  });
}

// Before the net's first forward pass, which allocates its parameters.
void set_hidden_width(Net& net, int width) {
  if (width < 1 || width > kMaxHiddenWidth) {
    throw InputError("network width",
                     std::to_string(width) + " is not in 1.." + std::to_string(kMaxHiddenWidth));
  }
  visit_hidden_fc(net, [&](auto& fc) { fc.set_num_outputs(width); });
}

int hidden_width_of(Net& net) {
  long width = 0;
  visit_hidden_fc(net, [&](auto& fc) { width = static_cast<long>(fc.get_num_outputs()); });
  return static_cast<int>(width);
}

dlib::matrix<float> row_of(const Eigen::MatrixXd& x, Eigen::Index r) {
  dlib::matrix<float> m(static_cast<long>(x.cols()), 1);
  for (Eigen::Index c = 0; c < x.cols(); ++c) m(static_cast<long>(c)) = static_cast<float>(x(r, c));
  return m;
}

std::vector<dlib::matrix<float>> rows_of(const Eigen::MatrixXd& x, const std::vector<int>& rows) {
  std::vector<dlib::matrix<float>> out;
  out.reserve(rows.size());
  for (int r : rows) out.push_back(row_of(x, r));
  return out;
}

// Our own mean squared error over all outputs: dlib's average loss is a
// running sum over the outputs (deps.md).
double mse(Net& net, const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
           const std::vector<int>& rows) {
  if (rows.empty()) return 0.0;
  const auto out = net(rows_of(x, rows), 1024);
  double sum = 0.0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (Eigen::Index c = 0; c < y.cols(); ++c) {
      const double e = out[i](static_cast<long>(c)) - y(rows[i], c);
      sum += e * e;
    }
  }
  return sum / static_cast<double>(rows.size() * static_cast<std::size_t>(y.cols()));
}

}  // namespace

struct TrainedNetwork::Impl {
  Net net;
};

TrainedNetwork::TrainedNetwork() : impl(std::make_unique<Impl>()) {}
TrainedNetwork::~TrainedNetwork() = default;
TrainedNetwork::TrainedNetwork(TrainedNetwork&&) noexcept = default;
TrainedNetwork& TrainedNetwork::operator=(TrainedNetwork&&) noexcept = default;

double TrainedNetwork::seconds_per_epoch() const {
  return curve.empty() ? 0.0 : train_s / static_cast<double>(curve.size());
}

Eigen::MatrixXd TrainedNetwork::forward(const Eigen::MatrixXd& x) const {
  std::vector<int> rows(static_cast<std::size_t>(x.rows()));
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<int>(i);
  const auto out = impl->net(rows_of(x, rows), 1024);
  Eigen::MatrixXd y(x.rows(), kActions);
  for (std::size_t i = 0; i < out.size(); ++i) {
    for (int c = 0; c < kActions; ++c) y(static_cast<Eigen::Index>(i), c) = out[i](c);
  }
  return y;
}

void TrainedNetwork::export_layers(std::vector<Eigen::MatrixXf>& weights,
                                   std::vector<Eigen::VectorXf>& biases) const {
  weights.clear();
  biases.clear();
  // dlib stores W as inputs x outputs, row-major: read as outputs x inputs
  // column-major, it is the matrix that multiplies the input column.
  dlib::visit_computational_layers(impl->net, [&](const auto& layer) {
    if constexpr (IsFc<std::decay_t<decltype(layer)>>::value) {
      // The alias instances own the views: keep them alive while reading.
      const auto w_alias = layer.get_weights();
      const auto b_alias = layer.get_biases();
      const dlib::tensor& w = w_alias.get();
      const dlib::tensor& b = b_alias.get();
      const auto outputs = static_cast<Eigen::Index>(b.size());
      weights.push_back(Eigen::Map<const Eigen::MatrixXf>(
          w.host(), outputs, static_cast<Eigen::Index>(w.size()) / outputs));
      biases.push_back(Eigen::Map<const Eigen::VectorXf>(b.host(), outputs));
    }
  });
  // The visit runs from the output layer down.
  std::reverse(weights.begin(), weights.end());
  std::reverse(biases.begin(), biases.end());
}

void TrainedNetwork::save(const std::string& path) const { dlib::serialize(path) << impl->net; }

std::string_view to_string(NetworkInputs inputs) {
  return inputs == NetworkInputs::Gap ? "gap" : "paper";
}

const char* manifest_key(NetworkInputs inputs) {
  return inputs == NetworkInputs::Gap ? "gap_action_inputs" : "action_inputs";
}

std::uint64_t member_seed(std::uint64_t seed, int member) {
  // Far apart, so that the seed offsets of DAgger's candidates (0, 1, ...) never
  // give two networks of different members the same seed.
  constexpr std::uint64_t kMemberStride = 1'000'003;
  return seed + kMemberStride * static_cast<std::uint64_t>(member);
}

TrainedNetwork train_network(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                             const std::vector<int>& train, const std::vector<int>& validation,
                             const NetworkSettings& s, std::ostream* progress,
                             const std::string& warm_start) {
  const auto start = std::chrono::steady_clock::now();
  TrainedNetwork result;
  Net net;
  if (warm_start.empty()) {
    set_hidden_width(net, s.hidden_width);
    // dlib draws its initial weights from std::rand when a layer is set up;
    // seeding it and setting up here (one forward pass) makes runs repeatable.
    // std::rand's state is global: an ensemble's networks train on several
    // threads, and each must draw its own seed's sequence whole.
    static std::mutex rand_mutex;
    const std::lock_guard lock(rand_mutex);
    std::srand(static_cast<unsigned>(s.seed));
    (void)net(row_of(x, 0));
  } else {
    try {
      dlib::deserialize(warm_start) >> net;
    } catch (const dlib::serialization_error& e) {
      throw InputError(warm_start, std::string("not a network of this model's shape: ") + e.what());
    }
    if (const int width = hidden_width_of(net); width != s.hidden_width) {
      throw InputError(warm_start, "a network " + std::to_string(width) + " wide, not " +
                                       std::to_string(s.hidden_width));
    }
  }
  dlib::dnn_trainer<Net, dlib::adam> trainer(net, dlib::adam(0.0, 0.9, 0.999));
  trainer.set_learning_rate(s.learning_rate);
  trainer.set_learning_rate_shrink_factor(1.0);  // our early stopping decides instead
  trainer.set_mini_batch_size(static_cast<unsigned long>(s.batch_size));

  std::mt19937_64 rng(s.seed);
  std::vector<int> order = train;
  double best = std::numeric_limits<double>::infinity();
  for (int epoch = 1; epoch <= s.max_epochs && epoch - result.best_epoch <= s.patience; ++epoch) {
    seeded_shuffle(order, rng);
    for (std::size_t begin = 0; begin < order.size();
         begin += static_cast<std::size_t>(s.batch_size)) {
      const std::vector<int> batch(
          order.begin() + static_cast<std::ptrdiff_t>(begin),
          order.begin() + static_cast<std::ptrdiff_t>(std::min(
                              order.size(), begin + static_cast<std::size_t>(s.batch_size))));
      std::vector<dlib::matrix<float>> targets;
      for (int r : batch) {
        dlib::matrix<float> t(kActions, 1);
        for (int c = 0; c < kActions; ++c) t(c) = static_cast<float>(y(r, c));
        targets.push_back(t);
      }
      trainer.train_one_step(rows_of(x, batch), targets);
    }
    Net& current = trainer.get_net();  // waits for the trainer's thread
    const LossPoint point{epoch, mse(current, x, y, train), mse(current, x, y, validation)};
    result.curve.push_back(point);
    if (point.validation_mse < best) {
      best = point.validation_mse;
      result.best_epoch = epoch;
      result.impl->net = current;
    }
    if (progress != nullptr && (epoch % 10 == 0 || epoch == 1)) {
      *progress << "  network epoch " << epoch << ": train mse " << point.train_mse
                << ", validation mse " << point.validation_mse << "\n";
    }
  }
  result.impl->net.clean();
  result.train_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace lanechange::learn
