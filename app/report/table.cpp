// Plain tables and CSV text (app/report/table.h).
#include "app/report/table.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <utility>

namespace pandora::report {

std::string HtmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string ComparisonHtml(const std::string& plain) {
  if (plain == "-") return "&mdash;";
  std::string s = HtmlEscape(plain);
  static const std::pair<const char*, const char*> kMarkup[] = {
      {"&gt;=", "&ge;"}, {"&lt;=", "&le;"}, {"sigma_max", "&sigma;<sub>max</sub>"}};
  for (const auto& [from, to] : kMarkup)
    for (std::size_t at = s.find(from); at != std::string::npos;
         at = s.find(from, at + std::strlen(to)))
      s.replace(at, std::strlen(from), to);
  return s;
}
namespace {

// Display width: UTF-8 continuation bytes do not count.
std::size_t Length(const std::string& s) {
  std::size_t n = 0;
  for (unsigned char ch : s)
    if ((ch & 0xC0) != 0x80) ++n;
  return n;
}

}  // namespace

std::string Cell(const char* format, double v) {
  return std::isfinite(v) ? Format(format, v) : "-";
}

std::string CsvNumber(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return Format("%.9g", v);
}

Table::Table(std::vector<std::string> header, std::string align)
    : header_(std::move(header)), align_(std::move(align)) {
  if (align_.empty() && !header_.empty()) align_ = "l" + std::string(header_.size() - 1, 'r');
  align_.resize(header_.size(), 'r');
}

void Table::AddRow(std::vector<std::string> row) {
  row.resize(header_.size());
  rows_.push_back(std::move(row));
}

std::string Table::Text() const {
  std::vector<std::size_t> width(header_.size());
  for (std::size_t c = 0; c < header_.size(); ++c) {
    width[c] = Length(header_[c]);
    for (const auto& r : rows_) width[c] = std::max(width[c], Length(r[c]));
  }
  std::string out;
  auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::string pad(width[c] - Length(cells[c]), ' ');
      out += (c == 0 ? "" : "  ") + (align_[c] == 'l' ? cells[c] + pad : pad + cells[c]);
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    out += '\n';
  };
  line(header_);
  for (const auto& r : rows_) line(r);
  return out;
}

std::string Table::Markdown() const {
  std::string out = "|";
  for (const auto& h : header_) out += " " + h + " |";
  out += "\n|";
  for (std::size_t c = 0; c < header_.size(); ++c) out += align_[c] == 'l' ? "---|" : "---:|";
  out += "\n";
  for (const auto& r : rows_) {
    out += "|";
    for (const auto& cell : r) out += " " + cell + " |";
    out += "\n";
  }
  return out;
}

std::string CsvText(const std::vector<std::string>& header,
                    const std::vector<std::vector<std::string>>& rows) {
  std::string out;
  auto line = [&](const std::vector<std::string>& cells) {
    for (std::size_t c = 0; c < cells.size(); ++c) {
      std::string field = cells[c];
      std::replace(field.begin(), field.end(), ',', ';');
      std::replace(field.begin(), field.end(), '"', '\'');
      out += (c ? "," : "") + field;
    }
    out += '\n';
  };
  line(header);
  for (const auto& r : rows) line(r);
  return out;
}

}  // namespace pandora::report
