#include <cstdio>
#include <sstream>

#include "common/json_fields.hpp"
#include "lanechange/learn/classifier.hpp"
#include "lanechange/learn/learn_data.hpp"
#include "lanechange/plot.hpp"
#include "lanechange/run/markdown.hpp"
#include "learn/outputs.hpp"

namespace lanechange::learn::detail {

namespace {

using nlohmann::json;

std::string fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

std::string percent(const json& value) { return fixed(100.0 * value.get<double>(), 1); }

// Labels with spaces: gnuplot's enhanced text would read '_' as a subscript.
std::string spaced(std::string_view name) {
  std::string s(name);
  for (char& c : s) c = c == '_' ? ' ' : c;
  return s;
}

void classifier_rows(const json& set, std::ostringstream& md) {
  run::Table table{
      {"classifier", "test accuracy", "CV accuracy (mean +- sd)", "macro F1", "precision (wp/ip/f)",
       "recall (wp/ip/f)", "train s", "predict us/scene", "hyperparameters"},
      {}};
  for (ClassifierKind kind : kClassifierKinds) {
    const std::string name(classifier_name(kind));
    if (!set.contains(name)) continue;
    const json& c = set.at(name);
    const auto triple = [&](const char* key) {
      std::string out;
      for (const auto& v : c.at(key)) {
        if (!out.empty()) out += '/';
        out += percent(v);
      }
      return out;
    };
    table.rows.push_back(
        {name, percent(c.at("test_accuracy")) + "%",
         percent(c.at("cv_accuracy_mean")) + "% +- " + percent(c.at("cv_accuracy_sd")),
         fixed(c.at("macro_f1").get<double>(), 3), triple("precision"), triple("recall"),
         fixed(c.at("train_s").get<double>(), 2),
         fixed(c.at("predict_us_per_scene").get<double>(), 1), c.at("hyperparameters").dump()});
  }
  md << run::markdown(table);
}

void behavior_rows(const json& set, std::ostringstream& md) {
  run::Table table{{"classifier"}, {}};
  for (std::string_view b : kBehaviorNames) table.header.emplace_back(b);
  for (ClassifierKind kind : kClassifierKinds) {
    const std::string name(classifier_name(kind));
    if (!set.contains(name)) continue;
    std::vector<std::string> row = {name};
    for (std::string_view b : kBehaviorNames) {
      const json& by = set.at(name).at("accuracy_by_behavior");
      row.push_back(by.contains(b) ? percent(by.at(b)) + "%" : std::string("-"));
    }
    table.rows.push_back(std::move(row));
  }
  md << run::markdown(table);
}

}  // namespace

void write_confusion_csv(const Eigen::MatrixXd& m, const std::string& path) {
  std::string text = "true\\predicted";
  for (std::string_view l : kLabelNames) {
    text += ',';
    text += l;
  }
  text += "\n";
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    text += std::string(kLabelNames[static_cast<std::size_t>(r)]);
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      text += ',';
      text += fixed(m(r, c), 6);
    }
    text += "\n";
  }
  lanechange::detail::write_file_atomically(path, text);
}

void plot_confusion(const Eigen::MatrixXd& m, const std::string& title,
                    const std::string& png_path) {
  render_png(
      [&](const std::string& png) {
        std::ostringstream s;
        s << "set terminal pngcairo size 640,520 font 'Sans,11'\nset output " << gnuplot_quoted(png)
          << "\nset title " << gnuplot_quoted(spaced(title)) << "\nset xlabel 'predicted class'\n"
          << "set ylabel 'true class'\nset xrange [-0.5:2.5]\nset yrange [2.5:-0.5]\n"
          << "set cbrange [0:1]\nset palette defined (0 'white', 1 '#2166ac')\n";
        std::string tics;
        for (std::size_t i = 0; i < kLabelNames.size(); ++i) {
          if (i > 0) tics += ", ";
          tics += gnuplot_quoted(spaced(kLabelNames[i]));
          tics += ' ';
          tics += std::to_string(i);
        }
        s << "set xtics (" << tics << ")\nset ytics (" << tics << ")\n$m << EOD\n";
        for (Eigen::Index r = 0; r < m.rows(); ++r) {
          for (Eigen::Index c = 0; c < m.cols(); ++c) s << c << " " << r << " " << m(r, c) << "\n";
        }
        s << "EOD\nplot $m using 1:2:3 with image notitle, "
          << "$m using 1:2:(sprintf('%.1f%%', 100*$3)) with labels notitle\n";
        return s.str();
      },
      png_path);
}

void write_loss_csv(const std::vector<LossPoint>& curve, const std::string& path) {
  std::string text = "epoch,train_mse,validation_mse\n";
  for (const LossPoint& p : curve) {
    text += std::to_string(p.epoch);
    for (double v : {p.train_mse, p.validation_mse}) {
      text += ',';
      text += fixed(v, 9);
    }
    text += '\n';
  }
  lanechange::detail::write_file_atomically(path, text);
}

void plot_loss(const std::vector<LossPoint>& curve, int best_epoch, const std::string& png_path) {
  render_png(
      [&](const std::string& png) {
        std::ostringstream s;
        s << "set terminal pngcairo size 800,480 font 'Sans,11'\nset output " << gnuplot_quoted(png)
          << "\nset title 'action network: mean squared error (normalised)'\n"
          << "set xlabel 'epoch'\nset ylabel 'MSE'\nset logscale y\nset grid\n"
          << "set arrow from " << best_epoch << ", graph 0 to " << best_epoch
          << ", graph 1 nohead dt 2\n$l << EOD\n";
        for (const LossPoint& p : curve) {
          s << p.epoch << " " << p.train_mse << " " << p.validation_mse << "\n";
        }
        s << "EOD\nplot $l using 1:2 with lines lw 2 title 'training', "
          << "$l using 1:3 with lines lw 2 title 'validation'\n";
        return s.str();
      },
      png_path);
}

std::string report_markdown(const json& m) {
  std::ostringstream md;
  const json& d = m.at("data");
  md << "# Training report\n\n"
     << d.at("scenarios") << " scenarios (" << d.at("train_scenarios") << " train, "
     << d.at("test_scenarios") << " test, split by scenario, seed " << m.at("seed") << "); "
     << d.at("train_samples") << " training and " << d.at("test_samples")
     << " test samples of well-posed plans.\n\n"
     << "Majority class (" << m.at("majority_class").at("class").get<std::string>()
     << ") accuracy on the test part: " << percent(m.at("majority_class").at("test_accuracy"))
     << "%.\n\n## Classifiers (13 features)\n\n";
  classifier_rows(m.at("classifiers"), md);
  md << "\n### Test accuracy by behavior\n\n";
  behavior_rows(m.at("classifiers"), md);
  md << "\n## Classifiers with the behavior one-hot (16 inputs)\n\n";
  classifier_rows(m.at("classifiers_with_behavior"), md);
  md << "\n### Test accuracy by behavior\n\n";
  behavior_rows(m.at("classifiers_with_behavior"), md);
  const json& n = m.at("network");
  run::Table outputs{{"output", "test RMSE", "test p95 abs error"}, {}};
  for (const auto& [name, rmse] : n.at("test_rmse").items()) {
    outputs.rows.push_back({name, fixed(rmse.get<double>(), 4),
                            fixed(n.at("test_p95_abs_error").at(name).get<double>(), 4)});
  }
  md << "\n## Action network\n\n" << run::markdown(outputs);
  md << "\nEpochs " << n.at("epochs") << " (best " << n.at("best_epoch") << "), "
     << fixed(n.at("train_s").get<double>(), 1) << " s ("
     << fixed(n.at("s_per_epoch").get<double>(), 3)
     << " s per epoch); best validation MSE (normalised) "
     << fixed(n.at("best_validation_mse").get<double>(), 5) << ".\n";
  return md.str();
}

}  // namespace lanechange::learn::detail
