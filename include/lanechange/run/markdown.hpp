#pragma once
// One writer for every Markdown table the toolkit prints or saves (reports,
// studies, model and DAgger summaries), so that they all read alike.
#include <string>
#include <vector>

namespace lanechange::run {

enum class Align { Left, Right };

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

/// "| a | b |\n".
[[nodiscard]] std::string markdown_row(const std::vector<std::string>& cells);
/// The header, its rule ("---", or "---:" for right-aligned columns) and the
/// rows. `align` is per column; a column it does not name is left-aligned.
[[nodiscard]] std::string markdown(const Table& table, const std::vector<Align>& align = {});

}  // namespace lanechange::run
