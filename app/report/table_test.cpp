// Plain tables and CSV text (app/report/table.h).
#include "app/report/table.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace pandora::report {
namespace {

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
