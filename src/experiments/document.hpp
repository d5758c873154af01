#pragma once
// The report as a list of blocks, written twice: as Markdown (pictures
// linked) and as one self-contained HTML file (pictures embedded), so the
// two never disagree.
#include <string>
#include <vector>

#include "lanechange/run/markdown.hpp"

namespace lanechange::experiments {

using run::Table;

class Document {
 public:
  void heading(int level, std::string text);
  void paragraph(std::string text);
  void bullets(std::vector<std::string> items);
  void table(Table table);
  /// A PNG under the report's directory; `path` is relative to it. A missing
  /// picture is named in the text rather than failing the report.
  void figure(std::string path, std::string caption);
  void code(std::string text);

  [[nodiscard]] std::string markdown() const;
  /// `base_dir`: where the figures' relative paths start.
  [[nodiscard]] std::string html(const std::string& base_dir, const std::string& title) const;

 private:
  enum class Kind { Heading, Paragraph, Bullets, Table, Figure, Code };
  struct Block {
    Kind kind = Kind::Paragraph;
    int level = 0;
    std::string text;  ///< heading, paragraph, code, figure path
    std::string caption;
    std::vector<std::string> items;
    Table table;
  };
  std::vector<Block> blocks_;
};

/// Standard base64 (RFC 4648) of the bytes.
[[nodiscard]] std::string base64(const std::string& bytes);

}  // namespace lanechange::experiments
