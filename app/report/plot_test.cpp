// The SVG log-log plot writer: decade ranges, skipped points, escaping, legend-only keys.
#include "app/report/plot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace pandora::report {
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

TEST(NiceTicks, StepsOfOneTwoFiveCoverTheRange) {
  const std::vector<double> one = NiceTicks(1.0, 5), expected{0, 0.2, 0.4, 0.6, 0.8, 1.0};
  ASSERT_EQ(one.size(), expected.size());
  for (std::size_t i = 0; i < one.size(); ++i) EXPECT_NEAR(one[i], expected[i], 1e-15);
  EXPECT_EQ(NiceTicks(7.0, 5), (std::vector<double>{0, 2, 4, 6, 8}));
  const std::vector<double> t = NiceTicks(0.0123, 4);
  EXPECT_DOUBLE_EQ(t[1], 0.005);
  EXPECT_GE(t.back(), 0.0123);
  EXPECT_EQ(NiceTicks(0.0), (std::vector<double>{0, 1}));
}

// The heights of the <rect> bars (the background rect has no height attribute in pixels).
std::vector<double> BarHeights(const std::string& svg) {
  std::vector<double> heights;
  const std::string key = "height=\"";
  for (std::size_t p = svg.find("<rect x="); p != std::string::npos;
       p = svg.find("<rect x=", p + 1)) {
    const std::size_t h = svg.find(key, p) + key.size();
    heights.push_back(std::stod(svg.substr(h, svg.find('"', h) - h)));
  }
  return heights;
}

TEST(BarChart, BarHeightsAreProportionalToValues) {
  BarChart chart;
  chart.title = "coverage <histogram>";
  chart.categories = {"0", "1", "2", "3"};
  chart.series.push_back({"rig", {0.1, 0.2, 0.0, std::nan("")}, ""});
  const std::string svg = RenderBarChartSvg(chart);
  const std::vector<double> h = BarHeights(svg);
  ASSERT_EQ(h.size(), 2u);  // zero and NaN draw nothing
  EXPECT_NEAR(h[1] / h[0], 2.0, 0.02);
  EXPECT_NE(svg.find("coverage &lt;histogram&gt;"), std::string::npos);
  // A shared y_max shrinks the bars: 0.2 of 0.4 is half the plot height.
  chart.y_max = 0.4;
  const std::vector<double> h2 = BarHeights(RenderBarChartSvg(chart));
  EXPECT_NEAR(h2[1] / h[1], 0.2 / 0.4 / (0.2 / 0.2), 0.02);
  EXPECT_EQ(Count(RenderBarChartSvg(BarChart{}), "no data"), 1);
}

TEST(BarChart, GroupedSeriesLegendAndMarker) {
  BarChart chart;
  chart.categories = {"a", "b", "c"};
  chart.series.push_back({"octagon", {1, 2, 3}, ""});
  chart.series.push_back({"grid4x2", {3, 2, 1}, "#123456"});
  chart.marker = 1.5;
  chart.marker_label = "2 mm";
  chart.percent = true;
  const std::string svg = RenderBarChartSvg(chart);
  EXPECT_EQ(Count(svg, "fill=\"#123456\""), 2);  // its group and its legend key
  EXPECT_EQ(Count(svg, ">octagon<"), 1);
  EXPECT_EQ(Count(svg, "stroke-dasharray"), 1);
  EXPECT_EQ(Count(svg, ">2 mm<"), 1);
  EXPECT_NE(svg.find("%<"), std::string::npos);
  // Edge labels sit one half bin left of centred ones.
  auto label_x = [](const std::string& text, const std::string& label) {
    const std::size_t p = text.rfind("<text x=\"", text.find(">" + label + "<"));
    return std::stod(text.substr(p + 9));
  };
  const double centred = label_x(svg, "b");
  chart.edge_labels = true;
  const std::string edges = RenderBarChartSvg(chart);
  EXPECT_NEAR(centred - label_x(edges, "b"), (label_x(svg, "c") - label_x(svg, "b")) / 2, 0.02);
}

TEST(NiceSteps, LabelStepsAreOneTwoFiveMultiplesOfTheBinWidth) {
  EXPECT_DOUBLE_EQ(NiceStep(0.0267), 0.05);
  EXPECT_DOUBLE_EQ(NiceStep(0.02), 0.02);
  EXPECT_DOUBLE_EQ(NiceStep(3), 5);
  EXPECT_DOUBLE_EQ(NiceStep(7), 10);
  EXPECT_DOUBLE_EQ(NiceLabelStep(0.02, 0.06), 0.1);  // not 0.06, nor 0.08 (4 bins)
  EXPECT_DOUBLE_EQ(NiceLabelStep(0.05, 0.1), 0.1);
  EXPECT_DOUBLE_EQ(NiceLabelStep(0.05, 0.11), 0.2);  // 0.2 = 4 bins of 0.05
  EXPECT_DOUBLE_EQ(NiceLabelStep(5, 11), 20);        // 20 = 4 bins; 25 is not 1-2-5
  EXPECT_DOUBLE_EQ(NiceLabelStep(2, 5), 10);         // 6 and 8 are not 1-2-5
  EXPECT_DOUBLE_EQ(NiceLabelStep(1, 3), 5);
  EXPECT_DOUBLE_EQ(NiceLabelStep(0.03, 0.05), 0.06);  // not 1-2-5 itself: whole multiples
}

TEST(BarChart, HistogramLabelsSitOnRoundNumbers) {
  // 30 bins of 0.02 mm and an overflow bin: too narrow to label each; the labels are the edges
  // that are multiples of 0.1 (every 5th bin), starting at 0.
  BarChart chart;
  for (int b = 0; b < 30; ++b) {
    char label[16];
    std::snprintf(label, sizeof label, "%g", b * 0.02);
    chart.categories.push_back(label);
  }
  chart.categories.push_back(">=0.6");
  chart.series.push_back({"x", std::vector<double>(31, 0.01), ""});
  chart.bin_width = 0.02;
  chart.edge_labels = true;
  const std::string svg = RenderBarChartSvg(chart);
  EXPECT_EQ(Count(svg, ">0<"), 2);  // the x axis's first bin and the y axis's 0
  for (const char* shown : {">0.1<", ">0.2<", ">0.5<"}) EXPECT_EQ(Count(svg, shown), 1) << shown;
  for (const char* hidden : {">0.02<", ">0.06<", ">0.08<", ">0.12<", ">0.18<"})
    EXPECT_EQ(Count(svg, hidden), 0) << hidden;
  // Bins of 0.25 (not itself a 1-2-5 step) from 0.25: wide enough for every label, yet only the
  // multiples of 0.5 are labelled. (y values of 7: ticks 0, 2, 4, 6, 8 do not collide.)
  BarChart wide;
  wide.categories = {"0.25", "0.5", "0.75", "1", "1.25"};
  wide.series.push_back({"x", {7, 7, 7, 7, 7}, ""});
  wide.bin_width = 0.25;
  wide.bin_origin = 0.25;
  const std::string w = RenderBarChartSvg(wide);
  for (const char* shown : {">0.5<", ">1<"}) EXPECT_EQ(Count(w, shown), 1) << shown;
  for (const char* hidden : {">0.25<", ">0.75<", ">1.25<"})
    EXPECT_EQ(Count(w, hidden), 0) << hidden;
}

TEST(Colorbar, DiscreteBoxesAndSwatches) {
  Colorbar bar;
  bar.label = "coverage (cameras)";
  bar.min = 0;
  bar.max = 8;
  bar.discrete = true;
  bar.swatches = {{"#808080", "outside region"}};
  const std::string svg = RenderColorbarSvg(bar);
  EXPECT_EQ(Count(svg, "<rect x="), 9 + 1);
  EXPECT_EQ(Count(svg, "fill=\"#440154\""), 1);  // viridis(0)
  EXPECT_EQ(Count(svg, "fill=\"#fde725\""), 1);  // viridis(1)
  EXPECT_EQ(Count(svg, ">outside region<"), 1);
  Colorbar ramp;
  ramp.label = "sigma_max (mm)";
  ramp.min = 0;
  ramp.max = 4;
  ramp.max_is_open = true;
  const std::string r = RenderColorbarSvg(ramp);
  EXPECT_EQ(Count(r, "<stop "), 17);
  EXPECT_NE(r.find("\u22654<"), std::string::npos) << r;
}
}  // namespace
}  // namespace pandora::report
