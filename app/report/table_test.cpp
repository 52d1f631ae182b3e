// Plain tables and CSV text (app/report/table.h).
#include "app/report/table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace pandora::report {
namespace {

TEST(ComparisonHtml, WritesTheRigComparisonsPlainTextAsTheReportsHtml) {
  // The labels volume/rig_comparison.cpp writes, as the report showed them before they were plain.
  EXPECT_EQ(ComparisonHtml("Coverage >= 2 cameras"), "Coverage &ge; 2 cameras");
  EXPECT_EQ(ComparisonHtml("sigma_max p90 (mm)"), "&sigma;<sub>max</sub> p90 (mm)");
  EXPECT_EQ(ComparisonHtml("Meets sigma_max <= 2 mm"), "Meets &sigma;<sub>max</sub> &le; 2 mm");
  EXPECT_EQ(ComparisonHtml("Covered at every time sample (>= 3 cameras)"),
            "Covered at every time sample (&ge; 3 cameras)");
  // A value: "-" alone is none; a negative number stays as it is.
  EXPECT_EQ(ComparisonHtml("-"), "&mdash;");
  EXPECT_EQ(ComparisonHtml("-0.500"), "-0.500");
  // Anything else is escaped.
  EXPECT_EQ(ComparisonHtml("a < b & c > d"), "a &lt; b &amp; c &gt; d");
}

TEST(Table, TextAlignsColumnsCountingUtf8Characters) {
  Table t({"name", "σ mm"});
  t.AddRow({"a", "1.5"});
  t.AddRow({"longer", "12"});
  t.AddRow({"x"});  // padded with an empty cell
  EXPECT_EQ(t.Text(),
            "name    σ mm\n"
            "a        1.5\n"
            "longer    12\n"
            "x\n");
  EXPECT_EQ(t.Markdown(),
            "| name | σ mm |\n"
            "|---|---:|\n"
            "| a | 1.5 |\n"
            "| longer | 12 |\n"
            "| x |  |\n");
}

TEST(Table, ExplicitAlignment) {
  Table t({"a", "b", "c"}, "rlr");
  t.AddRow({"1", "22", "333"});
  EXPECT_EQ(t.Text(), "a  b     c\n1  22  333\n");
  EXPECT_EQ(t.Markdown().substr(0, 27), "| a | b | c |\n|---:|---|---");
}

TEST(Csv, FieldsNeverNeedQuoting) {
  EXPECT_EQ(CsvText({"a", "b"}, {{"1,5", "say \"hi\""}, {"2", "3"}}), "a,b\n1;5,say 'hi'\n2,3\n");
  EXPECT_EQ(CsvNumber(0.1), "0.1");
  EXPECT_EQ(CsvNumber(1.0 / 3), "0.333333333");
  EXPECT_EQ(CsvNumber(std::nan("")), "nan");
  EXPECT_EQ(CsvNumber(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(CsvNumber(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(Cell("%.2f", 1.005), "1.00");
  EXPECT_EQ(Cell("%.2f", std::nan("")), "-");
  EXPECT_EQ(Format("%d-%s", 3, "x"), "3-x");
}

}  // namespace
}  // namespace pandora::report
