#include "lanechange/run/markdown.hpp"

namespace lanechange::run {

std::string markdown_row(const std::vector<std::string>& cells) {
  std::string line = "|";
  for (const auto& cell : cells) {
    line += ' ';
    line += cell;
    line += " |";
  }
  return line + "\n";
}

std::string markdown(const Table& table, const std::vector<Align>& align) {
  std::string rule = "|";
  for (std::size_t c = 0; c < table.header.size(); ++c) {
    rule += c < align.size() && align[c] == Align::Right ? "---:|" : "---|";
  }
  std::string out = markdown_row(table.header) + rule + "\n";
  for (const auto& row : table.rows) out += markdown_row(row);
  return out;
}

}  // namespace lanechange::run
