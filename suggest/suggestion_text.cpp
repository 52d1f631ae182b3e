#include "suggest/suggestion_text.h"

#include <cmath>
#include <cstdio>

#include "analysis/util/text.h"

namespace pandora {

std::string TableValue(double value, const char* format) {
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  if (std::isnan(value)) return "n/a";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

std::string FormatSuggestion(const Suggestion& s, const SuggestionContext& context) {
  std::string out =
      Format("%s: scene %s, rig %s, objective %s (%s is better), %d target points\n",
             context.title.c_str(), context.scene_path.c_str(), context.rig_name.c_str(),
             ObjectiveName(s.objective).c_str(),
             ObjectiveHigherIsBetter(s.objective) ? "higher" : "lower", s.target_points);
  out += Format("\n%-10s %9s %12s  %-28s %-28s\n", "camera", "move (m)", "rotate (deg)",
                "position before", "position after");
  auto position = [](const Eigen::Isometry3d& pose) {
    const Vec3 t = pose.translation();
    return Format("(%.3f, %.3f, %.3f)", t.x(), t.y(), t.z());
  };
  for (const CameraChange& c : s.cameras) {
    out += Format("%-10s %9.3f %12.2f  %-28s %-28s\n", c.id.c_str(), c.move_m, c.rotate_deg,
                  position(c.before).c_str(), position(c.after).c_str());
    if (c.focal_scale != 1.0)
      out += Format("           zoom: horizontal field of view %.2f -> %.2f deg\n",
                    c.hfov_before_deg, c.hfov_after_deg);
    if (std::isfinite(c.surface_distance_after) && c.surface_distance_after < 1.0)
      out += Format("           nearest surface: %.3f m -> %.3f m\n", c.surface_distance_before,
                    c.surface_distance_after);
    if (!c.note.empty()) out += "           note: " + c.note + "\n";
  }
  auto row = [&out](const std::string& name, double a, double b) {
    out += Format("%-26s %14s %14s\n", name.c_str(), TableValue(a).c_str(), TableValue(b).c_str());
  };
  out += Format("\n%-26s %14s %14s\n", "measure", "before", "after");
  row("objective " + ObjectiveName(s.objective), s.before.objective, s.after.objective);
  row("coverage >= 2 (share)", s.before.coverage2, s.after.coverage2);
  if (s.objective.k != 2)
    row("coverage >= " + std::to_string(s.objective.k) + " (share)", s.before.coverage_k,
        s.after.coverage_k);
  row("sigma_max p50 (mm)", s.before.sigma_p50, s.after.sigma_p50);
  row("sigma_max p90 (mm)", s.before.sigma_p90, s.after.sigma_p90);
  row("sigma_max p95 (mm)", s.before.sigma_p95, s.after.sigma_p95);
  row("untriangulable (share)", s.before.untriangulable, s.after.untriangulable);
  row("min resolution (px/m)", s.before.min_resolution, s.after.min_resolution);
  if (s.before.n1 && s.after.n1) {
    row("N-1 coverage >= " + std::to_string(s.objective.k) + " (share)", s.before.n1->coverage_k,
        s.after.n1->coverage_k);
    out += Format("%-26s %14s %14s\n", "  worst failure", s.before.n1->worst_camera.c_str(),
                  s.after.n1->worst_camera.c_str());
  }
  if (s.before.calibration && s.after.calibration) {
    const Metrics::Calibration& a = *s.before.calibration;
    const Metrics::Calibration& b = *s.after.calibration;
    row("calibration weakest link", double(a.weakest), double(b.weakest));
    out += Format("%-26s %14s %14s\n", "  between", (a.weakest_a + "-" + a.weakest_b).c_str(),
                  (b.weakest_a + "-" + b.weakest_b).c_str());
    row("  tree shared poses", double(a.tree_total), double(b.tree_total));
    row("  components", a.components, b.components);
    row("  uncalibratable cameras", a.uncalibratable, b.uncalibratable);
  }
  if (s.unsnapped)
    out +=
        "(before snapping the optimum had objective " + TableValue(s.unsnapped->objective) + ")\n";
  out += "\n";
  if (s.screened > 0)
    out += Format("screening: %d exact evaluations, best %s; then ", s.screened,
                  TableValue(s.screened_objective).c_str());
  out += Format("%d iterations (%d outer), %lld evaluations, %.3f s\n%s\n", s.iterations,
                s.outer_iterations, static_cast<long long>(s.evaluations), s.seconds,
                s.message.c_str());
  const bool any_inf = std::isinf(s.before.sigma_p50) || std::isinf(s.before.sigma_p90) ||
                       std::isinf(s.before.sigma_p95) || std::isinf(s.after.sigma_p50) ||
                       std::isinf(s.after.sigma_p90) || std::isinf(s.after.sigma_p95);
  if (any_inf) out += "(inf: the percentile falls on a point that is not triangulable)\n";
  return out;
}

std::string FormatRecovery(const Suggestion& s, double original_objective,
                           const std::string& perturbation) {
  const double lost = original_objective - s.before.objective;
  const double regained = s.after.objective - s.before.objective;
  return Format(
      "perturbed by %s: objective at the original poses %s; recovered %s of the lost %s (%.0f%%)\n",
      perturbation.c_str(), TableValue(original_objective).c_str(), TableValue(regained).c_str(),
      TableValue(lost).c_str(), lost != 0 ? 100.0 * regained / lost : 0.0);
}

}  // namespace pandora
