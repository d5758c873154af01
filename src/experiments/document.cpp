#include "experiments/document.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "lanechange/plot.hpp"

namespace lanechange::experiments {

namespace {

std::string escape_html(const std::string& text) { return xml_escaped(text); }

// Markdown's inline code and bold survive into the HTML as <code> and <b>:
// the report's prose uses nothing else.
std::string inline_html(const std::string& text) {
  std::string out;
  bool in_code = false;
  bool in_bold = false;
  const std::string escaped = escape_html(text);
  for (std::size_t i = 0; i < escaped.size(); ++i) {
    if (escaped[i] == '`') {
      out += in_code ? "</code>" : "<code>";
      in_code = !in_code;
    } else if (!in_code && escaped.compare(i, 2, "**") == 0) {
      out += in_bold ? "</b>" : "<b>";
      in_bold = !in_bold;
      ++i;
    } else {
      out += escaped[i];
    }
  }
  return out;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

}  // namespace

std::string base64(const std::string& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    unsigned triple = 0;
    for (std::size_t j = 0; j < 3; ++j) {
      triple <<= 8U;
      if (j < n) triple |= static_cast<unsigned char>(bytes[i + j]);
    }
    for (std::size_t j = 0; j < 4; ++j) {
      out += j <= n ? kAlphabet[(triple >> (18 - 6 * j)) & 63U] : '=';
    }
  }
  return out;
}

void Document::heading(int level, std::string text) {
  blocks_.push_back({Kind::Heading, level, std::move(text), {}, {}, {}});
}
void Document::paragraph(std::string text) {
  blocks_.push_back({Kind::Paragraph, 0, std::move(text), {}, {}, {}});
}
void Document::bullets(std::vector<std::string> items) {
  blocks_.push_back({Kind::Bullets, 0, {}, {}, std::move(items), {}});
}
void Document::table(Table table) {
  blocks_.push_back({Kind::Table, 0, {}, {}, {}, std::move(table)});
}
void Document::figure(std::string path, std::string caption) {
  blocks_.push_back({Kind::Figure, 0, std::move(path), std::move(caption), {}, {}});
}
void Document::code(std::string text) {
  blocks_.push_back({Kind::Code, 0, std::move(text), {}, {}, {}});
}

std::string Document::markdown() const {
  std::string out;
  for (const Block& b : blocks_) {
    switch (b.kind) {
      case Kind::Heading:
        out += std::string(static_cast<std::size_t>(b.level), '#') + " ";
        out += b.text + "\n\n";
        break;
      case Kind::Paragraph: out += b.text + "\n\n"; break;
      case Kind::Bullets:
        for (const auto& item : b.items) out += "- " + item + "\n";
        out += "\n";
        break;
      case Kind::Table: {
        out += run::markdown(b.table);
        out += "\n";
        break;
      }
      case Kind::Figure:
        out += "![" + b.caption + "](" + b.text + ")\n\n*" + b.caption + "*\n\n";
        break;
      case Kind::Code: out += "```\n" + b.text + "\n```\n\n"; break;
    }
  }
  return out;
}

std::string Document::html(const std::string& base_dir, const std::string& title) const {
  std::string out =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" + escape_html(title) +
      "</title>\n<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;}"
      "table{border-collapse:collapse;margin:1em 0;}td,th{border:1px solid #bbb;padding:"
      "3px 8px;text-align:right;}th{background:#eee;}img{max-width:100%;}"
      "pre{background:#f4f4f4;padding:8px;overflow-x:auto;}</style></head><body>\n";
  for (const Block& b : blocks_) {
    switch (b.kind) {
      case Kind::Heading: {
        std::string tag = "h";
        tag += std::to_string(b.level);
        out += "<";
        out += tag;
        out += ">";
        out += inline_html(b.text);
        out += "</";
        out += tag;
        out += ">\n";
        break;
      }
      case Kind::Paragraph: out += "<p>" + inline_html(b.text) + "</p>\n"; break;
      case Kind::Bullets:
        out += "<ul>\n";
        for (const auto& item : b.items) out += "<li>" + inline_html(item) + "</li>\n";
        out += "</ul>\n";
        break;
      case Kind::Table: {
        out += "<table><tr>";
        for (const auto& cell : b.table.header) out += "<th>" + inline_html(cell) + "</th>";
        out += "</tr>\n";
        for (const auto& row : b.table.rows) {
          out += "<tr>";
          for (const auto& cell : row) out += "<td>" + inline_html(cell) + "</td>";
          out += "</tr>\n";
        }
        out += "</table>\n";
        break;
      }
      case Kind::Figure: {
        const auto path = std::filesystem::path(base_dir) / b.text;
        out += "<figure>";
        if (std::filesystem::exists(path)) {
          out += "<img alt=\"" + escape_html(b.caption) + "\" src=\"data:image/png;base64," +
                 base64(read_bytes(path.string())) + "\">";
        } else {
          out += "<p>(missing picture: " + escape_html(b.text) + ")</p>";
        }
        out += "<figcaption>" + inline_html(b.caption) + "</figcaption></figure>\n";
        break;
      }
      case Kind::Code: out += "<pre>" + escape_html(b.text) + "</pre>\n"; break;
    }
  }
  return out + "</body></html>\n";
}

}  // namespace lanechange::experiments
