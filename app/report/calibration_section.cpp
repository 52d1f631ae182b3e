// The report's calibration section (app/report/calibration_section.h): a heat map of the
// co-visibility matrix drawn as SVG by hand (as plot.cpp draws its plots) and plain HTML tables.
#include "app/report/calibration_section.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "analysis/util/color.h"
#include "app/report/table.h"

namespace pandora::report {
namespace {

// Tableau 10 (as plot.cpp): one colour per component.
constexpr const char* kComponentColors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b",
                                            "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#d62728"};
constexpr int kComponentColorCount = sizeof(kComponentColors) / sizeof(kComponentColors[0]);
constexpr const char* kUncalibratable = "#c00000";
constexpr const char* kBelowMinimum = "#d9d9d9";

std::string OneDecimal(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", v);
  return b;
}

std::string ComponentColor(int component) {
  return component < 0 ? "#bbbbbb" : kComponentColors[component % kComponentColorCount];
}

bool IsUncalibratable(const CalibrationResult& r, int c) {
  return std::find(r.graph.uncalibratable.begin(), r.graph.uncalibratable.end(), c) !=
         r.graph.uncalibratable.end();
}

// The miss reasons of camera `c` with a count, "occluded 551, tilted 1449".
std::string MissText(const CalibrationResult& r, int c) {
  std::string s;
  for (int v = 0; v < kBoardViewCount; ++v)
    if (r.missed[c][v] > 0)
      s += (s.empty() ? "" : ", ") + std::string(BoardViewName(static_cast<BoardView>(v))) + " " +
           std::to_string(r.missed[c][v]);
  return s.empty() ? "&ndash;" : s;
}

}  // namespace

std::string CalibrationMatrixSvg(const CalibrationResult& r, const std::string& title) {
  const int n = static_cast<int>(r.camera_ids.size());
  const int cell = std::clamp(n > 0 ? static_cast<int>(std::lround(420.0 / n)) : 36, 12, 36);
  std::size_t longest = 1;
  for (const std::string& id : r.camera_ids) longest = std::max(longest, id.size());
  const double label = 7.2 * static_cast<double>(longest) + 6;  // 12 px text
  const double band = 8, gap = 3;
  const double left = 12 + label + gap + band + gap;
  const double top = 34 + label + gap + band + gap;
  const double side = static_cast<double>(n) * cell;
  const double legend_top = top + side + 22;
  const double width = std::max(left + side + 16, 540.0);
  const double height = legend_top + 60;
  // The colour scale: 0 to the largest off-diagonal count among enabled cameras.
  std::int64_t max_shared = 0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      if (a != b && r.enabled[a] && r.enabled[b]) max_shared = std::max(max_shared, r.shared[a][b]);
  const double scale = std::max<std::int64_t>(1, max_shared);
  // The spanning tree's links, and the weakest.
  std::vector<std::vector<int>> link(n, std::vector<int>(n, 0));
  for (std::size_t k = 0; k < r.graph.weakest_links.size(); ++k) {
    const CalibrationLink& l = r.graph.weakest_links[k];
    link[l.a][l.b] = link[l.b][l.a] = k == 0 ? 2 : 1;
  }

  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << OneDecimal(width) << "\" height=\""
    << OneDecimal(height) << "\" viewBox=\"0 0 " << OneDecimal(width) << " " << OneDecimal(height)
    << "\" font-family=\"DejaVu Sans, Arial, Helvetica, sans-serif\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"12\" y=\"20\" font-size=\"14\" font-weight=\"bold\">" << HtmlEscape(title)
    << "</text>\n";
  // Ids, component bands.
  for (int c = 0; c < n; ++c) {
    const double mid = c * cell + cell / 2.0;
    const bool bad = IsUncalibratable(r, c);
    const std::string fill = !r.enabled[c] ? "#999999" : bad ? kUncalibratable : "#222222";
    const std::string weight = bad ? " font-weight=\"bold\"" : "";
    s << "<text x=\"" << OneDecimal(12 + label) << "\" y=\"" << OneDecimal(top + mid + 4)
      << "\" font-size=\"12\" text-anchor=\"end\" fill=\"" << fill << "\"" << weight << ">"
      << HtmlEscape(r.camera_ids[c]) << "</text>\n";
    s << "<text transform=\"translate(" << OneDecimal(left + mid + 4) << ","
      << OneDecimal(34 + label) << ") rotate(-90)\" font-size=\"12\" fill=\"" << fill << "\""
      << weight << ">" << HtmlEscape(r.camera_ids[c]) << "</text>\n";
    const std::string color = ComponentColor(r.graph.component[c]);
    s << "<rect x=\"" << OneDecimal(left - gap - band) << "\" y=\"" << OneDecimal(top + c * cell)
      << "\" width=\"" << OneDecimal(band) << "\" height=\"" << cell << "\" fill=\"" << color
      << "\"/>\n";
    s << "<rect x=\"" << OneDecimal(left + c * cell) << "\" y=\"" << OneDecimal(top - gap - band)
      << "\" width=\"" << cell << "\" height=\"" << OneDecimal(band) << "\" fill=\"" << color
      << "\"/>\n";
  }
  // Cells.
  const bool numbers = cell >= 24;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const std::int64_t v = r.shared[a][b];
      std::string fill = "#ffffff";
      std::string text_color = "#222222";
      if (!r.enabled[a] || !r.enabled[b]) {
        fill = "#eeeeee";
      } else if (a == b) {
        fill = "#f4f4f4";
      } else if (v >= r.spec.min_shared) {
        const double t = std::min(1.0, v / scale);
        fill = HexColor(Viridis(t)).data();
        if (t < 0.6) text_color = "#ffffff";
      } else if (v > 0) {
        fill = kBelowMinimum;
      }
      const double x = left + b * cell, y = top + a * cell;
      s << "<rect x=\"" << OneDecimal(x) << "\" y=\"" << OneDecimal(y) << "\" width=\"" << cell
        << "\" height=\"" << cell << "\" fill=\"" << fill
        << "\" stroke=\"#cccccc\" stroke-width=\"0.5\"/>\n";
      if (numbers && r.enabled[a] && r.enabled[b] && (v > 0 || a == b)) {
        const std::string text = v >= 10000 ? OneDecimal(v / 1000.0) + "k" : std::to_string(v);
        const int size = text.size() <= 3 ? 10 : 8;
        s << "<text x=\"" << OneDecimal(x + cell / 2.0) << "\" y=\""
          << OneDecimal(y + cell / 2.0 + size * 0.35) << "\" font-size=\"" << size
          << "\" text-anchor=\"middle\" fill=\"" << text_color << "\""
          << (a == b ? " font-style=\"italic\"" : "") << ">" << text << "</text>\n";
      }
    }
  }
  // Spanning tree outlines on top of every cell.
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      if (link[a][b])
        s << "<rect x=\"" << OneDecimal(left + b * cell + 1) << "\" y=\""
          << OneDecimal(top + a * cell + 1) << "\" width=\"" << cell - 2 << "\" height=\""
          << cell - 2 << "\" fill=\"none\" stroke=\""
          << (link[a][b] == 2 ? kUncalibratable : "#000000") << "\" stroke-width=\"2\"/>\n";
  s << "<rect x=\"" << OneDecimal(left) << "\" y=\"" << OneDecimal(top) << "\" width=\""
    << OneDecimal(side) << "\" height=\"" << OneDecimal(side)
    << "\" fill=\"none\" stroke=\"#555555\" stroke-width=\"1\"/>\n";

  // Legend: the ramp with its ends, then the special cells.
  const double ramp_w = 200, ramp_h = 12, lx = 12;
  s << "<text x=\"" << OneDecimal(lx) << "\" y=\"" << OneDecimal(legend_top - 6)
    << "\" font-size=\"11\">poses both cameras "
    << "observe (linked at &#8805; " << r.spec.min_shared << ")</text>\n";
  for (int i = 0; i < 50; ++i)
    s << "<rect x=\"" << OneDecimal(lx + ramp_w * i / 50) << "\" y=\"" << OneDecimal(legend_top)
      << "\" width=\"" << OneDecimal(ramp_w / 50 + 0.5) << "\" height=\"" << OneDecimal(ramp_h)
      << "\" fill=\"" << HexColor(Viridis((i + 0.5) / 50)).data() << "\"/>\n";
  s << "<text x=\"" << OneDecimal(lx) << "\" y=\"" << OneDecimal(legend_top + ramp_h + 12)
    << "\" font-size=\"10\">0</text>\n"
    << "<text x=\"" << OneDecimal(lx + ramp_w) << "\" y=\"" << OneDecimal(legend_top + ramp_h + 12)
    << "\" font-size=\"10\" text-anchor=\"end\">" << max_shared << "</text>\n";
  const double sx = lx + 265;
  const auto swatch = [&](double y, const std::string& rect_attrs, const std::string& text) {
    s << "<rect x=\"" << OneDecimal(sx) << "\" y=\"" << OneDecimal(y)
      << "\" width=\"12\" height=\"12\" " << rect_attrs << "/>\n"
      << "<text x=\"" << OneDecimal(sx + 18) << "\" y=\"" << OneDecimal(y + 10)
      << "\" font-size=\"10\">" << text << "</text>\n";
  };
  swatch(legend_top - 16, "fill=\"" + std::string(kBelowMinimum) + "\" stroke=\"#cccccc\"",
         "1 to " + std::to_string(std::max(1, r.spec.min_shared - 1)) + " shared: no link");
  swatch(legend_top, "fill=\"white\" stroke=\"#000000\" stroke-width=\"2\"", "spanning-tree link");
  swatch(legend_top + 16,
         "fill=\"white\" stroke=\"" + std::string(kUncalibratable) + "\" stroke-width=\"2\"",
         "weakest link");
  swatch(legend_top + 32, "fill=\"" + std::string(kComponentColors[0]) + "\"",
         "band: component (red id: uncalibratable)");
  s << "<text x=\"" << OneDecimal(lx) << "\" y=\"" << OneDecimal(legend_top + ramp_h + 28)
    << "\" font-size=\"10\" fill=\"#555555\">diagonal (italic): poses the camera observes</text>\n";
  s << "</svg>\n";
  return s.str();
}

std::string CalibrationIntroHtml(const CalibrationSpec& spec) {
  std::ostringstream s;
  s << "<p class=\"note\">A simulated calibration session (docs/calibration.md): " << spec.samples
    << " poses of a ";
  if (spec.target == CalibrationSpec::Target::kWand) {
    s << "<b>wand</b> (one marker, seen from all sides) at random points of the region's free "
         "space; "
         "a camera observes a pose when it sees the marker (visibility rules, occlusion by the "
         "scene "
         "included).";
  } else {
    const CalibrationBoard& b = spec.board;
    char size[64];
    std::snprintf(size, sizeof size, "%g", b.square_m * 1e3);
    s << "<b>board</b> of " << b.squares_x << " &times; " << b.squares_y << " squares of " << size
      << " mm, centred at random points of the region's free space, "
      << (spec.orientation == CalibrationSpec::Orientation::kTowardCamera
              ? "turned toward a camera that sees its centre"
              : "in uniformly random orientations")
      << "; a camera observes a pose when every grid corner projects into its image and is "
         "unoccluded, "
         "the board faces it within "
      << OneDecimal(b.tilt_max_deg) << "&deg;, and every square edge spans at least "
      << OneDecimal(b.min_px_per_square) << " px.";
  }
  s << " Two cameras are linked when they share at least " << spec.min_shared
    << " poses; a camera outside the largest linked group, or observing fewer poses, cannot be "
       "calibrated with the rest. Seed "
    << spec.seed << ".</p>\n";
  return s.str();
}

std::string CalibrationCellHtml(
    const CalibrationResult& r, const std::string& rig_name,
    const std::function<std::string(const std::string& svg, const std::string& alt)>& svg_image) {
  std::ostringstream s;
  const int n = static_cast<int>(r.camera_ids.size());
  s << "<p class=\"" << (r.calibratable ? "calib-ok" : "calib-bad") << "\">"
    << (r.calibratable ? "Calibratable as one rig" : "<b>Not calibratable as one rig</b>") << ": "
    << r.graph.components.size() << " component" << (r.graph.components.size() == 1 ? "" : "s")
    << ", " << r.graph.uncalibratable.size() << " uncalibratable camera"
    << (r.graph.uncalibratable.size() == 1 ? "" : "s") << "; " << r.poses_observed << " of "
    << r.poses << " poses seen by a camera, " << r.poses_shared << " by two or more (simulated in "
    << OneDecimal(r.seconds * 1e3) << " ms).</p>\n";
  s << svg_image(CalibrationMatrixSvg(r, "Co-visibility: " + rig_name),
                 rig_name + " calibration co-visibility matrix");
  s << "<div class=\"scroll\"><table "
       "class=\"calibration\"><thead><tr><th>camera</th><th>component</th>"
       "<th>poses</th><th>share</th><th style=\"text-align:left\">missed (first failing "
       "rule)</th></tr></thead><tbody>\n";
  for (int c = 0; c < n; ++c) {
    const bool bad = IsUncalibratable(r, c);
    s << "<tr"
      << (!r.enabled[c] ? " class=\"disabled\""
          : bad         ? " class=\"uncalibratable\""
                        : "")
      << "><td>" << HtmlEscape(r.camera_ids[c]) << "</td><td>";
    if (r.graph.component[c] >= 0)
      s << "<span class=\"swatch\" style=\"background:" << ComponentColor(r.graph.component[c])
        << "\"></span>" << r.graph.component[c] + 1 << (bad ? " (uncalibratable)" : "");
    else
      s << "disabled";
    s << "</td><td>" << r.observed[c] << "</td><td>"
      << (r.poses > 0 ? OneDecimal(100.0 * r.observed[c] / r.poses) + "%" : "&ndash;") << "</td>"
      << "<td style=\"text-align:left\">" << (r.enabled[c] ? MissText(r, c) : "&ndash;")
      << "</td></tr>\n";
  }
  s << "</tbody></table></div>\n";
  if (r.graph.weakest_links.empty()) {
    s << "<p class=\"note\">No links: no two cameras share " << r.spec.min_shared
      << " poses.</p>\n";
  } else {
    s << "<p class=\"note\">Weakest links of the calibration chain (the maximum spanning tree's "
         "edges, "
         "weakest first):</p>\n<table class=\"calibration\"><thead><tr><th>cameras</th><th>shared "
         "poses</th>"
         "</tr></thead><tbody>\n";
    const std::size_t shown = std::min<std::size_t>(r.graph.weakest_links.size(), 5);
    for (std::size_t k = 0; k < shown; ++k) {
      const CalibrationLink& l = r.graph.weakest_links[k];
      s << "<tr><td>" << HtmlEscape(r.camera_ids[l.a]) << " &ndash; "
        << HtmlEscape(r.camera_ids[l.b]) << "</td><td>" << l.shared << "</td></tr>\n";
    }
    s << "</tbody></table>\n";
  }
  return s.str();
}

}  // namespace pandora::report
