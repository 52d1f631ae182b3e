// `pandora accuracy`: error against run time for the approximations Pandora makes or could make
// (issue 3, point 6). The studies are app/session/accuracy.h, their tables, CSV files and plots
// app/report/accuracy_tables.h; this runs them in turn, prints each table as it is done and
// writes every file in one output transaction.
#include <tbb/global_control.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/helper_program.h"
#include "app/output.h"
#include "app/report/accuracy_tables.h"
#include "app/session/accuracy.h"
#include "app/session/study.h"

namespace pandora::app {
namespace {

// The GPU renderer against the exact one: pandora_gl_bench (beside this program, the only code that
// links GL) on the scene's first view, its CSV read back.
// The bench program; InputError naming --gpu when it cannot run (checked before any study runs).
std::string GpuBench(const Scene& scene) {
  const std::string bench = HelperProgram("pandora_gl_bench", "--gpu", "the GPU bench");
  // No display needed: without one the bench's GL context is headless EGL (viewer/gl/context.h).
  if (scene.views.empty())
    throw InputError("--gpu", "", "the scene has no views to render", "add one to \"views\"");
  return bench;
}

report::AccuracySection GpuStudy(const Scene& scene, const Rig& rig, bool quick) {
  const std::string bench = GpuBench(scene);
  char name[] = "/tmp/pandora_gpu_XXXXXX";
  const int fd = mkstemp(name);
  if (fd < 0) throw InputError("--gpu", "", "cannot create a temporary file");
  close(fd);
  const std::string size = quick ? "320x180" : "1280x720";
  const std::string frames = quick ? "1" : "5";
  const int status =
      RunHelperProgram({bench, scene.path, "--rig", rig.name, "--size", size, "--frames", frames,
                        "--cpu-frames", quick ? "1" : "3", "--csv", name},
                       true);
  const std::string csv =
      status == 0 ? ReadInputFile(name, 1 << 20, "GPU bench output") : std::string();
  std::remove(name);
  if (csv.empty())
    throw InputError(
        "--gpu", "",
        "the GPU bench failed (exit " + std::to_string(status) + "; its message is above)",
        "without a display it needs EGL: install libegl1 and libegl-mesa0, or run "
        "under `xvfb-run -a`");
  const std::string note = "view '" + scene.views.begin()->first + "' at " + size + ", rig " +
                           rig.name + " (" + std::to_string(rig.enabled_count()) +
                           " cameras); times are of this machine's GL";
  return report::GpuSection(report::ParseGpuAccuracyCsv(csv, bench), note);
}

}  // namespace

int RunAccuracy(const AccuracyArgs& args) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  const auto study = session::Study::Load(args.scene);  // the scene and its ray caster, once
  const Scene& scene = study->scene();
  const Rig rig =
      session::DisableCameras(study->FindRig(args.rig, "--rig"), args.disable, "--disable");
  if (args.gpu && !args.disable.empty())  // the GL bench runs the rig as the file has it
    throw InputError("--disable", "", "cannot be combined with --gpu",
                     "run the GPU study without --disable");
  const AccuracyOptions options = args.quick ? AccuracyOptions::Quick() : AccuracyOptions();
  options.Check();
  if (args.gpu) GpuBench(scene);  // a missing display fails now, not after the other studies
  OutputTransaction output;
  AddSceneInputs(output, scene);
  // Staged first, so that a bad --out fails before minutes of work; written last.
  const std::filesystem::path dir(args.out);
  const std::string tables_path = output.Stage((dir / "accuracy_tables.md").string(), "--out");
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  std::printf(
      "accuracy: %s, rig %s (%d cameras), study voxel %g mm, pixel sigma %.3g px, %d threads%s\n",
      scene.path.c_str(), rig.name.c_str(), rig.enabled_count(), 1e3 * scene.study.voxel_size,
      scene.study.pixel_sigma, threads, args.quick ? ", quick" : "");
  std::fflush(stdout);
  const RayCaster* caster = &study->caster();

  std::string markdown = report::AccuracyTablesHeading(scene.path, rig.name);
  std::vector<std::string> written;
  auto emit = [&](const report::AccuracySection& section) {
    std::printf("%s", section.Text().c_str());
    std::fflush(stdout);
    markdown += section.Markdown();
    for (const auto& [name, text] :
         {std::pair{section.csv_name, section.csv}, std::pair{section.svg_name, section.svg}}) {
      const std::string path = (dir / name).string();
      output.Write(path, "--out", text);
      written.push_back(path);
    }
  };
  emit(report::VoxelSection(RunVoxelStudy(scene, rig, *caster, options)));
  const MonteCarloStudy monte_carlo = RunMonteCarloStudy(scene, rig, *caster, options);
  emit(report::MonteCarloSection(monte_carlo, threads));
  emit(report::SteadySection(RunSteadyStudy(scene, monte_carlo, options)));
  emit(report::RefineSection(RunRefineStudy(scene, rig, *caster, &study->solid_trees())));
  emit(report::GateSection(RunGateStudy(scene, rig, *caster, options)));
  if (args.gpu) emit(GpuStudy(scene, rig, args.quick));

  WriteFileAtomically(tables_path, markdown);
  written.push_back(tables_path);
  output.Commit();
  std::printf("\n%.1f s; wrote", std::chrono::duration<double>(Clock::now() - start).count());
  for (const std::string& path : written)
    std::printf(" %s", std::filesystem::path(path).filename().c_str());
  std::printf(" in %s\n", args.out.c_str());
  return 0;
}

// Registers `pandora accuracy` and its options.
Command AddAccuracyCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<AccuracyArgs>();
  AccuracyArgs& accuracy = *args;
  int& threads = common.threads;
  const CLI::Validator& threads_check = common.threads_check;
  CLI::App* acc = app.add_subcommand("accuracy",
                                     "Error against run time: voxel size, Monte Carlo trials, "
                                     "steady-state solvers, coarse-to-fine, and the Monte Carlo "
                                     "gate per voxel");
  acc->add_option("scene", accuracy.scene, "Scene file (JSON)")->required();
  acc->add_option("--rig", accuracy.rig, "Rig name (default: the first rig)");
  acc->add_option("--disable", accuracy.disable,
                  "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                  "loses when they fail)")
      ->delimiter(',');
  acc->add_option("--out", accuracy.out, "Output folder")->capture_default_str();
  acc->add_flag("--quick", accuracy.quick,
                "Fewer voxel sizes, trials and sample points (for tests)");
  acc->add_flag("--gpu", accuracy.gpu,
                "Also the GPU renderer of pandora view against the exact one per shadow-map size "
                "(needs a display)");
  acc->add_option("--threads", threads, "Worker threads (default: all cores)")
      ->check(threads_check);
  return {acc, [args] { return RunAccuracy(*args); }};
}

}  // namespace pandora::app
