#include "app/report/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "analysis/util/color.h"
#include "app/report/table.h"

namespace pandora::report {
namespace {

// Tableau 10, colour-blind friendly enough for a handful of series.
constexpr const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                   "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
constexpr int kColorCount = sizeof(kColors) / sizeof(kColors[0]);

bool Plottable(double v) { return std::isfinite(v) && v > 0; }

// Text in the SVG, escaped as the report's HTML is.
std::string Escape(const std::string& s) { return HtmlEscape(s); }

std::string Num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

// Whole decades [lo, hi] (log10) holding [min, max]; at least one decade wide. The top keeps
// `head_room` decades above the largest value (room for its label).
void DecadeRange(double min_value, double max_value, double head_room, int* lo, int* hi) {
  if (!(min_value <= max_value)) {
    *lo = 0;
    *hi = 1;
    return;
  }
  *lo = static_cast<int>(std::floor(std::log10(min_value) - 1e-9));
  *hi = static_cast<int>(std::ceil(std::log10(max_value) + head_room));
  if (*hi <= *lo) *hi = *lo + 1;
}

// "10" with the exponent as a superscript (U+2212 for minus).
std::string DecadeLabel(int k) {
  if (k == 0) return "1";
  if (k == 1) return "10";
  std::string exponent = k < 0 ? "\u2212" + std::to_string(-k) : std::to_string(k);
  return "10<tspan dy=\"-7\" font-size=\"10\">" + exponent + "</tspan>";
}

void Marker(std::ostringstream& o, int shape, double x, double y, const char* color) {
  const double r = 4;
  switch (shape % 4) {
    case 0:
      o << "<circle cx=\"" << Num(x) << "\" cy=\"" << Num(y) << "\" r=\"" << r << "\" fill=\""
        << color << "\"/>\n";
      break;
    case 1:
      o << "<rect x=\"" << Num(x - r) << "\" y=\"" << Num(y - r) << "\" width=\"" << 2 * r
        << "\" height=\"" << 2 * r << "\" fill=\"" << color << "\"/>\n";
      break;
    case 2:
      o << "<polygon points=\"" << Num(x) << "," << Num(y - 1.2 * r) << " " << Num(x - 1.1 * r)
        << "," << Num(y + 0.8 * r) << " " << Num(x + 1.1 * r) << "," << Num(y + 0.8 * r)
        << "\" fill=\"" << color << "\"/>\n";
      break;
    default:
      o << "<polygon points=\"" << Num(x) << "," << Num(y - 1.3 * r) << " " << Num(x + 1.3 * r)
        << "," << Num(y) << " " << Num(x) << "," << Num(y + 1.3 * r) << " " << Num(x - 1.3 * r)
        << "," << Num(y) << "\" fill=\"" << color << "\"/>\n";
  }
}

// A log-log plot being drawn: the plot, its frame in pixels, its whole decades, the SVG so far, and
// the colour and marker shape of each series.
struct LogLogCanvas {
  LogLogCanvas(const LogLogPlot& plot, double left, double right, double top, double bottom,
               int xlo, int xhi, int ylo, int yhi)
      : plot(plot),
        left(left),
        right(right),
        top(top),
        bottom(bottom),
        xlo(xlo),
        xhi(xhi),
        ylo(ylo),
        yhi(yhi) {}

  // The x pixel of data value x.
  double Px(double x) const { return left + (std::log10(x) - xlo) / (xhi - xlo) * (right - left); }
  // The y pixel of data value y.
  double Py(double y) const {
    return bottom - (std::log10(y) - ylo) / (yhi - ylo) * (bottom - top);
  }

  void GridAndTicks();
  void FrameAndLabels(bool has_data);
  void VerticalMarkers();
  void Series();
  void Legend();

  const LogLogPlot& plot;
  const double left, right, top, bottom;
  const int xlo, xhi, ylo, yhi;
  std::ostringstream o;
  std::vector<std::string> colors;
  std::vector<int> shapes;
};

// Grid and ticks. Label every decade, or every 2nd/3rd when there are many.
void LogLogCanvas::GridAndTicks() {
  auto step_for = [](int decades) { return decades <= 9 ? 1 : decades <= 18 ? 2 : 3; };
  const int xstep = step_for(xhi - xlo), ystep = step_for(yhi - ylo);
  o << "<g stroke=\"#e4e4e4\" stroke-width=\"1\">\n";
  for (int k = xlo; k <= xhi; ++k) {
    const double x = left + double(k - xlo) / (xhi - xlo) * (right - left);
    o << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(top) << "\" x2=\"" << Num(x) << "\" y2=\""
      << Num(bottom) << "\"/>\n";
  }
  for (int k = ylo; k <= yhi; ++k) {
    const double y = bottom - double(k - ylo) / (yhi - ylo) * (bottom - top);
    o << "<line x1=\"" << Num(left) << "\" y1=\"" << Num(y) << "\" x2=\"" << Num(right)
      << "\" y2=\"" << Num(y) << "\"/>\n";
  }
  o << "</g>\n<g stroke=\"black\" stroke-width=\"1\">\n";
  const bool x_minor = xhi - xlo <= 6, y_minor = yhi - ylo <= 6;
  for (int k = xlo; k <= xhi; ++k) {
    const double x = Px(std::pow(10.0, k));
    o << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(bottom) << "\" x2=\"" << Num(x) << "\" y2=\""
      << Num(bottom + 6) << "\"/>\n";
    if (x_minor && k < xhi)
      for (int m = 2; m <= 9; ++m) {
        const double xm = Px(m * std::pow(10.0, k));
        o << "<line x1=\"" << Num(xm) << "\" y1=\"" << Num(bottom) << "\" x2=\"" << Num(xm)
          << "\" y2=\"" << Num(bottom + 3) << "\"/>\n";
      }
  }
  for (int k = ylo; k <= yhi; ++k) {
    const double y = Py(std::pow(10.0, k));
    o << "<line x1=\"" << Num(left - 6) << "\" y1=\"" << Num(y) << "\" x2=\"" << Num(left)
      << "\" y2=\"" << Num(y) << "\"/>\n";
    if (y_minor && k < yhi)
      for (int m = 2; m <= 9; ++m) {
        const double ym = Py(m * std::pow(10.0, k));
        o << "<line x1=\"" << Num(left - 3) << "\" y1=\"" << Num(ym) << "\" x2=\"" << Num(left)
          << "\" y2=\"" << Num(ym) << "\"/>\n";
      }
  }
  o << "</g>\n";
  for (int k = xlo; k <= xhi; k += xstep)
    o << "<text x=\"" << Num(Px(std::pow(10.0, k))) << "\" y=\"" << Num(bottom + 22)
      << "\" text-anchor=\"middle\">" << DecadeLabel(k) << "</text>\n";
  for (int k = ylo; k <= yhi; k += ystep)
    o << "<text x=\"" << Num(left - 10) << "\" y=\"" << Num(Py(std::pow(10.0, k)) + 4)
      << "\" text-anchor=\"end\">" << DecadeLabel(k) << "</text>\n";
}

// The frame, the axis labels, the note, and "no data" when nothing is plottable.
void LogLogCanvas::FrameAndLabels(bool has_data) {
  o << "<rect x=\"" << Num(left) << "\" y=\"" << Num(top) << "\" width=\"" << Num(right - left)
    << "\" height=\"" << Num(bottom - top) << "\" fill=\"none\" stroke=\"black\"/>\n";
  o << "<text x=\"" << Num((left + right) / 2) << "\" y=\"" << Num(bottom + 42)
    << "\" text-anchor=\"middle\" font-size=\"13\">" << Escape(plot.x_label) << "</text>\n";
  const double ymid = (top + bottom) / 2;
  o << "<text x=\"18\" y=\"" << Num(ymid) << "\" text-anchor=\"middle\" font-size=\"13\" "
    << "transform=\"rotate(-90 18 " << Num(ymid) << ")\">" << Escape(plot.y_label) << "</text>\n";
  if (!plot.note.empty())
    o << "<text x=\"" << Num(left) << "\" y=\"" << Num(bottom + 62)
      << "\" font-size=\"11\" fill=\"#555\">" << Escape(plot.note) << "</text>\n";
  if (!has_data)
    o << "<text x=\"" << Num((left + right) / 2) << "\" y=\"" << Num(ymid)
      << "\" text-anchor=\"middle\" fill=\"#888\">no data</text>\n";
}

// Vertical markers.
void LogLogCanvas::VerticalMarkers() {
  for (const PlotMarker& m : plot.vertical_lines) {
    if (!Plottable(m.x)) continue;
    const double x = Px(m.x);
    o << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(top) << "\" x2=\"" << Num(x) << "\" y2=\""
      << Num(bottom) << "\" stroke=\"#444\" stroke-width=\"1.5\" stroke-dasharray=\"2,3\"/>\n";
    o << "<text x=\"" << Num(x + 4) << "\" y=\"" << Num(top + 14) << "\" font-size=\"11\" "
      << "fill=\"#444\">" << Escape(m.label) << "</text>\n";
  }
}

// Series, clipped to the frame; their point labels after them, unclipped.
void LogLogCanvas::Series() {
  o << "<clipPath id=\"frame\"><rect x=\"" << Num(left - 6) << "\" y=\"" << Num(top - 6)
    << "\" width=\"" << Num(right - left + 12) << "\" height=\"" << Num(bottom - top + 12)
    << "\"/></clipPath>\n<g clip-path=\"url(#frame)\">\n";
  // Colour and marker shape of each series.
  int next_shape = 0;
  for (std::size_t si = 0; si < plot.series.size(); ++si) {
    const PlotSeries& s = plot.series[si];
    colors.push_back(s.color.empty() ? kColors[si % kColorCount] : s.color);
    shapes.push_back(s.shape >= 0 ? s.shape : s.markers ? next_shape++ : 0);
  }
  std::ostringstream labels;  // point labels, drawn unclipped after the series
  for (std::size_t si = 0; si < plot.series.size(); ++si) {
    const PlotSeries& s = plot.series[si];
    const char* color = colors[si].c_str();
    const std::size_t n = std::min(s.x.size(), s.y.size());
    if (s.line) {
      std::string d;
      bool pen_down = false;
      for (std::size_t i = 0; i < n; ++i) {
        if (!Plottable(s.x[i]) || !Plottable(s.y[i])) {
          pen_down = false;
          continue;
        }
        d += (pen_down ? " L" : " M") + Num(Px(s.x[i])) + "," + Num(Py(s.y[i]));
        pen_down = true;
      }
      if (!d.empty())
        o << "<path d=\"" << d.substr(1) << "\" fill=\"none\" stroke=\"" << color
          << "\" stroke-width=\"1.8\"" << (s.dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (!Plottable(s.x[i]) || !Plottable(s.y[i])) continue;
      const double x = Px(s.x[i]), y = Py(s.y[i]);
      if (s.markers) Marker(o, shapes[si], x, y, color);
      if (i < s.point_labels.size() && !s.point_labels[i].empty()) {
        const bool near_right = x > right - 70;  // keep the label inside the frame
        labels << "<text x=\"" << Num(near_right ? x - 6 : x + 6) << "\" y=\""
               << Num(s.labels_below ? y + 15 : y - 6) << "\" font-size=\"10\" fill=\"" << color
               << "\"" << (near_right ? " text-anchor=\"end\"" : "") << ">"
               << Escape(s.point_labels[i]) << "</text>\n";
      }
    }
  }
  o << "</g>\n" << labels.str();
}

// Legend, in its own column right of the frame (after Series, which picks the colours and shapes).
void LogLogCanvas::Legend() {
  double ly = top + 8;
  for (std::size_t si = 0; si < plot.series.size(); ++si) {
    const PlotSeries& s = plot.series[si];
    if (!s.in_legend) continue;
    const char* color = colors[si].c_str();
    const double lx = right + 18;
    if (s.line)
      o << "<line x1=\"" << Num(lx) << "\" y1=\"" << Num(ly) << "\" x2=\"" << Num(lx + 26)
        << "\" y2=\"" << Num(ly) << "\" stroke=\"" << color << "\" stroke-width=\"1.8\""
        << (s.dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
    if (s.markers) Marker(o, shapes[si], lx + 13, ly, color);
    o << "<text x=\"" << Num(lx + 34) << "\" y=\"" << Num(ly + 4) << "\">" << Escape(s.label)
      << "</text>\n";
    ly += 20;
  }
}

}  // namespace

std::string RenderLogLogSvg(const LogLogPlot& plot) {
  const double inf = std::numeric_limits<double>::infinity();
  double x_min = inf, x_max = -inf, y_min = inf, y_max = -inf;
  for (const PlotSeries& s : plot.series)
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (Plottable(s.x[i]) && Plottable(s.y[i])) {
        x_min = std::min(x_min, s.x[i]);
        x_max = std::max(x_max, s.x[i]);
        y_min = std::min(y_min, s.y[i]);
        y_max = std::max(y_max, s.y[i]);
      }
  const bool has_data = x_min <= x_max;
  for (const PlotMarker& m : plot.vertical_lines)
    if (Plottable(m.x)) {
      x_min = std::min(x_min, m.x);
      x_max = std::max(x_max, m.x);
    }
  int xlo, xhi, ylo, yhi;
  DecadeRange(x_min, x_max, 0.12, &xlo, &xhi);
  DecadeRange(y_min, y_max, 0.05, &ylo, &yhi);

  const double W = plot.width, H = plot.height;
  const double left = 78, right = W - 240, top = 42, bottom = H - (plot.note.empty() ? 62 : 80);
  LogLogCanvas canvas(plot, left, right, top, bottom, xlo, xhi, ylo, yhi);

  std::ostringstream& o = canvas.o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << plot.width
    << "\" height=\"" << plot.height << "\" viewBox=\"0 0 " << plot.width << " " << plot.height
    << "\" font-family=\"DejaVu Sans, Arial, Helvetica, sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<text x=\"" << Num((left + right) / 2) << "\" y=\"24\" text-anchor=\"middle\" "
    << "font-size=\"15\" font-weight=\"bold\">" << Escape(plot.title) << "</text>\n";

  canvas.GridAndTicks();
  canvas.FrameAndLabels(has_data);
  canvas.VerticalMarkers();
  canvas.Series();
  canvas.Legend();
  o << "</svg>\n";
  return o.str();
}

std::vector<double> NiceTicks(double max, int count) {
  if (!(max > 0) || !std::isfinite(max)) return {0.0, 1.0};
  const double raw = max / std::max(1, count);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = power;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw * (1 - 1e-9)) {
      step = m * power;
      break;
    }
  std::vector<double> ticks;
  for (int k = 0; k * step <= max * (1 + 1e-9) || ticks.size() < 2; ++k) ticks.push_back(k * step);
  if (ticks.back() < max * (1 - 1e-9)) ticks.push_back(ticks.back() + step);
  return ticks;
}

double NiceStep(double raw) {
  if (!(raw > 0) || !std::isfinite(raw)) return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw * (1 - 1e-9)) return m * power;
  return 10.0 * power;
}

double NiceLabelStep(double bin_width, double min_step) {
  if (!(bin_width > 0) || !std::isfinite(bin_width)) return 1.0;
  min_step = std::max(min_step, bin_width);
  auto whole = [](double x) { return std::abs(x - std::round(x)) <= 1e-9 * std::max(1.0, x); };
  // Candidates 1, 2, 5 x 10^k from NiceStep(min_step) upward; a 1-2-5 bin width always has one
  // within three decades.
  double power = std::pow(10.0, std::floor(std::log10(NiceStep(min_step))));
  for (int decade = 0; decade < 4; ++decade, power *= 10)
    for (double m : {1.0, 2.0, 5.0}) {
      const double step = m * power;
      if (step >= min_step * (1 - 1e-9) && whole(step / bin_width)) return step;
    }
  return std::ceil(min_step / bin_width - 1e-9) * bin_width;
}

namespace {

// Tick label: up to 3 significant digits, or a percentage.
std::string TickLabel(double v, bool percent) {
  char b[32];
  if (percent)
    std::snprintf(b, sizeof b, "%g%%", std::round(v * 1e5) / 1e3);
  else
    std::snprintf(b, sizeof b, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return b;
}

std::string SvgHeader(int width, int height) {
  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << width
    << "\" height=\"" << height << "\" viewBox=\"0 0 " << width << " " << height
    << "\" font-family=\"DejaVu Sans, Arial, Helvetica, sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  return o.str();
}

}  // namespace

std::string RenderBarChartSvg(const BarChart& chart) {
  const std::size_t n = chart.categories.size();
  double data_max = 0;
  for (const BarSeries& s : chart.series)
    for (double v : s.values)
      if (std::isfinite(v)) data_max = std::max(data_max, v);
  const double y_top_value = std::isfinite(chart.y_max) && chart.y_max > 0 ? chart.y_max : data_max;
  const std::vector<double> ticks = NiceTicks(y_top_value > 0 ? y_top_value : 1.0);
  const double y_top = ticks.back();
  const bool legend = chart.series.size() > 1;
  const double W = chart.width, H = chart.height;
  const double left = 64, right = W - (legend ? 130 : 16), top = 40;
  const double bottom = H - (chart.note.empty() ? 58 : 74);
  auto py = [&](double y) { return bottom - std::min(y, y_top) / y_top * (bottom - top); };

  std::ostringstream o;
  o << SvgHeader(chart.width, chart.height);
  o << "<text x=\"" << Num((left + right) / 2) << "\" y=\"22\" text-anchor=\"middle\" "
    << "font-size=\"14\" font-weight=\"bold\">" << Escape(chart.title) << "</text>\n";
  o << "<g stroke=\"#e4e4e4\" stroke-width=\"1\">\n";
  for (double t : ticks)
    o << "<line x1=\"" << Num(left) << "\" y1=\"" << Num(py(t)) << "\" x2=\"" << Num(right)
      << "\" y2=\"" << Num(py(t)) << "\"/>\n";
  o << "</g>\n<g text-anchor=\"end\" fill=\"#333\">\n";
  for (double t : ticks)
    o << "<text x=\"" << Num(left - 6) << "\" y=\"" << Num(py(t) + 4) << "\">"
      << TickLabel(t, chart.percent) << "</text>\n";
  o << "</g>\n";
  if (n == 0) {
    o << "<text x=\"" << Num((left + right) / 2) << "\" y=\"" << Num((top + bottom) / 2)
      << "\" text-anchor=\"middle\" fill=\"#888\">no data</text>\n";
  } else {
    const double bin = (right - left) / n;
    const std::size_t k = std::max<std::size_t>(1, chart.series.size());
    const double gap = std::min(0.15 * bin, 6.0);
    const double bar = (bin - 2 * gap) / k;
    for (std::size_t si = 0; si < chart.series.size(); ++si) {
      const BarSeries& s = chart.series[si];
      const std::string color = s.color.empty() ? kColors[si % kColorCount] : s.color;
      o << "<g fill=\"" << Escape(color) << "\">\n";
      for (std::size_t i = 0; i < n && i < s.values.size(); ++i) {
        const double v = s.values[i];
        if (!std::isfinite(v) || v <= 0) continue;
        const double x = left + i * bin + gap + si * bar;
        o << "<rect x=\"" << Num(x) << "\" y=\"" << Num(py(v)) << "\" width=\""
          << Num(std::max(bar - 1, 0.5)) << "\" height=\"" << Num(bottom - py(v)) << "\"/>\n";
      }
      o << "</g>\n";
    }
    // Category labels: every one when they fit (about 7 px per character), else thinned.
    std::size_t longest = 1;
    for (const std::string& c : chart.categories) longest = std::max(longest, c.size());
    std::size_t every =
        std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil((longest * 7.0 + 6) / bin)));
    std::size_t first = 0;
    if (chart.bin_width > 0) {
      // Numeric bins: label the lower edges that are multiples of a 1-2-5 step.
      const double step = NiceLabelStep(chart.bin_width, every * chart.bin_width);
      every =
          std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(step / chart.bin_width)));
      // Bin i's lower edge is bin_origin + i bin_width: the first label where it is a multiple.
      const long long e = static_cast<long long>(every);
      const long long origin_index = std::llround(chart.bin_origin / chart.bin_width);
      first = static_cast<std::size_t>(((-origin_index) % e + e) % e);
    }
    o << "<g text-anchor=\"middle\" fill=\"#333\">\n";
    for (std::size_t i = first; i < n; i += every)
      o << "<text x=\"" << Num(left + (i + (chart.edge_labels ? 0.0 : 0.5)) * bin) << "\" y=\""
        << Num(bottom + 16) << "\">" << Escape(chart.categories[i]) << "</text>\n";
    o << "</g>\n";
    if (std::isfinite(chart.marker)) {
      const double x = left + std::clamp(chart.marker, 0.0, double(n)) * bin;
      o << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(top) << "\" x2=\"" << Num(x) << "\" y2=\""
        << Num(bottom) << "\" stroke=\"#d62728\" stroke-width=\"1.5\" stroke-dasharray=\"5,4\"/>\n"
        << "<text x=\"" << Num(x + 4) << "\" y=\"" << Num(top + 12) << "\" fill=\"#d62728\">"
        << Escape(chart.marker_label) << "</text>\n";
    }
  }
  o << "<line x1=\"" << Num(left) << "\" y1=\"" << Num(bottom) << "\" x2=\"" << Num(right)
    << "\" y2=\"" << Num(bottom) << "\" stroke=\"#333\"/>\n"
    << "<line x1=\"" << Num(left) << "\" y1=\"" << Num(top) << "\" x2=\"" << Num(left) << "\" y2=\""
    << Num(bottom) << "\" stroke=\"#333\"/>\n";
  o << "<text x=\"" << Num((left + right) / 2) << "\" y=\"" << Num(bottom + 36)
    << "\" text-anchor=\"middle\">" << Escape(chart.x_label) << "</text>\n";
  if (!chart.note.empty())
    o << "<text x=\"" << Num((left + right) / 2) << "\" y=\"" << Num(bottom + 54)
      << "\" text-anchor=\"middle\" font-size=\"10\" fill=\"#666\">" << Escape(chart.note)
      << "</text>\n";
  o << "<text transform=\"translate(16," << Num((top + bottom) / 2)
    << ") rotate(-90)\" text-anchor=\"middle\">" << Escape(chart.y_label) << "</text>\n";
  if (legend) {
    double y = top + 6;
    for (std::size_t si = 0; si < chart.series.size(); ++si, y += 20) {
      const std::string color =
          chart.series[si].color.empty() ? kColors[si % kColorCount] : chart.series[si].color;
      o << "<rect x=\"" << Num(right + 14) << "\" y=\"" << Num(y)
        << "\" width=\"12\" height=\"12\" "
        << "fill=\"" << Escape(color) << "\"/><text x=\"" << Num(right + 32) << "\" y=\""
        << Num(y + 11) << "\">" << Escape(chart.series[si].label) << "</text>\n";
    }
  }
  o << "</svg>\n";
  return o.str();
}

std::string RenderColorbarSvg(const Colorbar& bar) {
  const double W = bar.width;
  const double left = 14, top = 24, height = 16;
  // Swatches take the right part: about 8 px per character plus the box.
  double swatch_width = 0;
  for (const auto& s : bar.swatches) swatch_width += 28 + 6.5 * s.second.size();
  const double right = std::max(left + 120, W - 14 - swatch_width);
  const double span = bar.max - bar.min;
  std::ostringstream o;
  o << SvgHeader(bar.width, bar.height);
  o << "<text x=\"" << Num(left) << "\" y=\"16\" font-weight=\"bold\">" << Escape(bar.label)
    << "</text>\n";
  std::vector<double> ticks;
  if (bar.discrete) {
    const int lo = static_cast<int>(std::lround(bar.min)),
              hi = static_cast<int>(std::lround(bar.max));
    const int count = std::max(1, hi - lo + 1);
    const double w = (right - left) / count;
    for (int k = 0; k < count; ++k) {
      const double t = count > 1 ? double(k) / (count - 1) : 1.0;
      o << "<rect x=\"" << Num(left + k * w) << "\" y=\"" << Num(top) << "\" width=\"" << Num(w)
        << "\" height=\"" << Num(height) << "\" fill=\"" << HexColor(Viridis(t)).data() << "\"/>\n";
      o << "<text x=\"" << Num(left + (k + 0.5) * w) << "\" y=\"" << Num(top + height + 14)
        << "\" text-anchor=\"middle\" fill=\"#333\">" << (lo + k) << "</text>\n";
    }
  } else {
    o << "<defs><linearGradient id=\"ramp\" x1=\"0\" x2=\"1\" y1=\"0\" y2=\"0\">\n";
    for (int k = 0; k <= 16; ++k)
      o << "<stop offset=\"" << Num(k / 16.0) << "\" stop-color=\""
        << HexColor(Viridis(k / 16.0)).data() << "\"/>\n";
    o << "</linearGradient></defs>\n<rect x=\"" << Num(left) << "\" y=\"" << Num(top)
      << "\" width=\"" << Num(right - left) << "\" height=\"" << Num(height)
      << "\" fill=\"url(#ramp)\" stroke=\"#333\" stroke-width=\"0.5\"/>\n";
    const double step_max = span > 0 ? span : 1.0;
    for (double t : NiceTicks(step_max, 4)) {
      if (t > span * (1 + 1e-9)) break;
      const double x = left + (span > 0 ? t / span : 0) * (right - left);
      const bool last = bar.max_is_open && std::abs(t - span) < 1e-9 * std::max(1.0, span);
      o << "<line x1=\"" << Num(x) << "\" y1=\"" << Num(top + height) << "\" x2=\"" << Num(x)
        << "\" y2=\"" << Num(top + height + 4) << "\" stroke=\"#333\"/>\n"
        << "<text x=\"" << Num(x) << "\" y=\"" << Num(top + height + 16)
        << "\" text-anchor=\"middle\" fill=\"#333\">" << (last ? "\u2265" : "")
        << TickLabel(bar.min + t, false) << "</text>\n";
    }
    if (bar.max_is_open && span > 0 && std::abs(NiceTicks(span, 4).back() - span) > 1e-9 * span)
      o << "<text x=\"" << Num(right) << "\" y=\"" << Num(top - 4)
        << "\" text-anchor=\"end\" font-size=\"10\" fill=\"#333\">\u2265"
        << TickLabel(bar.max, false) << " in the top colour</text>\n";
  }
  double x = right + 14;
  for (const auto& [color, label] : bar.swatches) {
    o << "<rect x=\"" << Num(x) << "\" y=\"" << Num(top) << "\" width=\"16\" height=\""
      << Num(height) << "\" fill=\"" << Escape(color) << "\" stroke=\"#333\" stroke-width=\"0.5\"/>"
      << "<text x=\"" << Num(x + 20) << "\" y=\"" << Num(top + 12) << "\">" << Escape(label)
      << "</text>\n";
    x += 28 + 6.5 * label.size();
  }
  o << "</svg>\n";
  return o.str();
}
}  // namespace pandora::report
