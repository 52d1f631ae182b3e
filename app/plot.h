#pragma once
/// \file plot.h
/// A small self-contained SVG writer for log-log line plots (error against run time): decade ticks
/// and labels, minor ticks, axis labels, a legend, optional per-point labels and vertical marker
/// lines. No dependencies; the output is a standalone SVG 1.1 document that browsers, GitHub and
/// Inkscape display.

#include <string>
#include <vector>

namespace pandora::app {

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

}  // namespace pandora::app
