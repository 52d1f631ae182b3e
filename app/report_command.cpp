// `pandora report`: one self-contained HTML page per scene (docs/report.md). The page and its
// numbers are app/report/report.h; this parses the options, checks them, runs and prints.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/rig_check.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/report/report.h"
#include "app/session/study.h"
#include "app/validate_report.h"
#include "validation/validate.h"

namespace pandora::app {
namespace {

// "--rig a,b --rig c": every name, in order, empty parts dropped.
std::vector<std::string> SplitList(const std::vector<std::string>& items) {
  std::vector<std::string> out;
  for (const std::string& item : items) {
    std::stringstream ss(item);
    std::string part;
    while (std::getline(ss, part, ','))
      if (!part.empty()) out.push_back(part);
  }
  return out;
}

// --disable: each id disabled in every rig of the report that has it; an id that none of them has
// (or an empty one) is an error naming the option.
void DisableInReportRigs(Scene* scene, const std::vector<std::string>& rigs,
                         const std::vector<std::string>& ids) {
  std::vector<Rig*> selected;
  for (Rig& rig : scene->rigs)
    if (rigs.empty() || std::find(rigs.begin(), rigs.end(), rig.name) != rigs.end())
      selected.push_back(&rig);
  for (const std::string& id : ids) {
    if (id.empty()) throw InputError("--disable", "", "an empty camera id", "e.g. --disable c1,c2");
    bool found = false;
    for (Rig* rig : selected) {
      const int index = rig->FindCamera(id);
      if (index < 0) continue;
      rig->cameras[index].enabled = false;
      found = true;
    }
    if (found) continue;
    std::string names, cameras;
    for (const Rig* rig : selected) {
      names += (names.empty() ? "'" : ", '") + rig->name + "'";
      cameras += (cameras.empty() ? "" : "; ") + rig->name + ": " + rig->CameraIds();
    }
    throw InputError("--disable", "", "no camera '" + id + "' in rig " + names,
                     "cameras: " + cameras);
  }
}

}  // namespace

int RunReport(const ReportArgs& args) {
  const auto study = session::Study::Load(args.scene);  // the scene and its ray caster, once
  const Scene& scene = study->scene();
  report::ReportOptions options;
  options.rigs = SplitList(args.rigs);
  options.voxel_size = args.voxel_size;
  options.view_width = args.width;
  options.camera_width = args.camera_width;
  options.brightness = args.brightness;
  std::optional<ProgressBar> bar;  // one per rig's field evaluation
  options.rig_started = [&](const std::string& rig) { bar.emplace("report " + rig, !args.quiet); };
  options.progress = [&](double fraction) { bar->Update(fraction); };
  options.Check(scene);
  // --validate: each rig's validation study on the scene at its first time sample.
  Scene validation_scene;
  if (args.validate) {
    validation_scene = scene.Animated() ? SceneAtSample(scene, scene.TimeSamples().front()) : scene;
    options.validation_intro =
        "A ChArUco board waved through the region, rendered in every camera, detected by OpenCV "
        "and triangulated with the known cameras: measured / predicted RMS error along each "
        "principal axis of the predicted covariance, per bin of predicted &sigma;max (1 = as "
        "predicted; &ldquo;one &sigma;&rdquo;: against the design's single pixel noise). "
        "<code>pandora validate</code> writes the full tables (docs/validation.md).";
    options.validation = [&](const Rig& rig, const auto& svg_image) {
      ValidateOptions o;
      o.poses = args.validate_poses;
      ProgressBar validation_bar("validate " + rig.name, !args.quiet);
      const ValidateResult r = RunValidation(validation_scene, rig, o, [&](int done, int total) {
        validation_bar.Update(double(done) / total);
      });
      validation_bar.Finish();
      return ValidationCellHtml(r, o.min_bin, 0.25, svg_image);
    };
  }
  // --disable applies to a copy of the scene whose rigs the report evaluates.
  Scene disabled;
  if (!args.disable.empty()) {
    disabled = scene;
    DisableInReportRigs(&disabled, options.rigs, args.disable);
  }
  const Scene& report_scene = args.disable.empty() ? scene : disabled;

  OutputTransaction output;
  AddSceneInputs(output, scene);
  const report::ReportTarget target = report::StageReport(output, args.out, "--out");
  const RayCaster* caster = &study->caster();
  const report::ReportData data = report::ComputeReport(report_scene, *caster, options);
  bar.reset();
  const report::ReportFile file = report::WriteReport(report_scene, *caster, data, options, target);
  output.Commit();
  if (!args.quiet) {
    std::printf("wrote %s (%d images, %.1f MiB)\n", file.path.c_str(), file.images,
                file.bytes / 1048576.0);
    std::fflush(stdout);
    for (const report::RigReport& r : data.rigs)
      for (const Warning& w : r.warnings)
        std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  }
  return 0;
}

// Registers `pandora report` and its options.
Command AddReportCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<ReportArgs>();
  ReportArgs& report = *args;
  int& threads = common.threads;
  const CLI::Validator& threads_check = common.threads_check;
  CLI::App* rep = app.add_subcommand("report",
                                     "One self-contained HTML report: renders, field slices, "
                                     "histograms, cameras, rigs side by side");
  rep->add_option("scene", report.scene, "Scene file (JSON)")->required();
  rep->add_option("--rig", report.rigs,
                  "Rig name(s), repeatable or comma-separated (default: every rig)");
  rep->add_option("--disable", report.disable,
                  "Camera ids to disable in every rig of the report that has them, comma-separated "
                  "or repeated")
      ->delimiter(',');
  rep->add_option("--out", report.out, "Output folder (report.html is written there)")
      ->capture_default_str();
  rep->add_option("--voxel-size", report.voxel_size,
                  "Voxel size in metres (default: study.voxel_size)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  rep->add_option("--width", report.width, "Width in pixels of the renders from the named views")
      ->capture_default_str()
      ->check(Number(16, 8192, "pixels", true));
  rep->add_option("--camera-width", report.camera_width,
                  "Width in pixels of each camera's own view")
      ->capture_default_str()
      ->check(Number(16, 8192, "pixels", true));
  rep->add_option(
         "--brightness", report.brightness,
         "Scale of every camera's light in the renders (default min(1, 3 / enabled cameras))")
      ->check(Number(0, 1e6, "times one camera's light", false, true));
  rep->add_option("--threads", threads, "Worker threads (default: all cores)")
      ->check(threads_check);
  rep->add_flag("--quiet,-q", report.quiet, "Print nothing but errors");
  rep->add_flag("--validate", report.validate,
                "Add a \"Predicted against measured\" section: a board synthesised through the "
                "region, detected by OpenCV, triangulated, against the predicted uncertainty (a "
                "minute per rig)");
  rep->add_option("--validate-poses", report.validate_poses, "Board poses of --validate")
      ->capture_default_str()
      ->check(Number(1, 100000, "poses", true));
  return {rep, [args] { return RunReport(*args); }};
}

}  // namespace pandora::app
