// The validation study's shared outputs (app/validate_report.h): its plot and verdict for
// `pandora validate`, and its cell of the report's "Predicted against measured" section.
#include "app/validate_report.h"

#include <algorithm>
#include <cmath>

#include "analysis/util/text.h"
#include "app/report/plot.h"
#include "app/report/table.h"

namespace pandora::app {

// Measured against predicted RMS per sigma bin and axis (log-log, the identity dashed).
std::string ValidationPlotSvg(const ValidateResult& r) {
  report::LogLogPlot plot;
  plot.title = "Measured against predicted error, by bin of predicted sigma";
  plot.x_label = "predicted RMS error along the axis (mm)";
  plot.y_label = "measured RMS error along the axis (mm)";
  plot.note = Format(
      "%zu corners triangulated from OpenCV's detections; pixel sigma %.3f px "
      "from their residuals",
      r.points.size(), r.sigma_px);
  static const char* const kAxis[3] = {"major", "middle", "minor"};
  double lo = 1e300, hi = 0;
  for (int a = 0; a < 3; ++a) {
    report::PlotSeries s;
    s.label = Format("%s axis", kAxis[a]);
    s.line = false;
    for (const ValidateBin& b : r.sigma_bins) {
      s.x.push_back(b.predicted_mm[a]);
      s.y.push_back(b.measured_mm[a]);
      lo = std::min(lo, b.predicted_mm[a]);
      hi = std::max(hi, b.predicted_mm[a]);
    }
    plot.series.push_back(s);
  }
  report::PlotSeries identity;
  identity.label = "measured = predicted";
  identity.markers = false;
  identity.dashed = true;
  if (hi > 0) identity.x = identity.y = {lo, hi};
  plot.series.push_back(identity);
  return report::RenderLogLogSvg(plot);
}

bool ValidationPasses(const ValidateResult& r, int min_bin, double tolerance) {
  bool pass = !r.sigma_bins.empty();
  for (const ValidateBin& b : r.sigma_bins)
    if (b.points >= min_bin)
      for (int a = 0; a < 3; ++a) pass = pass && std::abs(b.ratio[a] - 1) <= tolerance;
  return pass;
}

std::string ValidationCellHtml(
    const ValidateResult& r, int min_bin, double tolerance,
    const std::function<std::string(const std::string& svg, const std::string& alt)>& svg_image) {
  const bool pass = ValidationPasses(r, min_bin, tolerance);
  std::string html = Format(
      "<p>%s: %zu corners triangulated from %lld views (%s); detection noise %.3f px. Every bin "
      "of &ge; %d corners within %.0f %% on every axis: <b>%s</b>.</p>\n",
      report::HtmlEscape(r.board).c_str(), r.points.size(), (long long)r.views,
      Format("%d poses", r.poses).c_str(), r.sigma_px, min_bin, 100 * tolerance,
      pass ? "yes" : "no");
  html +=
      "<table><tr><th>predicted &sigma;max</th><th>corners</th><th>angle &deg;</th><th>major</th>"
      "<th>middle</th><th>minor</th><th>one &sigma;</th><th>skew</th></tr>\n";
  for (const ValidateBin& b : r.sigma_bins)
    html += Format(
        "<tr><td>%s</td><td>%d</td><td>%.1f</td><td>%.3f</td><td>%.3f</td><td>%.3f</td>"
        "<td>%.2f/%.2f/%.2f</td><td>%.2f</td></tr>\n",
        report::HtmlEscape(b.label).c_str(), b.points, b.median_angle_deg, b.ratio[0], b.ratio[1],
        b.ratio[2], b.ratio_one_sigma[0], b.ratio_one_sigma[1], b.ratio_one_sigma[2], b.skew_major);
  html += "</table>\n";
  if (!r.sigma_bins.empty())
    html += svg_image(ValidationPlotSvg(r), "measured against predicted error per bin and axis");
  for (const std::string& n : r.notes)
    html += "<p class=\"note\">" + report::HtmlEscape(n) + "</p>\n";
  return html;
}

}  // namespace pandora::app
