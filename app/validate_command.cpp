// `pandora validate` (issue 31, point 3; docs/validation.md): a ChArUco board waved through the
// region, synthesised in every camera, detected by OpenCV, triangulated with the known cameras; the
// measured 3D errors against the covariance Pandora predicts at those points. Tables, CSV files, a
// measured-against-predicted plot and one synthetic view beside its detections, in one
// transaction.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/report/plot.h"
#include "app/report/table.h"
#include "app/validate_calibration.h"
#include "app/validate_report.h"
#include "render/render.h"
#include "validation/validate.h"

namespace pandora::app {
namespace {

struct ValidateArgs {
  std::string scene, rig, out = "out/validate";
  ValidateOptions options;
  int time_sample = -1;
  double tolerance = 0.25;  ///< The verdict: every bin's ratios within this of 1.
  bool quiet = false;
  bool calibration = false;  ///< The calibration study instead (validate_calibration.h).
  bool poses_given = false, squares_given = false;
  bool partial_views = false;  ///< --partial-views (calibration only).
};

report::Table BinTable(const std::vector<ValidateBin>& bins, const char* first) {
  report::Table table({first, "corners", "cameras", "angle °", "major", "middle", "minor",
                       "one σ: major/middle/minor", "RMS major mm", "predicted mm", "skew major"});
  for (const ValidateBin& b : bins)
    table.AddRow(
        {b.label, std::to_string(b.points), Format("%.0f", b.median_cameras),
         Format("%.1f", b.median_angle_deg), Format("%.3f", b.ratio[0]), Format("%.3f", b.ratio[1]),
         Format("%.3f", b.ratio[2]),
         Format("%.2f/%.2f/%.2f", b.ratio_one_sigma[0], b.ratio_one_sigma[1], b.ratio_one_sigma[2]),
         Format("%.4f", b.measured_mm[0]), Format("%.4f", b.predicted_mm[0]),
         Format("%.2f", b.skew_major)});
  return table;
}

std::string BinsCsv(const ValidateResult& r) {
  std::vector<std::vector<std::string>> rows;
  auto add = [&](const char* by, const ValidateBin& b) {
    rows.push_back({by, b.label, std::to_string(b.points), report::CsvNumber(b.median_cameras),
                    report::CsvNumber(b.median_angle_deg), report::CsvNumber(b.ratio[0]),
                    report::CsvNumber(b.ratio[1]), report::CsvNumber(b.ratio[2]),
                    report::CsvNumber(b.ratio_one_sigma[0]),
                    report::CsvNumber(b.ratio_one_sigma[1]),
                    report::CsvNumber(b.ratio_one_sigma[2]), report::CsvNumber(b.measured_mm[0]),
                    report::CsvNumber(b.predicted_mm[0]), report::CsvNumber(b.measured_mm[2]),
                    report::CsvNumber(b.predicted_mm[2]), report::CsvNumber(b.skew_major)});
  };
  for (const ValidateBin& b : r.sigma_bins) add("sigma", b);
  for (const ValidateBin& b : r.angle_bins) add("angle", b);
  add("all", r.all);
  return report::CsvText(
      {"by", "bin", "corners", "cameras", "angle_deg", "ratio_major", "ratio_middle", "ratio_minor",
       "one_sigma_major", "one_sigma_middle", "one_sigma_minor", "measured_major_mm",
       "predicted_major_mm", "measured_minor_mm", "predicted_minor_mm", "skew_major"},
      rows);
}

std::string PointsCsv(const ValidateResult& r) {
  std::vector<std::vector<std::string>> rows;
  for (const ValidatedPoint& p : r.points) {
    const Vec3 e = p.estimate - p.truth;
    rows.push_back(
        {std::to_string(p.pose), std::to_string(p.id), report::CsvNumber(p.truth.x()),
         report::CsvNumber(p.truth.y()), report::CsvNumber(p.truth.z()),
         report::CsvNumber(1e3 * e.x()), report::CsvNumber(1e3 * e.y()),
         report::CsvNumber(1e3 * e.z()), std::to_string(p.cameras.size()),
         report::CsvNumber(p.angle_deg), report::CsvNumber(1e3 * std::sqrt(p.variances[0])),
         report::CsvNumber(1e3 * std::sqrt(p.variances[1])),
         report::CsvNumber(1e3 * std::sqrt(p.variances[2])), report::CsvNumber(p.whitened[0]),
         report::CsvNumber(p.whitened[1]), report::CsvNumber(p.whitened[2])});
  }
  return report::CsvText({"pose", "corner", "x_m", "y_m", "z_m", "error_x_mm", "error_y_mm",
                          "error_z_mm", "cameras", "angle_deg", "sigma_major_mm", "sigma_middle_mm",
                          "sigma_minor_mm", "z_major", "z_middle", "z_minor"},
                         rows);
}

std::string DetectionsCsv(const Rig& rig, const ValidateResult& r) {
  std::vector<std::vector<std::string>> rows;
  for (const BoardObservation& ob : r.observations)
    rows.push_back({std::to_string(ob.pose), rig.cameras[ob.camera].id, std::to_string(ob.id),
                    report::CsvNumber(ob.found.x()), report::CsvNumber(ob.found.y()),
                    report::CsvNumber(ob.truth.x()), report::CsvNumber(ob.truth.y()),
                    report::CsvNumber(ob.view_sigma), std::to_string(ob.window)});
  return report::CsvText({"pose", "camera", "corner", "found_x", "found_y", "truth_x", "truth_y",
                          "sigma_px", "window_px"},
                         rows);
}

// The sample view three times enlarged, its detections as green crosses and the exact projections
// as red dots.
std::string DetectionsPng(const ValidateResult::Sample& s) {
  const int k = 3, w = s.image.width * k, h = s.image.height * k;
  std::vector<std::uint8_t> rgb(3 * static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        rgb[3 * (std::size_t(y) * w + x) + c] =
            s.image.rgb[3 * (std::size_t(y / k) * s.image.width + x / k) + c];
  auto put = [&](int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    std::uint8_t* p = &rgb[3 * (std::size_t(y) * w + x)];
    p[0] = r, p[1] = g, p[2] = b;
  };
  // Pixel centre (u, v) is at ((u + 0.5) k, (v + 0.5) k) in the enlarged image.
  for (const Vec2& f : s.found) {
    const int cx = int(std::lround((f.x() + 0.5) * k)), cy = int(std::lround((f.y() + 0.5) * k));
    for (int d = -6; d <= 6; ++d) put(cx + d, cy, 0, 220, 0), put(cx, cy + d, 0, 220, 0);
  }
  for (const Vec2& t : s.truth) {
    const int cx = int(std::lround((t.x() + 0.5) * k)), cy = int(std::lround((t.y() + 0.5) * k));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) put(cx + dx, cy + dy, 230, 0, 0);
  }
  return EncodePngSrgb8(w, h, rgb);
}

std::string Markdown(const ValidateArgs& args, const Rig& rig, const ValidateResult& r, bool pass) {
  std::string md = "# pandora validate: " + args.scene + ", rig " + rig.name + "\n\n";
  md += Format(
      "Board: %s, %d poses through the region (the calibration simulation's), %lld views "
      "rendered. Synthetic images: %d x %d rays per pixel, blur %.2g px, noise %.3g levels.\n\n",
      r.board.c_str(), r.poses, (long long)r.views, args.options.synth.samples,
      args.options.synth.samples, args.options.synth.blur_px, args.options.synth.noise);
  md += Format(
      "OpenCV found %lld of the %lld corner views the truth holds within %.3g px (%.1f %%), %lld "
      "misdetections. Pixel noise from the residuals: **%.4f px** per coordinate (mean residual "
      "%.4f, %.4f px).\n\n",
      (long long)r.detected, (long long)r.expected, args.options.outlier_px,
      r.expected ? 100.0 * r.detected / r.expected : 0.0, (long long)r.misdetected, r.sigma_px,
      r.mean_residual.x(), r.mean_residual.y());
  std::vector<double> views = r.view_sigma;
  std::sort(views.begin(), views.end());
  if (!views.empty())
    md += Format(
        "Each view's own noise (RMS of its residuals, %zu views of >= 6 corners): median %.3f px, "
        "from %.3f to %.3f px.\n\n",
        views.size(), views[views.size() / 2], views.front(), views.back());
  if (args.options.noise_model == ValidateOptions::NoiseModel::kCorner) {
    std::string windows;
    for (const auto& [window, sigma] : r.window_sigma)
      windows += Format("%s%d px: %.3f px", windows.empty() ? "" : ", ", window, sigma);
    md += Format(
        "Noise model (`--noise-model corner`): each detection's noise is the residual RMS of the "
        "detections refined in a window of its size (half-width %s), scaled to its view's "
        "residuals%s, and shaped by its window's structure tensor (a foreshortened corner is less "
        "certain across its sharp angle). The triangulation weights each detection by that "
        "covariance (the maximum-likelihood estimate the prediction describes).\n\n",
        windows.c_str(),
        r.corner_noise_scale > 0
            ? Format(" (views of fewer than 6 corners: to theirs together, x %.3f)",
                     r.corner_noise_scale)
                  .c_str()
            : "");
  } else {
    md += "Noise model (`--noise-model view`): each detection has its view's noise";
    if (r.small_view_sigma > 0)
      md += Format("; views of fewer than 6 corners share their pooled noise, %.3f px",
                   r.small_view_sigma);
    md += ". The triangulation weights each detection so.\n\n";
  }
  md += Format(
      "The columns \"one σ\" compare with the design's assumption instead: one noise (%.3f px) "
      "for every camera and view.\n\n",
      r.sigma_px);
  md += Format(
      "%zu corners seen by >= 2 cameras triangulated. Measured / predicted RMS along each "
      "principal axis of the predicted covariance (1 = as predicted):\n\n",
      r.points.size());
  md += "## By predicted sigma_max\n\n" + BinTable(r.sigma_bins, "predicted σmax").Markdown();
  md += "\n## By triangulation angle\n\n" + BinTable(r.angle_bins, "angle").Markdown();
  md += "\n## All\n\n" + BinTable({r.all}, "").Markdown();
  md += Format("\nVerdict: every bin of >= %d corners within %.0f %% on every axis: **%s**.\n",
               args.options.min_bin, 100 * args.tolerance, pass ? "yes" : "no");
  for (const std::string& n : r.notes) md += "\n- " + n;
  md += Format("\n\nTime: %.1f s (rendering %.1f s, detection %.1f s, summed over threads).\n",
               r.total_seconds, r.render_seconds, r.detect_seconds);
  return md;
}

// The calibration study with the options given (its own defaults for --poses and --squares).
int RunCalibration(const ValidateArgs& args) {
  CalibrateOptions o;
  if (args.poses_given) o.poses = args.options.poses;
  if (args.squares_given)
    o.squares_x = args.options.squares_x, o.squares_y = args.options.squares_y;
  o.seed = args.options.seed;
  o.square_m = args.options.square_m;
  o.synth = args.options.synth;
  o.partial_views = args.partial_views;
  o.Check();
  const Scene scene = LoadSceneAtSample(args.scene, args.time_sample);
  const Rig& rig = FindRigOption(scene, args.rig);
  return RunValidateCalibration(args.scene, scene, rig, o, args.out, args.quiet);
}

int RunValidate(const ValidateArgs& args) {
  if (args.calibration) return RunCalibration(args);
  args.options.Check();
  const Scene scene = LoadSceneAtSample(args.scene, args.time_sample);
  const Rig& rig = FindRigOption(scene, args.rig);
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::filesystem::path dir(args.out);
  const std::string md_path = output.Stage((dir / "validation.md").string(), "--out");
  ProgressBar bar("validate", !args.quiet);
  const ValidateResult r = RunValidation(
      scene, rig, args.options, [&](int done, int total) { bar.Update(double(done) / total); });
  bar.Finish();
  const bool pass = ValidationPasses(r, args.options.min_bin, args.tolerance);
  const std::string md = Markdown(args, rig, r, pass);
  output.Write((dir / "validation_bins.csv").string(), "--out", BinsCsv(r));
  output.Write((dir / "validation_points.csv").string(), "--out", PointsCsv(r));
  output.Write((dir / "validation_detections.csv").string(), "--out", DetectionsCsv(rig, r));
  output.Write((dir / "validation.svg").string(), "--out", ValidationPlotSvg(r));
  if (r.sample.image.width > 0)
    output.Write((dir / "detections.png").string(), "--out", DetectionsPng(r.sample));
  WriteFileAtomically(md_path, md);
  output.Commit();
  if (!args.quiet) std::printf("%s", md.c_str());
  return 0;
}

}  // namespace

// Registers `pandora validate` and its options.
Command AddValidateCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<ValidateArgs>();
  ValidateArgs& a = *args;
  CLI::App* cmd = app.add_subcommand(
      "validate",
      "Synthesise a board waved through the region, detect it with OpenCV, triangulate, and "
      "compare the errors with the predicted uncertainty");
  cmd->add_option("scene", a.scene, "Scene file (JSON)")->required();
  cmd->add_option("--rig", a.rig, "Rig name (default: the first rig)");
  cmd->add_option("--out", a.out, "Output folder")->capture_default_str();
  cmd->add_flag("--calibration", a.calibration,
                "Calibrate the rig end to end from the synthetic board views (OpenCV per camera, "
                "a Ceres bundle adjustment of the rig) and compare with the truth and with "
                "Pandora's feasibility verdict");
  cmd->add_flag("--partial-views", a.partial_views,
                "With --calibration: use partly hidden boards too (ChArUco), not only the views "
                "the feasibility simulation counts");
  cmd->add_option_function<int>(
         "--poses",
         [&a](int poses) {
           a.options.poses = poses;
           a.poses_given = true;
         },
         "Board poses (default 60; 200 with --calibration)")
      ->check(Number(1, 100000, "poses", true));
  cmd->add_option("--square", a.options.square_m,
                  "Board square, metres (default: sized from the rig's distances and focal "
                  "lengths)")
      ->check(Number(0, 10, "m"));
  cmd->add_option_function<std::vector<int>>(
         "--squares",
         [&a](const std::vector<int>& v) {
           if (v.size() != 2)
             throw CLI::ValidationError("--squares", "give two numbers of squares, e.g. 5,4");
           a.options.squares_x = v[0];
           a.options.squares_y = v[1];
           a.squares_given = true;
         },
         "Board squares across and up (3 to 20 each; default 5,4; with --calibration 7,5 "
         "unless the study names its board)")
      ->delimiter(',')
      ->check(Number(3, 20, "squares", true));
  cmd->add_option("--seed", a.options.seed, "Seed of the poses and the noise")
      ->capture_default_str();
  cmd->add_option("--samples", a.options.synth.samples, "Rays per pixel per axis (1 to 16)")
      ->capture_default_str()
      ->check(Number(1, 16, "samples", true));
  cmd->add_option("--blur", a.options.synth.blur_px, "Gaussian optical blur, sigma in pixels")
      ->capture_default_str()
      ->check(Number(0, 100, "px"));
  cmd->add_option("--noise", a.options.synth.noise, "Gaussian sensor noise, 8-bit levels")
      ->capture_default_str()
      ->check(Number(0, 255, "levels"));
  cmd->add_option("--min-bin", a.options.min_bin, "Corners per bin of predicted sigma")
      ->capture_default_str()
      ->check(Number(2, 1e9, "corners", true));
  cmd->add_option_function<std::string>(
         "--noise-model",
         [&a](const std::string& v) {
           a.options.noise_model = v == "view" ? ValidateOptions::NoiseModel::kView
                                               : ValidateOptions::NoiseModel::kCorner;
         },
         "Each detection's noise in the prediction: corner (its window's precision scaled by "
         "its view's residuals; default) or view (its view's residual RMS)")
      ->check(CLI::IsMember({"corner", "view"}));
  cmd->add_option("--tolerance", a.tolerance, "The verdict's tolerance on measured / predicted RMS")
      ->capture_default_str()
      ->check(Number(0, 10, "", false, true));
  cmd->add_option("--time-sample", a.time_sample,
                  "Time sample of a scene with moving objects (default: the first)")
      ->check(Number(0, 1e6, "sample", true));
  cmd->add_flag("--quiet", a.quiet, "Print nothing but errors");
  cmd->add_option("--threads", common.threads, "Worker threads (default: all cores)")
      ->check(common.threads_check);
  return {cmd, [args] { return RunValidate(*args); }};
}

}  // namespace pandora::app
