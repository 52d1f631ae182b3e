#pragma once
/// \file plot.h
/// A small self-contained SVG writer for log-log line plots (error against run time): decade ticks
/// and labels, minor ticks, axis labels, a legend, optional per-point labels and vertical marker
/// lines. No dependencies; the output is a standalone SVG 1.1 document that browsers, GitHub and
/// Inkscape display.

#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace pandora::report {

/// One data series. Points whose x or y is not finite and positive cannot be placed on log axes;
/// they are skipped and break the line there.
struct PlotSeries {
  std::string label;                      ///< Legend entry.
  std::vector<double> x, y;               ///< Same length.
  std::vector<std::string> point_labels;  ///< Empty, or one (possibly empty) label per point.
  bool line = true;                       ///< Connect consecutive points.
  bool markers = true;                    ///< Draw a marker at each point.
  bool dashed = false;                    ///< Dashed line (guides, fits).
  std::string color;      ///< SVG colour; empty: the palette's colour for the series' index.
  int shape = -1;         ///< Marker 0 circle, 1 square, 2 triangle, 3 diamond; -1: the next one.
  bool in_legend = true;  ///< A series without points and with in_legend is a legend-only key.
  bool labels_below = false;  ///< Point labels below the points instead of above.
};

/// A vertical line across the plot at `x` with a label at its top.
struct PlotMarker {
  double x = 1;
  std::string label;
};

/// A log-log plot. Both axes are log10; their ranges are whole decades that hold every point and
/// every marker, with room for point labels at the top and right.
struct LogLogPlot {
  std::string title;
  std::string x_label, y_label;
  std::string note;  ///< Small text under the x axis label (empty: none).
  std::vector<PlotSeries> series;
  std::vector<PlotMarker> vertical_lines;
  int width = 880, height = 500;  ///< Pixels, legend column included.
};

/// Renders `plot` as an SVG document (UTF-8 text). Text is XML-escaped. With no plottable point the
/// axes span 1 to 10 and the plot says "no data".
std::string RenderLogLogSvg(const LogLogPlot& plot);

/// One series of a bar chart: a value per category.
struct BarSeries {
  std::string label;           ///< Legend entry (no legend when there is one series).
  std::vector<double> values;  ///< One per category; non-finite values draw no bar.
  std::string color;           ///< Empty: the palette's colour for the series' index.
};

/// A bar chart on a linear y axis from 0: categories along x (bins), the series' bars side by side
/// within each category.
struct BarChart {
  std::string title;
  std::string x_label, y_label;
  std::string note;                     ///< Small text under the x axis label.
  std::vector<std::string> categories;  ///< Labels under the bars; thinned to fit when many.
  std::vector<BarSeries> series;
  double y_max = std::numeric_limits<double>::quiet_NaN();  ///< NaN: from the data.
  bool percent = false;  ///< Tick labels as percentages of 1 (0.25 -> "25%").
  /// Category labels at the left edge of their bar (bins of a continuous value, labelled by their
  /// lower bound) instead of under its centre.
  bool edge_labels = false;
  /// Numeric bins (a histogram): category i covers [bin_origin + i bin_width, + bin_width). When
  /// bin_width > 0 the category labels are thinned to the bins whose lower edge is a multiple of a
  /// 1-2-5 step (NiceLabelStep), so the axis reads 0, 0.1, 0.2, ... rather than 0, 0.06, 0.12.
  double bin_width = 0;
  double bin_origin = 0;
  /// A vertical dashed line at a position in category units (0 = left edge of the first bin,
  /// categories.size() = right edge of the last); NaN: none.
  double marker = std::numeric_limits<double>::quiet_NaN();
  std::string marker_label;
  int width = 560, height = 320;
};

/// Renders `chart` as a standalone SVG document. With no category the plot says "no data".
std::string RenderBarChartSvg(const BarChart& chart);

/// A horizontal colour bar legend for a viridis-coloured image (analysis/util/color.h): the ramp
/// from `min` to `max` with ticks, the label (quantity and unit), and swatches for the special
/// colours.
struct Colorbar {
  std::string label;  ///< E.g. "sigma_max (mm)".
  double min = 0, max = 1;
  /// Whole numbers from min to max in equal steps (coverage): one box per value instead of a ramp.
  bool discrete = false;
  bool max_is_open = false;  ///< Values above max are drawn in the max colour: label it ">= max".
  std::vector<std::pair<std::string, std::string>> swatches;  ///< (colour "#rrggbb", label).
  int width = 420, height = 74;
};

/// Renders `bar` as a standalone SVG document.
std::string RenderColorbarSvg(const Colorbar& bar);

/// "Nice" axis ticks (1, 2 or 5 times a power of ten) covering [0, max], about `count` of them.
std::vector<double> NiceTicks(double max, int count = 5);

/// The smallest 1, 2 or 5 times a power of ten that is >= raw (raw > 0 and finite; else 1).
double NiceStep(double raw);

/// The label step of a histogram with bins of `bin_width`: the smallest 1, 2 or 5 times a power of
/// ten that is at least `min_step` and a whole multiple of bin_width (to 1e-9 relative); when
/// bin_width is not itself such a number, the smallest whole multiple of it >= min_step.
double NiceLabelStep(double bin_width, double min_step);

}  // namespace pandora::report
