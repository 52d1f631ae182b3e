// `pandora validate --calibration` (issue 31, point 4; docs/validation.md): the calibration study
// of validation/calibrate.h written as a table per camera (OpenCV's intrinsics and the bundle
// adjustment's rig against the truth, beside Pandora's feasibility verdict), a CSV file and one
// view beside its detections, in one transaction.
#include "app/validate_calibration.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "analysis/util/text.h"
#include "app/output.h"
#include "app/report/table.h"

namespace pandora::app {
namespace {

std::string FiniteOrDash(double v, const char* format) {
  return std::isfinite(v) ? Format(format, v) : std::string("—");
}

// fx error and its ratio to OpenCV's standard deviation, "0.31 (0.8σ)".
std::string ErrorAndSigma(double error, double sigma, const char* format = "%+.2f") {
  if (!(sigma > 0) || !std::isfinite(sigma)) return Format(format, error);
  return Format(format, error) + Format(" (%.1fσ)", std::abs(error) / sigma);
}

report::Table CameraTable(const CalibrationStudy& s) {
  report::Table t({"camera", "lens", "views", "corners", "Pandora: poses", "link", "verdict",
                   "result", "OpenCV RMS px", "fx err px", "fy err px", "cx err px", "cy err px",
                   "map RMS / max px", "world px", "rotation °", "position mm"});
  for (const CameraCalibration& c : s.cameras) {
    if (!c.enabled) continue;
    const bool intr = c.intrinsics_ok;
    const Intrinsics& f = c.final;
    t.AddRow(
        {c.id + (c.reference ? " (held)" : ""), LensModelName(c.truth.model),
         std::to_string(c.views), std::to_string(c.corners), std::to_string(c.predicted_observed),
         std::to_string(c.link_strength),
         c.predicted_calibratable ? "calibratable" : "**uncalibratable**",
         c.calibrated ? c.status : "**" + c.status + "**",
         intr ? Format("%.3f", c.opencv_rms_px) : "—",
         intr ? ErrorAndSigma(f.fx - c.truth.fx, c.std_fx) : "—",
         intr ? ErrorAndSigma(f.fy - c.truth.fy, c.std_fy) : "—",
         intr ? ErrorAndSigma(f.cx - c.truth.cx, c.std_cx) : "—",
         intr ? ErrorAndSigma(f.cy - c.truth.cy, c.std_cy) : "—",
         intr ? (c.map_within_bound ? "" : "**") + FiniteOrDash(c.map_rms_px, "%.3f") +
                    (c.map_within_bound ? "" : "**") + " / " + FiniteOrDash(c.map_max_px, "%.2f")
              : "—",
         c.linked ? FiniteOrDash(c.world_rms_px, "%.3f") : "—",
         c.linked && !c.reference ? ErrorAndSigma(c.rotation_error_deg, c.rotation_sd_deg, "%.4f")
                                  : "—",
         c.linked && !c.reference ? ErrorAndSigma(c.position_error_mm, c.position_sd_mm, "%.2f")
                                  : "—"});
  }
  return t;
}

std::string CamerasCsv(const CalibrationStudy& s) {
  std::vector<std::vector<std::string>> rows;
  auto n = [](double v) { return report::CsvNumber(v); };
  for (const CameraCalibration& c : s.cameras) {
    const Intrinsics& f = c.final;
    rows.push_back({c.id,
                    c.enabled ? "1" : "0",
                    LensModelName(c.truth.model),
                    std::to_string(c.views),
                    std::to_string(c.corners),
                    std::to_string(c.predicted_observed),
                    std::to_string(c.link_strength),
                    c.predicted_calibratable ? "1" : "0",
                    c.status,
                    c.reference ? "1" : "0",
                    n(c.opencv_rms_px),
                    n(c.truth.fx),
                    n(f.fx),
                    n(c.std_fx),
                    n(c.truth.fy),
                    n(f.fy),
                    n(c.std_fy),
                    n(c.truth.cx),
                    n(f.cx),
                    n(c.std_cx),
                    n(c.truth.cy),
                    n(f.cy),
                    n(c.std_cy),
                    n(c.map_rms_px),
                    n(c.map_max_px),
                    n(c.map_footprint_rms_px),
                    n(c.world_rms_px),
                    n(c.rotation_error_deg),
                    n(c.rotation_sd_deg),
                    n(c.position_error_mm),
                    n(c.position_sd_mm),
                    n(c.opencv.fx),
                    n(c.opencv_std_fx),
                    n(c.opencv.cx),
                    n(c.opencv_std_cx),
                    std::to_string(c.shared_views)});
  }
  return report::CsvText({"camera",
                          "enabled",
                          "lens",
                          "views",
                          "corners",
                          "predicted_poses",
                          "link_strength",
                          "predicted_calibratable",
                          "status",
                          "held",
                          "opencv_rms_px",
                          "fx_true",
                          "fx",
                          "fx_std",
                          "fy_true",
                          "fy",
                          "fy_std",
                          "cx_true",
                          "cx",
                          "cx_std",
                          "cy_true",
                          "cy",
                          "cy_std",
                          "map_rms_px",
                          "map_max_px",
                          "footprint_rms_px",
                          "world_rms_px",
                          "rotation_error_deg",
                          "rotation_sd_deg",
                          "position_error_mm",
                          "position_sd_mm",
                          "opencv_fx",
                          "opencv_fx_std",
                          "opencv_cx",
                          "opencv_cx_std",
                          "shared_views"},
                         rows);
}

std::string CalibrationMarkdown(const std::string& scene, const Rig& rig, const CalibrationStudy& s,
                                const CalibrateOptions& o) {
  std::string md = "# pandora validate --calibration: " + scene + ", rig " + rig.name + "\n\n";
  md += Format(
      "Board: %s, waved through the region at %d poses of the calibration simulation; %lld "
      "views rendered (%d x %d rays per pixel, blur %.2g px, noise %.3g levels), %zu corner "
      "detections kept (%lld rejected). A view counts with >= %d corners; a camera needs >= %d "
      "views. %s\n\n",
      s.board.c_str(), s.capture.poses, (long long)s.capture.views, o.synth.samples,
      o.synth.samples, o.synth.blur_px, o.synth.noise, s.capture.observations.size(),
      (long long)s.capture.misdetected, o.min_view_corners, o.min_views,
      o.partial_views
          ? "Views of partly hidden boards are used too (`--partial-views`): the "
            "simulation's verdict does not count them."
          : "Only views of the whole board, as the feasibility simulation counts them.");
  md += Format(
      "Intrinsics: OpenCV per camera (`cv::calibrateCamera`: k1 k2 p1 p2 for a lens the design "
      "calls pinhole, k1 k2 p1 p2 k3 for Brown-Conrady; `cv::fisheye::calibrate` for a "
      "fisheye). Rig: Ceres bundle adjustment of every linked camera's intrinsics and pose and "
      "every board pose (%lld corner detections, %d iterations, reprojection RMS %.4f px), "
      "camera %s held at its design pose; the board's size fixes the scale.\n\n",
      (long long)s.ba_residuals, s.ba_iterations, s.ba_rms_px,
      s.reference >= 0 ? s.cameras[s.reference].id.c_str() : "(none)");
  md += Format(
      "Pandora's verdict: the feasibility simulation of the study (%d poses, min_shared %d); "
      "\"link\" is the weakest shared count on the camera's path to the held camera in the "
      "maximum spanning forest. Errors are the final (adjusted) values against the truth, in "
      "units of the estimate's own standard deviation (the adjustment's covariance; OpenCV's "
      "for a camera calibrated alone); \"map\" is the final lens model's pixel for each "
      "pixel's true ray over a 32 x 24 grid of the whole image (intrinsics alone), \"world\" "
      "the calibrated camera's pixel for each board corner it saw against the true camera's "
      "(intrinsics and pose together, as triangulation uses them).\n\n",
      s.spec.samples, s.spec.min_shared);
  md += CameraTable(s).Markdown();
  md += Format(
      "\nA camera is calibrated when it is linked to the rig and its world pixels are within "
      "%.3g px RMS of the true camera's. The verdict holds (every camera Pandora calls "
      "uncalibratable failed, every other one calibrated): **%s**.\n",
      o.bound_px, s.verdict_holds ? "yes" : "no");
  int maps = 0, within = 0;
  for (const CameraCalibration& c : s.cameras)
    if (c.intrinsics_ok) ++maps, within += c.map_within_bound;
  if (maps > 0)
    md += Format(
        "\nLens map within %.3g px RMS over the whole image: %d of %d calibrated lenses (bold: "
        "not; the views do not cover the image, which the simulation does not ask).\n",
        o.bound_px, within, maps);
  if (std::isfinite(s.link_error_correlation))
    md += Format(
        "\nSpearman correlation of link strength and position error over the calibrated cameras: "
        "%.2f (negative: weaker links, larger errors).\n",
        s.link_error_correlation);
  for (const std::string& n : s.notes) md += "\n- " + n;
  md += Format(
      "\n\nTime: %.1f s (rendering %.1f s, detection %.1f s summed over threads; calibration "
      "%.1f s).\n",
      s.total_seconds, s.capture.render_seconds, s.capture.detect_seconds, s.calibrate_seconds);
  return md;
}

}  // namespace

int RunValidateCalibration(const std::string& scene_path, const Scene& scene, const Rig& rig,
                           const CalibrateOptions& options, const std::string& out, bool quiet) {
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::filesystem::path dir(out);
  const std::string md_path = output.Stage((dir / "calibration.md").string(), "--out");
  ProgressBar bar("validate --calibration", !quiet);
  const CalibrationStudy s = RunCalibrationStudy(
      scene, rig, options, [&](int done, int total) { bar.Update(double(done) / total); });
  bar.Finish();
  const std::string md = CalibrationMarkdown(scene_path, rig, s, options);
  output.Write((dir / "calibration_cameras.csv").string(), "--out", CamerasCsv(s));
  WriteFileAtomically(md_path, md);
  output.Commit();
  if (!quiet) std::printf("%s", md.c_str());
  return 0;
}

}  // namespace pandora::app
