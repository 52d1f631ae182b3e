// The tables, CSV files and plots of `pandora accuracy` (app/report/accuracy_tables.h).
#include "app/report/accuracy_tables.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "app/report/plot.h"

namespace pandora::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Millimetres(double metres) { return Format("%g mm", 1e3 * metres); }

double RelativeError(double value, double reference) {
  return std::fabs(value - reference) / std::fabs(reference);
}

}  // namespace

std::string AccuracySection::Text() const {
  std::string out = "\n" + title + "\n" + table.Text();
  for (const std::string& n : notes) out += "  note: " + n + "\n";
  return out;
}

std::string AccuracySection::Markdown() const {
  std::string out = "## " + title + "\n\n" + table.Markdown();
  for (const std::string& n : notes) out += "\n- " + n;
  return out + "\n\n";
}

std::string AccuracyTablesHeading(const std::string& scene_path, const std::string& rig) {
  return "# pandora accuracy: " + scene_path + ", rig " + rig + "\n\n";
}

AccuracySection VoxelSection(const VoxelStudy& v) {
  AccuracySection section;
  section.title = "(a) Voxel size against the error of the summaries (reference: the finest size)";
  section.csv_name = "accuracy_voxel.csv";
  section.svg_name = "accuracy_voxel.svg";
  section.notes = v.notes;
  std::vector<std::string> header{"voxel_size_m",
                                  "factor",
                                  "reference",
                                  "region_voxels",
                                  "triangulable_voxels",
                                  "seconds",
                                  "repeats",
                                  "time_ratio",
                                  "ge1",
                                  "ge2",
                                  "ge3",
                                  "ge1_err_pp",
                                  "ge2_err_pp",
                                  "ge3_err_pp",
                                  "sigma_max_p50_mm",
                                  "sigma_max_p90_mm",
                                  "sigma_max_p50_err_pct",
                                  "sigma_max_p90_err_pct"};
  if (v.steady)
    for (const char* h : {"sigma_max_steady_p50_mm", "sigma_max_steady_p90_mm",
                          "sigma_max_steady_p50_err_pct", "sigma_max_steady_p90_err_pct"})
      header.push_back(h);
  std::vector<std::string> th{"voxel",    "voxels",      "time (s)", "x ref",
                              "|Δ≥1| pp", "|Δ≥2| pp",    "|Δ≥3| pp", "σmax p50 mm",
                              "err %",    "σmax p90 mm", "err %"};
  if (v.steady)
    for (const char* h : {"steady p50 mm", "err %", "steady p90 mm", "err %"}) th.push_back(h);
  section.table = Table(th);
  std::vector<std::vector<std::string>> csv;
  LogLogPlot plot;
  plot.title = "Voxel size: summary error against run time";
  plot.x_label = "evaluation time (s)";
  plot.y_label = "error against the finest size (pp or %)";
  if (v.rows.empty()) {  // not even the coarsest size fits the memory budget
    section.csv = CsvText(header, csv);
    section.svg = RenderLogLogSvg(plot);
    return section;
  }
  const VoxelRow& ref = v.rows.back();
  plot.note = Format("reference: %s voxels; zero errors are not drawn (log axis)",
                     Millimetres(ref.voxel_size).c_str());
  std::vector<PlotSeries> series(v.steady ? 7 : 5);
  series[0].label = "|Δ coverage ≥1| (pp)";
  series[1].label = "|Δ coverage ≥2| (pp)";
  series[2].label = "|Δ coverage ≥3| (pp)";
  series[3].label = "σmax p50 (%)";
  series[4].label = "σmax p90 (%)";
  if (v.steady) {
    series[5].label = "steady σmax p50 (%)";
    series[6].label = "steady σmax p90 (%)";
    series[5].dashed = series[6].dashed = true;  // they lie on the static curves
  }
  for (const VoxelRow& r : v.rows) {
    const bool is_ref = &r == &ref;
    double ge_err[3];
    for (int m = 0; m < 3; ++m) ge_err[m] = 100 * std::fabs(r.ge[m] - ref.ge[m]);
    const double p50e = 100 * RelativeError(r.p50, ref.p50),
                 p90e = 100 * RelativeError(r.p90, ref.p90);
    const double s50e = 100 * RelativeError(r.steady_p50, ref.steady_p50);
    const double s90e = 100 * RelativeError(r.steady_p90, ref.steady_p90);
    std::vector<std::string> row{CsvNumber(r.voxel_size),
                                 CsvNumber(r.factor),
                                 is_ref ? "1" : "0",
                                 std::to_string(r.region_voxels),
                                 std::to_string(r.triangulable_voxels),
                                 CsvNumber(r.seconds),
                                 std::to_string(r.repeats),
                                 CsvNumber(r.seconds / ref.seconds)};
    for (int m = 0; m < 3; ++m) row.push_back(CsvNumber(r.ge[m]));
    for (int m = 0; m < 3; ++m) row.push_back(CsvNumber(ge_err[m]));
    for (double x : {r.p50, r.p90, p50e, p90e}) row.push_back(CsvNumber(x));
    if (v.steady)
      for (double x : {r.steady_p50, r.steady_p90, s50e, s90e}) row.push_back(CsvNumber(x));
    csv.push_back(row);
    std::vector<std::string> cells{Millimetres(r.voxel_size) + (is_ref ? " (ref)" : ""),
                                   std::to_string(r.region_voxels), Format("%.3g", r.seconds),
                                   Format("%.3g", r.seconds / ref.seconds)};
    for (int m = 0; m < 3; ++m) cells.push_back(Cell("%.2f", ge_err[m]));
    cells.push_back(Cell("%.4f", r.p50));
    cells.push_back(Cell("%.2f", p50e));
    cells.push_back(Cell("%.4f", r.p90));
    cells.push_back(Cell("%.2f", p90e));
    if (v.steady) {
      cells.push_back(Cell("%.4f", r.steady_p50));
      cells.push_back(Cell("%.2f", s50e));
      cells.push_back(Cell("%.4f", r.steady_p90));
      cells.push_back(Cell("%.2f", s90e));
    }
    section.table.AddRow(cells);
    if (is_ref) continue;
    const double errors[7] = {ge_err[0], ge_err[1], ge_err[2], p50e, p90e, s50e, s90e};
    for (std::size_t s = 0; s < series.size(); ++s) {
      series[s].x.push_back(r.seconds);
      series[s].y.push_back(errors[s]);
      series[s].point_labels.push_back(s == 3 ? Millimetres(r.voxel_size) : "");
    }
  }
  plot.series = series;
  plot.vertical_lines.push_back({ref.seconds, "reference " + Millimetres(ref.voxel_size)});
  section.csv = CsvText(header, csv);
  section.svg = RenderLogLogSvg(plot);
  return section;
}

AccuracySection MonteCarloSection(const MonteCarloStudy& mc, int threads) {
  AccuracySection section;
  section.title =
      "(b) Monte Carlo trials against the error of sigma (reference: the closed-form J^-1)";
  section.csv_name = "accuracy_montecarlo.csv";
  section.svg_name = "accuracy_montecarlo.svg";
  const std::vector<std::string> header{"trials",
                                        "points",
                                        "seconds_per_point",
                                        "sigma_max_rel_err_mean_pct",
                                        "sigma_max_rel_err_max_pct",
                                        "frobenius_rel_err_mean_pct",
                                        "frobenius_rel_err_max_pct",
                                        "failures",
                                        "prediction_seconds_per_point",
                                        "time_ratio_to_prediction"};
  section.table = Table({"trials", "points", "time/point (s)", "σmax err mean %", "max %",
                         "Frobenius mean %", "max %", "failures", "x prediction"});
  std::vector<std::vector<std::string>> csv;
  PlotSeries rel, frob, guide;
  rel.label = "σmax rel. error (mean)";
  frob.label = "Frobenius rel. error (mean)";
  guide.label = "1/sqrt(πN) (expected σ error)";
  guide.markers = false;
  guide.dashed = true;
  for (const MonteCarloRow& r : mc.rows) {
    const double ratio = r.seconds_per_point / mc.prediction_seconds;
    csv.push_back({std::to_string(r.trials), std::to_string(r.points),
                   CsvNumber(r.seconds_per_point), CsvNumber(100 * r.rel_mean),
                   CsvNumber(100 * r.rel_max), CsvNumber(100 * r.frob_mean),
                   CsvNumber(100 * r.frob_max), std::to_string(r.failures),
                   CsvNumber(mc.prediction_seconds), CsvNumber(ratio)});
    section.table.AddRow({std::to_string(r.trials), std::to_string(r.points),
                          Format("%.3g", r.seconds_per_point), Format("%.2f", 100 * r.rel_mean),
                          Format("%.2f", 100 * r.rel_max), Format("%.2f", 100 * r.frob_mean),
                          Format("%.2f", 100 * r.frob_max), std::to_string(r.failures),
                          Format("%.3g", ratio)});
    rel.x.push_back(r.seconds_per_point);
    rel.y.push_back(100 * r.rel_mean);
    rel.point_labels.push_back(Format("N=%d", r.trials));
    rel.labels_below = true;
    frob.x.push_back(r.seconds_per_point);
    frob.y.push_back(100 * r.frob_mean);
    guide.x.push_back(r.seconds_per_point);
    guide.y.push_back(100 / std::sqrt(kPi * r.trials));
  }
  section.table.AddRow({"prediction", std::to_string(mc.points.size()),
                        Cell("%.3g", mc.prediction_seconds), "(reference)", "", "", "", "", "1"});
  section.notes = mc.notes;
  section.notes.push_back(Format(
      "pixel sigma %.3g px; Monte Carlo runs its trials on %d threads (wall time), the prediction "
      "(Jacobians, J, eigen-decomposition, J^-1) on one",
      mc.sigma_px, threads));
  if (std::isfinite(mc.seconds_for_1pct))
    section.notes.push_back(Format(
        "1%% mean sigma_max error (fitted power law): Monte Carlo %.3g s per point, %.3g x the "
        "prediction's %.3g us",
        mc.seconds_for_1pct, mc.seconds_for_1pct / mc.prediction_seconds,
        1e6 * mc.prediction_seconds));
  for (const SamplePoint& p : mc.points)
    section.notes.push_back(
        Format("point (%.3f, %.3f, %.3f) m: %zu cameras, predicted sigma_max %.4f mm", p.X.x(),
               p.X.y(), p.X.z(), p.cameras.size(), 1e3 * p.sigma_max));
  LogLogPlot plot;
  plot.title = "Monte Carlo covariance against the closed-form prediction";
  plot.x_label = "time per point (s)";
  plot.y_label = "relative error against J^-1 (%)";
  plot.note = Format("mean over %zu sample points seen by >= 2 cameras; %d threads",
                     mc.points.size(), threads);
  plot.series = {rel, frob, guide};
  if (std::isfinite(mc.prediction_seconds))
    plot.vertical_lines.push_back(
        {mc.prediction_seconds, Format("prediction %.2g µs", 1e6 * mc.prediction_seconds)});
  section.csv = CsvText(header, csv);
  section.svg = RenderLogLogSvg(plot);
  return section;
}

namespace {

// Nearest-rank percentile p in [0, 1] of the finite values; NaN when none.
double PercentileOf(std::vector<double> v, double p) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t rank = static_cast<std::size_t>(std::ceil(p * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

}  // namespace

AccuracySection GateSection(const GateStudy& st) {
  AccuracySection section;
  section.title =
      Format("(f) Monte Carlo gate per voxel: %d noisy triangulations against J^-1", st.trials);
  section.csv_name = "accuracy_gate.csv";
  section.svg_name = "accuracy_gate.svg";
  section.table =
      Table({"axis", "tolerance", "measured/predicted p2.5", "median", "p97.5", "within",
             "resolvable axes", "angle median °", "p95 °", "max °", "within 3°"});
  static const char* const kAxis[3] = {"major", "middle", "minor"};
  std::vector<std::vector<std::string>> csv;
  PlotSeries axes[3];
  for (int a = 0; a < 3; ++a) {
    std::vector<double> ratio, angle;
    int within = 0, within_angle = 0;
    for (const GateVoxel& v : st.voxels) {
      ratio.push_back(v.Ratio(a));
      within += std::abs(v.Ratio(a) - 1) <= kGateEigenTolerance[a] ? 1 : 0;
      if (std::isfinite(v.axis_deg[a])) {
        angle.push_back(v.axis_deg[a]);
        within_angle += v.axis_deg[a] <= kGateAngleDeg ? 1 : 0;
      }
      axes[a].x.push_back(1e3 * std::sqrt(v.predicted[a]));
      axes[a].y.push_back(1e3 * std::sqrt(v.empirical[a]));
    }
    const double n = static_cast<double>(st.voxels.size());
    section.table.AddRow(
        {kAxis[a], Format("±%.0f%%", 100 * kGateEigenTolerance[a]),
         Cell("%.3f", PercentileOf(ratio, 0.025)), Cell("%.3f", PercentileOf(ratio, 0.5)),
         Cell("%.3f", PercentileOf(ratio, 0.975)), Cell("%.1f%%", 100 * within / n),
         Format("%zu", angle.size()), Cell("%.2f", PercentileOf(angle, 0.5)),
         Cell("%.2f", PercentileOf(angle, 0.95)), Cell("%.2f", PercentileOf(angle, 1.0)),
         angle.empty() ? "-" : Format("%.1f%%", 100.0 * within_angle / angle.size())});
    axes[a].label = Format("%s axis", kAxis[a]);
    axes[a].line = false;
  }
  std::vector<double> skew;
  for (const GateVoxel& v : st.voxels) {
    skew.push_back(std::abs(v.skew_major));
    csv.push_back(
        {CsvNumber(v.X.x()), CsvNumber(v.X.y()), CsvNumber(v.X.z()), std::to_string(v.cameras),
         CsvNumber(v.angle_deg), CsvNumber(1e3 * std::sqrt(v.predicted[0])),
         CsvNumber(1e3 * std::sqrt(v.predicted[1])), CsvNumber(1e3 * std::sqrt(v.predicted[2])),
         CsvNumber(v.Ratio(0)), CsvNumber(v.Ratio(1)), CsvNumber(v.Ratio(2)),
         CsvNumber(v.axis_deg[0]), CsvNumber(v.axis_deg[1]), CsvNumber(v.axis_deg[2]),
         CsvNumber(v.skew_major), std::to_string(v.failures), v.pass ? "1" : "0"});
  }
  section.notes = st.notes;
  section.notes.push_back(Format(
      "%zu voxels sampled uniformly in the region among those >= 2 cameras see; %.1f%% pass every "
      "eigenvalue tolerance and every resolvable axis within %.0f°; pixel sigma %.3g px; %.3g s",
      st.voxels.size(), 100 * st.PassShare(), kGateAngleDeg, st.sigma_px, st.seconds));
  section.notes.push_back(Format(
      "an axis is resolvable when the sample's own error of its direction (from the eigenvalue "
      "gaps and %d trials) is <= %.0f°; nearly equal eigenvalues leave their plane's directions "
      "undetermined",
      st.trials, kGateResolvableDeg));
  if (!st.voxels.empty()) {
    const auto worst = std::max_element(st.voxels.begin(), st.voxels.end(),
                                        [](const GateVoxel& a, const GateVoxel& b) {
                                          return std::abs(a.skew_major) < std::abs(b.skew_major);
                                        });
    section.notes.push_back(Format(
        "skew of the errors along the major axis (0 for the Gaussian the first-order prediction "
        "assumes): median |skew| %.3f, largest %.3f at (%.3f, %.3f, %.3f) m, %d cameras, best "
        "triangulation angle %.1f°, measured/predicted major variance %.3f",
        PercentileOf(skew, 0.5), std::abs(worst->skew_major), worst->X.x(), worst->X.y(),
        worst->X.z(), worst->cameras, worst->angle_deg, worst->Ratio(0)));
  }
  LogLogPlot plot;
  plot.title = "Measured against predicted sigma per principal axis";
  plot.x_label = "predicted sigma along the axis (mm)";
  plot.y_label = "Monte Carlo sigma along the axis (mm)";
  plot.note = Format("%zu voxels, %d trials each; dashed: measured = predicted", st.voxels.size(),
                     st.trials);
  PlotSeries identity;
  identity.label = "measured = predicted";
  identity.markers = false;
  identity.dashed = true;
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (const PlotSeries& s : axes)
    for (double x : s.x)
      if (x > 0 && std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
  if (hi > 0) identity.x = identity.y = {lo, hi};
  plot.series = {axes[0], axes[1], axes[2], identity};
  section.csv = CsvText(
      {"x_m", "y_m", "z_m", "cameras", "angle_deg", "predicted_major_mm", "predicted_middle_mm",
       "predicted_minor_mm", "ratio_major", "ratio_middle", "ratio_minor", "axis_major_deg",
       "axis_middle_deg", "axis_minor_deg", "skew_major", "failures", "pass"},
      csv);
  section.svg = RenderLogLogSvg(plot);
  return section;
}

AccuracySection RefineSection(const RefineStudy& st) {
  AccuracySection section;
  section.title = "(e) Coarse-to-fine evaluation against the full one at the study's voxel size";
  section.csv_name = "accuracy_refine.csv";
  section.svg_name = "accuracy_refine.svg";
  section.notes = st.notes;
  section.notes.insert(section.notes.begin(),
                       Format("reference: the full evaluation at %s, %lld region voxels (%lld "
                              "triangulable), %.3g s",
                              Millimetres(st.voxel_size).c_str(), (long long)st.reference_voxels,
                              (long long)st.reference_triangulable, st.reference_seconds));
  const std::vector<std::string> header{"coarse_voxel_m",
                                        "factor",
                                        "tolerance",
                                        "coarse_seconds",
                                        "refine_seconds",
                                        "time_ratio",
                                        "refined_voxels",
                                        "refined_share",
                                        "coverage_wrong_pct",
                                        "coverage_class_wrong_pct",
                                        "sigma_max_err_p50_pct",
                                        "sigma_max_err_p99_pct",
                                        "sigma_max_err_max_pct",
                                        "triangulable_mismatch"};
  section.table = Table({"coarse", "tol", "refined", "time (s)", "x full", "count wrong %",
                         "class wrong %", "σmax err p50 %", "p99 %", "max %", "triang. mismatch"});
  std::vector<std::vector<std::string>> csv;
  LogLogPlot plot;
  plot.title = "Coarse-to-fine: error against run time";
  plot.x_label = "coarse + refining evaluation (s)";
  plot.y_label = "error against the full evaluation (%)";
  plot.note = "zero errors are not drawn (log axis)";
  std::vector<PlotSeries> series(2);
  series[0].label = "camera count wrong (%)";  // the classes are in the table (0 where refined)
  series[1].label = "σmax error p99 (%)";
  for (auto& s : series) s.line = false;
  for (const RefineRow& r : st.rows) {
    const double seconds = r.coarse_seconds + r.refine_seconds;
    const double ratio = seconds / st.reference_seconds;
    const double share =
        double(r.refined_voxels) / double(std::max<std::int64_t>(1, st.reference_voxels));
    csv.push_back({CsvNumber(r.factor * st.voxel_size), std::to_string(r.factor),
                   CsvNumber(r.tolerance), CsvNumber(r.coarse_seconds), CsvNumber(r.refine_seconds),
                   CsvNumber(ratio), std::to_string(r.refined_voxels), CsvNumber(share),
                   CsvNumber(r.coverage_wrong_pct), CsvNumber(r.class_wrong_pct),
                   CsvNumber(r.sigma_p50_pct), CsvNumber(r.sigma_p99_pct),
                   CsvNumber(r.sigma_max_pct), std::to_string(r.triangulable_mismatch)});
    section.table.AddRow({Millimetres(r.factor * st.voxel_size), Format("%g", r.tolerance),
                          Format("%.0f%%", 100 * share), Format("%.3g", seconds),
                          Format("%.2f", ratio), Format("%.3f", r.coverage_wrong_pct),
                          Format("%.3f", r.class_wrong_pct), Format("%.3f", r.sigma_p50_pct),
                          Format("%.2f", r.sigma_p99_pct), Format("%.1f", r.sigma_max_pct),
                          std::to_string(r.triangulable_mismatch)});
    const std::string label = Format("%dx, %g", r.factor, r.tolerance);
    series[0].x.push_back(seconds);
    series[0].y.push_back(r.coverage_wrong_pct);
    series[0].point_labels.push_back("");
    series[1].x.push_back(seconds);
    series[1].y.push_back(r.sigma_p99_pct);
    series[1].point_labels.push_back(label);
  }
  plot.series = series;
  plot.vertical_lines.push_back({st.reference_seconds, "full evaluation"});
  section.csv = CsvText(header, csv);
  section.svg = RenderLogLogSvg(plot);
  return section;
}

AccuracySection SteadySection(const SteadyStudy& st) {
  AccuracySection section;
  section.title = "(c) Steady-state solvers (per voxel: three axes)";
  section.csv_name = "accuracy_steady.csv";
  section.svg_name = "accuracy_steady.svg";
  const std::vector<std::string> header{
      "case",   "q_m2_s3",    "rate_hz",   "tracking_index_min", "tracking_index_max",
      "method", "iterations", "converged", "seconds_per_voxel",  "rel_err"};
  section.table = Table({"case", "q m²/s³", "rate Hz", "Λ min..max", "method", "iter.", "conv.",
                         "time/voxel (s)", "rel. error"},
                        "lrrrlrlrr");
  std::vector<std::vector<std::string>> csv;
  LogLogPlot plot;
  plot.title = "Steady-state solvers: error against time";
  plot.x_label = "time per voxel, 3 axes (s)";
  plot.y_label = "relative error of the posterior position variance";
  constexpr double kFloor = 1e-17;
  plot.note = "reference: the closed form in long double; errors below 1e-17 are drawn at 1e-17";
  // Colour: the method; marker shape: the case. Legend-only keys for both.
  std::vector<std::string> methods;  // plot labels, in table order
  for (const SteadyRow& r : st.rows)
    if (std::find(methods.begin(), methods.end(), r.label) == methods.end())
      methods.push_back(r.label);
  constexpr const char* kMethodColors[] = {"#7f7f7f", "#1f77b4", "#2ca02c", "#17becf", "#ff7f0e",
                                           "#d62728", "#9467bd", "#8c564b", "#e377c2", "#bcbd22"};
  auto method_color = [&](const std::string& m) {
    const std::size_t i = std::find(methods.begin(), methods.end(), m) - methods.begin();
    return std::string(kMethodColors[i % 10]);
  };
  for (std::size_t ci = 0; ci < st.cases.size(); ++ci)
    for (const SteadyRow& r : st.rows) {
      if (r.case_name != st.cases[ci].name) continue;
      PlotSeries s;
      s.line = false;
      s.in_legend = false;
      s.color = method_color(r.label);
      s.shape = static_cast<int>(ci);
      s.x.push_back(r.seconds);
      s.y.push_back(std::isfinite(r.error) ? std::max(r.error, kFloor) : kNaN);
      plot.series.push_back(s);
    }
  for (const std::string& m : methods) {
    PlotSeries key;
    key.label = m;
    key.markers = false;
    key.color = method_color(m);
    plot.series.push_back(key);
  }
  for (std::size_t ci = 0; ci < st.cases.size(); ++ci) {
    PlotSeries key;
    key.label = st.cases[ci].name +
                Format(" (q %g, %g Hz)", st.cases[ci].motion.q, st.cases[ci].motion.rate_hz);
    key.line = false;
    key.color = "#444";
    key.shape = static_cast<int>(ci);
    plot.series.push_back(key);
  }
  for (const SteadyRow& r : st.rows) {
    csv.push_back({r.case_name, CsvNumber(r.motion.q), CsvNumber(r.motion.rate_hz),
                   CsvNumber(r.lambda_min), CsvNumber(r.lambda_max), r.method,
                   std::to_string(r.iterations), r.converged ? "1" : "0", CsvNumber(r.seconds),
                   CsvNumber(r.error)});
    section.table.AddRow({r.case_name, Format("%g", r.motion.q), Format("%g", r.motion.rate_hz),
                          Format("%.2g..%.2g", r.lambda_min, r.lambda_max), r.method,
                          r.iterations ? std::to_string(r.iterations) : "-",
                          r.run_on      ? "-"
                          : r.converged ? "yes"
                                        : "NO",
                          Format("%.3g", r.seconds), Cell("%.2g", r.error)});
  }
  section.notes = st.notes;
  section.notes.push_back(st.J_source);
  section.notes.push_back(
      "error: largest over the three eigen-directions of J of |variance - reference| / reference, "
      "posterior position variance; reference: the closed form evaluated in long double");
  section.csv = CsvText(header, csv);
  section.svg = RenderLogLogSvg(plot);
  return section;
}

std::vector<GpuAccuracyRow> ParseGpuAccuracyCsv(const std::string& text, const std::string& file) {
  std::vector<GpuAccuracyRow> rows;
  std::size_t start = text.find('\n');  // the header
  int line = 1;
  while (start != std::string::npos && start + 1 < text.size()) {
    const std::size_t end = text.find('\n', start + 1);
    const std::string row =
        text.substr(start + 1, end == std::string::npos ? std::string::npos : end - start - 1);
    ++line;
    start = end;
    if (row.empty()) continue;
    GpuAccuracyRow r;
    char rest = 0;
    if (std::sscanf(row.c_str(), "%d,%lf,%lf,%lf,%lf,%lf%c", &r.map, &r.gpu_ms, &r.eye_only_ms,
                    &r.cpu_ms, &r.differ_compared_pct, &r.differ_all_pct, &rest) != 6)
      throw InputError(file, "",
                       "line " + std::to_string(line) + " is not six numbers: '" + row + "'");
    rows.push_back(r);
  }
  return rows;
}

AccuracySection GpuSection(const std::vector<GpuAccuracyRow>& rows, const std::string& view_note) {
  AccuracySection section;
  section.title =
      "GPU projective light (pandora view) against the exact renderer, per shadow-map size";
  section.csv_name = "accuracy_gpu.csv";
  section.svg_name = "accuracy_gpu.svg";
  section.table = Table({"map", "GPU frame (ms)", "eye-only frame (ms)", "CPU frame (ms)",
                         "sets differ, off edges", "sets differ, all pixels"});
  std::vector<std::vector<std::string>> csv;
  LogLogPlot plot;
  plot.title = "GPU light: pixels whose camera sets differ, against frame time";
  plot.x_label = "GPU frame time (ms, every map drawn)";
  plot.y_label = "pixels whose camera sets differ (%)";
  plot.note = view_note;
  PlotSeries off, all;
  off.label = "off the one-pixel edge band";
  all.label = "all pixels";
  for (const GpuAccuracyRow& r : rows) {
    section.table.AddRow({std::to_string(r.map), Cell("%.1f", r.gpu_ms),
                          Cell("%.1f", r.eye_only_ms), Cell("%.1f", r.cpu_ms),
                          Cell("%.4f %%", r.differ_compared_pct),
                          Cell("%.3f %%", r.differ_all_pct)});
    csv.push_back({std::to_string(r.map), CsvNumber(r.gpu_ms), CsvNumber(r.eye_only_ms),
                   CsvNumber(r.cpu_ms), CsvNumber(r.differ_compared_pct),
                   CsvNumber(r.differ_all_pct)});
    for (PlotSeries* s : {&off, &all}) {
      s->x.push_back(r.gpu_ms);
      s->y.push_back(s == &off ? r.differ_compared_pct : r.differ_all_pct);
      s->point_labels.push_back(std::to_string(r.map));
    }
  }
  if (!rows.empty()) {
    PlotMarker cpu;
    cpu.x = rows.front().cpu_ms;
    cpu.label = "exact CPU frame";
    plot.vertical_lines.push_back(cpu);
  }
  plot.series = {off, all};
  section.csv = CsvText(
      {"map", "gpu_ms", "eye_only_ms", "cpu_ms", "differ_compared_pct", "differ_all_pct"}, csv);
  section.svg = RenderLogLogSvg(plot);
  section.notes.push_back(view_note);
  section.notes.push_back(
      "Zero shares are not drawn on the log axis. A pixel's camera set is the cameras whose light "
      "reaches the surface point it shows; the edge band is one pixel around every edge of the "
      "exact image (footprints, shadows, silhouettes), where a rasteriser and a ray caster "
      "legitimately disagree (docs/viewer.md).");
  return section;
}

}  // namespace pandora::report
