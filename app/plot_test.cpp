// The SVG log-log plot writer: decade ranges, skipped points, escaping, legend-only keys.
#include "app/plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace pandora::app {
namespace {

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

TEST(LogLogPlot, DecadesHoldEveryPointAndMarker) {
  LogLogPlot plot;
  plot.title = "t";
  PlotSeries s;
  s.label = "a";
  s.x = {2, 50};
  s.y = {3e-6, 4e-5};
  plot.series.push_back(s);
  plot.vertical_lines.push_back({0.4, "prediction"});
  const std::string svg = RenderLogLogSvg(plot);
  const auto label = [](const std::string& exponent) {
    return ">10<tspan dy=\"-7\" font-size=\"10\">" + exponent + "</tspan>";
  };
  // x from 1e-1 (the marker) to 1e2 (50 plus head room for its label); y from 1e-6 to 1e-4.
  for (const char* e : {"\u22121", "2", "\u22126", "\u22125", "\u22124"})
    EXPECT_NE(svg.find(label(e)), std::string::npos) << e;
  EXPECT_NE(svg.find(">1</text>"), std::string::npos);
  EXPECT_NE(svg.find(">10</text>"), std::string::npos);
  for (const char* e : {"\u22127", "\u22123", "\u22122", "3"})
    EXPECT_EQ(svg.find(label(e)), std::string::npos) << e;
  EXPECT_EQ(svg.rfind("</svg>\n"), svg.size() - 7);
  EXPECT_EQ(Count(svg, "<text"), Count(svg, "</text>"));
}

TEST(LogLogPlot, NonPositiveAndNonFinitePointsAreSkippedAndBreakTheLine) {
  LogLogPlot plot;
  PlotSeries s;
  s.label = "gaps";
  s.x = {1, 2, 3, 4, 5};
  s.y = {1, 0, 3, std::numeric_limits<double>::quiet_NaN(), 5};
  plot.series.push_back(s);
  const std::string svg = RenderLogLogSvg(plot);
  // Three markers (circles) plus the legend's; the path restarts (M) after each gap.
  EXPECT_EQ(Count(svg, "<circle"), 3 + 1);
  EXPECT_EQ(Count(svg, "<path d=\"M"), 1);
  EXPECT_EQ(Count(svg, " M"), 2);
}

TEST(LogLogPlot, NoDataAndEscaping) {
  LogLogPlot plot;
  plot.title = "a < b & c";
  PlotSeries key;  // legend-only
  key.label = "\"key\"";
  plot.series.push_back(key);
  const std::string svg = RenderLogLogSvg(plot);
  EXPECT_NE(svg.find("no data"), std::string::npos);
  EXPECT_NE(svg.find("a &lt; b &amp; c"), std::string::npos);
  EXPECT_NE(svg.find("&quot;key&quot;"), std::string::npos);
  EXPECT_EQ(svg.find("a < b"), std::string::npos);
}

}  // namespace
}  // namespace pandora::app
