// `pandora export-surface`: the scene's surfaces as a PLY point cloud with coverage, resolution and
// sigma_max per sample (docs/report.md, "Surface export").
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/rig_check.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/session/study.h"
#include "volume/surface.h"

#ifndef PANDORA_VERSION
#define PANDORA_VERSION "dev"
#endif

namespace pandora::app {

int RunExportSurface(const ExportSurfaceArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  // Options first: a bad --spacing or --out is reported before the scene's meshes are read.
  CheckPositiveOption("--spacing", args.spacing, "metres");
  if (args.out.empty())
    throw InputError("--out", "", "no output file given", "e.g. --out surface.ply");
  const auto study = session::Study::Load(args.scene);
  const Scene& scene = study->scene();
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string staged = output.Stage(args.out, "--out");
  const Rig rig =
      session::DisableCameras(study->FindRig(args.rig, "--rig"), args.disable, "--disable");
  const SurfaceSelection selection =
      args.all_surfaces ? SurfaceSelection::kAll : SurfaceSelection::kFacing;
  const std::vector<SurfaceSample> samples =
      SampleSurfaces(scene, args.spacing, args.seed, "--spacing", selection, &rig);
  const RayCaster* caster = &study->caster();
  const std::vector<PointValues> values =
      PointEvaluator(scene, rig, *caster).EvaluateSamples(samples);

  std::int64_t seen = 0, triangulable = 0;
  for (const PointValues& v : values) {
    seen += v.coverage > 0;
    triangulable += v.triangulable;
  }
  char spacing[32];
  std::snprintf(spacing, sizeof spacing, "%.6g", args.spacing);
  std::vector<std::string> comments{
      "pandora " PANDORA_VERSION " export-surface",
      "scene " + scene.path + " sha256 " + scene.sha256,
      "rig " + rig.name + " (" + std::to_string(rig.enabled_count()) + " enabled cameras)",
      std::string("spacing_m ") + spacing + " seed " + std::to_string(args.seed),
      args.all_surfaces ? "surfaces: all (--all-surfaces)"
                        : "surfaces: facing the region or a camera (some region point or enabled "
                          "camera centre in front of the triangle's plane); --all-surfaces for all",
      "units: x y z metres; coverage cameras; resolution px/m (0: unseen); sigma_max mm "
      "(0 where triangulable is 0)",
      "red green blue: viridis of coverage / enabled cameras, grey where no camera sees the point"};
  for (std::size_t i = 0; i < scene.objects.size(); ++i)
    comments.push_back("object " + std::to_string(i) + " " + scene.objects[i].name);
  WriteSurfacePly(staged, samples, values, rig.enabled_count(), comments);
  output.Commit();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!args.quiet) {
    const double n = samples.empty() ? 1.0 : double(samples.size());
    std::printf("rig %s: %zu surface samples at %s m spacing, %.1f%% seen, %.1f%% triangulable\n",
                rig.name.c_str(), samples.size(), spacing, 100.0 * seen / n,
                100.0 * triangulable / n);
    if (!args.all_surfaces)
      std::printf(
          "surfaces facing the region or a camera: %.3g of %.3g m^2 (--all-surfaces for all)\n",
          SurfaceArea(scene, selection, &rig), SurfaceArea(scene));
    std::printf("wrote %s (%.2f s)\n", args.out.c_str(), seconds);
    std::fflush(stdout);
    for (const Warning& w : CheckRig(scene, rig, *caster))
      std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  }
  return 0;
}

// Registers `pandora export-surface` and its options.
Command AddExportSurfaceCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<ExportSurfaceArgs>();
  ExportSurfaceArgs& surface = *args;
  int& threads = common.threads;
  const CLI::Validator& threads_check = common.threads_check;
  CLI::App* es = app.add_subcommand(
      "export-surface",
      "Sample the scene's surfaces; write coverage, resolution and sigma_max per sample as PLY");
  es->add_option("scene", surface.scene, "Scene file (JSON)")->required();
  es->add_option("--rig", surface.rig, "Rig name (default: the first rig)");
  es->add_option("--disable", surface.disable,
                 "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                 "loses when they fail)")
      ->delimiter(',');
  es->add_option("--spacing", surface.spacing, "Distance between samples in metres")
      ->capture_default_str()
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  es->add_option("--out", surface.out, "Output PLY file")->required();
  es->add_option("--seed", surface.seed, "Seed of the sample positions")
      ->capture_default_str()
      ->check(Number(0, 9.2e18, "(any whole number)", true));
  es->add_flag(
      "--all-surfaces", surface.all_surfaces,
      "Sample every surface, also those facing away from the study region and every camera");
  es->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  es->add_flag("--quiet,-q", surface.quiet, "Print nothing but errors");
  return {es, [args] { return RunExportSurface(*args); }};
}

}  // namespace pandora::app
