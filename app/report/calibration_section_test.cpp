// The report's calibration section: the heat map has a cell per camera pair, both axes labelled,
// the spanning tree outlined and the uncalibratable camera marked; the cell embeds it once.
#include "app/report/calibration_section.h"

#include <gtest/gtest.h>

#include <string>

namespace pandora::report {
namespace {

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// Four cameras: a, b, c&d linked (a-b 30, b-c&d 50), e alone.
CalibrationResult FourCameras() {
  CalibrationResult r;
  r.spec.min_shared = 20;
  r.camera_ids = {"a", "b", "c&d", "e"};
  r.enabled = {true, true, true, true};
  r.shared = {{60, 30, 5, 0}, {30, 90, 50, 0}, {5, 50, 70, 0}, {0, 0, 0, 3}};
  r.observed = {60, 90, 70, 3};
  r.missed.assign(4, {});
  r.missed[3][static_cast<int>(BoardView::kOccluded)] = 97;
  r.poses = 100;
  r.graph = BuildCalibrationGraph(r.shared, r.enabled, r.spec.min_shared);
  return r;
}

TEST(CalibrationSection, HeatMapCellsLabelsAndLinks) {
  const CalibrationResult r = FourCameras();
  ASSERT_EQ(r.graph.uncalibratable, std::vector<int>{3});
  const std::string svg = CalibrationMatrixSvg(r, "Co-visibility: <rig>");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(Count(svg, "stroke=\"#cccccc\" stroke-width=\"0.5\""), 16);  // 4 x 4 cells
  EXPECT_EQ(Count(svg, ">c&amp;d</text>"), 2);                           // both axes, escaped
  EXPECT_EQ(Count(svg, "c&d"), 0);
  EXPECT_NE(svg.find("&lt;rig&gt;"), std::string::npos);
  // The tree: a-b (30, the weakest, red) and b-c&d (50, black), each drawn in both halves.
  EXPECT_EQ(Count(svg, "fill=\"none\" stroke=\"#c00000\" stroke-width=\"2\""), 2);
  EXPECT_EQ(Count(svg, "fill=\"none\" stroke=\"#000000\" stroke-width=\"2\""), 2);
  // e is uncalibratable: its ids are red and bold.
  EXPECT_EQ(Count(svg, "fill=\"#c00000\" font-weight=\"bold\">e</text>"), 2);
  // a-c&d share 5 (< 20): the grey of "no link" in both halves (and in the legend), its count
  // written.
  EXPECT_EQ(Count(svg, "fill=\"#d9d9d9\" stroke=\"#cccccc\""), 3);
  EXPECT_EQ(Count(svg, ">5</text>"), 2);
}

TEST(CalibrationSection, CellEmbedsTheMapOnceAndListsCameras) {
  const CalibrationResult r = FourCameras();
  int images = 0;
  const std::string html =
      CalibrationCellHtml(r, "ring", [&](const std::string& svg, const std::string& alt) {
        ++images;
        EXPECT_EQ(alt, "ring calibration co-visibility matrix");
        EXPECT_NE(svg.find("Co-visibility: ring"), std::string::npos);
        return std::string("<img>");
      });
  EXPECT_EQ(images, 1);
  EXPECT_NE(html.find("Not calibratable as one rig"), std::string::npos);
  EXPECT_EQ(Count(html, "<tr class=\"uncalibratable\">"), 1);
  EXPECT_NE(html.find("occluded 97"), std::string::npos);
  EXPECT_NE(html.find("<td>a &ndash; b</td><td>30</td>"), std::string::npos);
}

}  // namespace
}  // namespace pandora::report
