#pragma once
/// \file table.h
/// Plain tables for reports: aligned text for a terminal and Markdown from the same cells, and CSV
/// text whose fields never need quoting.

#include <string>
#include <vector>

#include "analysis/util/text.h"

namespace pandora::report {

/// `s` with & < > " replaced by their HTML entities, for text and attribute values in the report.
std::string HtmlEscape(const std::string& s);

/// A plain-text label or value of the rig comparison (volume/rig_comparison.h) as the report's
/// HTML: escaped, then ">=" as &ge;, "<=" as &le;, "sigma_max" as &sigma;<sub>max</sub>, and a
/// value of "-" alone (none) as &mdash;.
std::string ComparisonHtml(const std::string& plain);

/// A table of already formatted cells.
class Table {
 public:
  /// `align`: one 'l' or 'r' per column; default: the first column left, the others right.
  explicit Table(std::vector<std::string> header = {}, std::string align = {});
  /// Adds a row, padded with empty cells or cut to the header's width.
  void AddRow(std::vector<std::string> row);
  /// Columns padded to their widest cell (UTF-8 aware), two spaces apart, no trailing spaces; the
  /// header first; one line per row, each ending in '\n'.
  std::string Text() const;
  /// A GitHub Markdown table ("| a | b |", "|---|---:|", ...), each line ending in '\n'.
  std::string Markdown() const;
  const std::vector<std::string>& header() const { return header_; }
  const std::vector<std::vector<std::string>>& rows() const { return rows_; }

 private:
  std::vector<std::string> header_;
  std::string align_;
  std::vector<std::vector<std::string>> rows_;
};

/// CSV text: the header and the rows of already formatted fields, one line each. Fields are plain
/// (no quoting): a comma or a double quote inside one becomes a semicolon or an apostrophe, so
/// `awk -F,` and spreadsheets read the same columns.
std::string CsvText(const std::vector<std::string>& header,
                    const std::vector<std::vector<std::string>>& rows);

/// A number for a CSV field: %.9g, or "nan", "inf", "-inf".
std::string CsvNumber(double v);

/// A number for a table cell: printf `format` when finite, "-" otherwise.
std::string Cell(const char* format, double v);

using pandora::Format;  // analysis/util/text.h

}  // namespace pandora::report
