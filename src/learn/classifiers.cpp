// The Table I classifiers over their libraries. OpenCV and libsvm take
// single-precision rows and C arrays; the conversions live here only.
#include <svm.h>

#include <algorithm>
#include <fstream>
#include <opencv2/ml.hpp>

#include "common/json_fields.hpp"
#include "lanechange/error.hpp"
#include "lanechange/learn/classifier.hpp"
#include "lanechange/learn/learn_data.hpp"
#include "lanechange/learn/naive_bayes.hpp"

namespace lanechange::learn {

namespace {

using nlohmann::json;

constexpr std::uint64_t kOpenCvSeed = 0x5eed;

cv::Mat to_cv(const Eigen::MatrixXd& x) {
  cv::Mat m(static_cast<int>(x.rows()), static_cast<int>(x.cols()), CV_32F);
  for (int r = 0; r < m.rows; ++r) {
    for (int c = 0; c < m.cols; ++c) m.at<float>(r, c) = static_cast<float>(x(r, c));
  }
  return m;
}

cv::Ptr<cv::ml::TrainData> train_data(const Eigen::MatrixXd& x, const std::vector<int>& y) {
  // Integer responses make OpenCV treat the task as classification.
  cv::Mat labels(static_cast<int>(y.size()), 1, CV_32S);
  for (int r = 0; r < labels.rows; ++r) labels.at<int>(r) = y[static_cast<std::size_t>(r)];
  return cv::ml::TrainData::create(to_cv(x), cv::ml::ROW_SAMPLE, labels);
}

std::vector<int> labels_of(const cv::Mat& predictions) {
  std::vector<int> out(static_cast<std::size_t>(predictions.rows));
  for (int r = 0; r < predictions.rows; ++r) {
    out[static_cast<std::size_t>(r)] = static_cast<int>(std::lround(predictions.at<float>(r)));
  }
  return out;
}

void require_trained(bool trained, const char* what) {
  if (!trained) throw std::runtime_error(std::string(what) + " failed to train");
}

// Decision tree and random forest share OpenCV's tree settings.
template <class Model>
void set_tree(Model& m, const json& hyper) {
  m.setMaxDepth(hyper.value("max_depth", 10));
  m.setMinSampleCount(hyper.value("min_samples", 5));
  m.setCVFolds(0);  // OpenCV's own pruning CV segfaults (deps.md); ours chooses the depth
  m.setUseSurrogates(false);
  m.setMaxCategories(kClasses);
}

template <class Model>
class OpenCvClassifier : public Classifier {
 public:
  explicit OpenCvClassifier(cv::Ptr<Model> model) : model_(std::move(model)) {}
  void fit(const Eigen::MatrixXd& x, const std::vector<int>& y) override {
    // RTrees draws its bootstrap samples and feature subsets from the
    // calling thread's cv::theRNG(), whose state depends on what that thread
    // ran before: reseeding it makes every fit repeatable.
    cv::theRNG() = cv::RNG(kOpenCvSeed);
    require_trained(model_->train(train_data(x, y)), "an OpenCV model");
  }
  [[nodiscard]] std::vector<int> predict(const Eigen::MatrixXd& x) const override {
    cv::Mat out;
    model_->predict(to_cv(x), out);
    return labels_of(out);
  }
  void save(const std::string& path) const override { model_->save(path); }
  void load(const std::string& path) override {
    try {
      model_ = Model::load(path);
    } catch (const cv::Exception& e) {
      throw InputError("", path + " is not a readable model (" + e.what() + ")");
    }
    if (model_.empty() || !model_->isTrained()) throw InputError("", path + " holds no model");
  }

 protected:
  cv::Ptr<Model> model_;
};

class KnnClassifier : public OpenCvClassifier<cv::ml::KNearest> {
 public:
  explicit KnnClassifier(int k) : OpenCvClassifier(cv::ml::KNearest::create()), k_(k) {
    model_->setDefaultK(k);
    model_->setIsClassifier(true);
  }
  [[nodiscard]] std::vector<int> predict(const Eigen::MatrixXd& x) const override {
    cv::Mat out;
    model_->findNearest(to_cv(x), k_, out);
    return labels_of(out);
  }

 private:
  int k_;
};

void quiet_libsvm(const char*) {}

// libsvm keeps pointers into the training rows, so they live as long as the model.
class SvmClassifier : public Classifier {
 public:
  explicit SvmClassifier(const json& hyper) : hyper_(hyper) {}
  ~SvmClassifier() override { release(); }
  SvmClassifier(const SvmClassifier&) = delete;
  SvmClassifier& operator=(const SvmClassifier&) = delete;

  void fit(const Eigen::MatrixXd& x, const std::vector<int>& y) override {
    release();
    svm_set_print_string_function(&quiet_libsvm);
    rows_ = nodes_of(x);
    labels_.assign(y.begin(), y.end());
    pointers_.clear();
    for (auto& row : rows_) pointers_.push_back(row.data());
    svm_problem problem{static_cast<int>(y.size()), labels_.data(), pointers_.data()};
    svm_parameter p = parameters(static_cast<int>(x.cols()));
    if (const char* bad = svm_check_parameter(&problem, &p)) throw std::runtime_error(bad);
    model_ = svm_train(&problem, &p);
  }
  [[nodiscard]] std::vector<int> predict(const Eigen::MatrixXd& x) const override {
    std::vector<int> out;
    for (const auto& row : nodes_of(x)) {
      out.push_back(static_cast<int>(std::lround(svm_predict(model_, row.data()))));
    }
    return out;
  }
  void save(const std::string& path) const override {
    if (svm_save_model(path.c_str(), model_) != 0) {
      throw std::runtime_error("cannot write " + path);
    }
  }
  void load(const std::string& path) override {
    release();
    model_ = svm_load_model(path.c_str());
    if (model_ == nullptr) throw InputError("", path + " is not a readable libsvm model");
  }

 private:
  svm_parameter parameters(int features) const {
    svm_parameter p{};
    p.svm_type = C_SVC;
    p.kernel_type = POLY;
    p.degree = 3;
    // (gamma u'v + 1)^3: the constant keeps the lower orders, as MATLAB's
    // polynomial kernel does.
    p.gamma = hyper_.value("gamma_factor", 1.0) / features;
    p.coef0 = 1.0;
    p.C = hyper_.value("C", 1.0);
    p.cache_size = 200;
    p.eps = 1e-3;
    p.shrinking = 1;
    return p;
  }
  static std::vector<std::vector<svm_node>> nodes_of(const Eigen::MatrixXd& x) {
    std::vector<std::vector<svm_node>> rows(static_cast<std::size_t>(x.rows()));
    for (Eigen::Index r = 0; r < x.rows(); ++r) {
      auto& row = rows[static_cast<std::size_t>(r)];
      for (Eigen::Index c = 0; c < x.cols(); ++c) {
        row.push_back({static_cast<int>(c + 1), x(r, c)});
      }
      row.push_back({-1, 0.0});
    }
    return rows;
  }
  void release() {
    if (model_ != nullptr) svm_free_and_destroy_model(&model_);
    model_ = nullptr;
  }

  json hyper_;
  svm_model* model_ = nullptr;
  std::vector<std::vector<svm_node>> rows_;
  std::vector<svm_node*> pointers_;
  std::vector<double> labels_;
};

class NaiveBayesClassifier : public Classifier {
 public:
  explicit NaiveBayesClassifier(const json& hyper)
      : model_({hyper.value("kernel", true), hyper.value("bandwidth_scale", 1.0)}) {}
  void fit(const Eigen::MatrixXd& x, const std::vector<int>& y) override {
    // The labels are 0..kClasses-1, or a gap classifier's 0..kGapClasses-1.
    const int top = y.empty() ? 0 : *std::max_element(y.begin(), y.end());
    model_.fit(x, y, std::max(kClasses, top + 1));
  }
  [[nodiscard]] std::vector<int> predict(const Eigen::MatrixXd& x) const override {
    std::vector<int> out;
    for (Eigen::Index r = 0; r < x.rows(); ++r) out.push_back(model_.predict(x.row(r)));
    return out;
  }
  void save(const std::string& path) const override {
    lanechange::detail::write_file_atomically(path, model_.to_json().dump());
  }
  void load(const std::string& path) override {
    try {
      model_ = NaiveBayes::from_json(lanechange::detail::read_json_file(path));
    } catch (const json::exception& e) {
      throw InputError("", path + " is not a naive Bayes model (" + e.what() + ")");
    }
  }

 private:
  NaiveBayes model_;
};

std::unique_ptr<Classifier> make_tree(const json& hyper) {
  auto model = cv::ml::DTrees::create();
  set_tree(*model, hyper);
  return std::make_unique<OpenCvClassifier<cv::ml::DTrees>>(model);
}

std::unique_ptr<Classifier> make_forest(const json& hyper) {
  auto model = cv::ml::RTrees::create();
  set_tree(*model, hyper);
  model->setActiveVarCount(0);  // sqrt of the features, the usual forest choice
  model->setCalculateVarImportance(false);
  model->setTermCriteria(
      cv::TermCriteria(cv::TermCriteria::MAX_ITER, hyper.value("trees", 30), 0.0));
  return std::make_unique<OpenCvClassifier<cv::ml::RTrees>>(model);
}

}  // namespace

std::string_view classifier_name(ClassifierKind kind) {
  switch (kind) {
    case ClassifierKind::DecisionTree: return "decision_tree";
    case ClassifierKind::NaiveBayes: return "naive_bayes";
    case ClassifierKind::Svm: return "svm";
    case ClassifierKind::Knn: return "knn";
    case ClassifierKind::Ensemble: return "ensemble";
  }
  return "?";
}

std::string classifier_file(ClassifierKind kind) {
  switch (kind) {
    case ClassifierKind::NaiveBayes: return "naive_bayes.json";
    case ClassifierKind::Svm: return "svm.libsvm";
    default: return std::string(classifier_name(kind)) + ".yml";
  }
}

std::unique_ptr<Classifier> make_classifier(ClassifierKind kind, const json& hyper) {
  switch (kind) {
    case ClassifierKind::DecisionTree: return make_tree(hyper);
    case ClassifierKind::NaiveBayes: return std::make_unique<NaiveBayesClassifier>(hyper);
    case ClassifierKind::Svm: return std::make_unique<SvmClassifier>(hyper);
    case ClassifierKind::Knn: return std::make_unique<KnnClassifier>(hyper.value("k", 10));
    case ClassifierKind::Ensemble: return make_forest(hyper);
  }
  throw std::logic_error("unknown classifier kind");
}

std::vector<json> hyperparameter_grid(ClassifierKind kind, const SearchSettings& s) {
  std::vector<json> grid;
  switch (kind) {
    case ClassifierKind::DecisionTree:
      for (int depth : s.quick ? std::vector<int>{4, 8} : std::vector<int>{3, 5, 8, 12, 20}) {
        for (int min : s.quick ? std::vector<int>{5} : std::vector<int>{2, 10, 30}) {
          grid.push_back({{"max_depth", depth}, {"min_samples", min}});
        }
      }
      break;
    case ClassifierKind::NaiveBayes:
      if (!s.naive_bayes_kernel) return {{{"kernel", false}}};
      for (double scale : s.quick ? std::vector<double>{0.5, 1.0}
                                  : std::vector<double>{0.25, 0.5, 1.0, 2.0, 4.0}) {
        grid.push_back({{"kernel", true}, {"bandwidth_scale", scale}});
      }
      break;
    case ClassifierKind::Svm:
      for (double c :
           s.quick ? std::vector<double>{1.0, 10.0} : std::vector<double>{0.1, 1.0, 10.0, 100.0}) {
        grid.push_back({{"C", c}, {"gamma_factor", 1.0}});
      }
      break;
    case ClassifierKind::Knn: grid.push_back({{"k", s.knn_k}}); break;
    case ClassifierKind::Ensemble:
      for (int depth : s.quick ? std::vector<int>{10} : std::vector<int>{8, 16, 25}) {
        grid.push_back({{"trees", s.ensemble_trees}, {"max_depth", depth}, {"min_samples", 2}});
      }
      break;
  }
  return grid;
}

}  // namespace lanechange::learn
