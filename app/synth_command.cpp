// `pandora synth` (issue 31, point 1; docs/validation.md): every enabled camera's synthetic image
// at its native resolution through its exact lens, with the ground truth beside it: the rig as
// OpenCV YAML and as a COLMAP text model, every fiducial corner's 3D point and exact pixel in each
// camera that images it, and a depth layer (EXR). All outputs in one transaction.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/rig/rig_formats.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/output.h"
#include "render/prepared_scene.h"
#include "render/render.h"
#include "validation/synth.h"

namespace pandora::app {
namespace {

struct SynthArgs {
  std::string scene, rig, out = "out/synth";
  std::vector<std::string> cameras;  ///< Empty: every enabled camera.
  SynthOptions synth;
  int time_sample = -1;  ///< -1: the first of an animated scene.
  bool quiet = false;
};

std::vector<int> ChosenCameras(const Rig& rig, const std::vector<std::string>& ids) {
  std::vector<int> chosen;
  if (ids.empty()) {
    for (int c = 0; c < static_cast<int>(rig.cameras.size()); ++c)
      if (rig.cameras[c].enabled) chosen.push_back(c);
    return chosen;
  }
  for (const std::string& id : ids) {
    int found = -1;
    for (int c = 0; c < static_cast<int>(rig.cameras.size()); ++c)
      if (rig.cameras[c].id == id) found = c;
    if (found < 0) throw InputError("--cameras", "", "no camera '" + id + "' in rig " + rig.name);
    chosen.push_back(found);
  }
  return chosen;
}

std::string CornersCsv(const Scene& scene, const Rig& rig, const std::vector<CornerTruth>& truth) {
  std::string csv = "fiducial,kind,corner,x_m,y_m,z_m,camera,u_px,v_px\n";
  for (const CornerTruth& t : truth) {
    const Fiducial& f = scene.fiducials[t.fiducial];
    const std::string head = f.name + "," + FiducialKindName(f.kind) + "," + std::to_string(t.id) +
                             "," + Format("%.9g,%.9g,%.9g", t.X.x(), t.X.y(), t.X.z());
    if (t.views.empty()) csv += head + ",,,\n";
    for (const CornerView& v : t.views)
      csv +=
          head + "," + rig.cameras[v.camera].id + Format(",%.6f,%.6f\n", v.pixel.x(), v.pixel.y());
  }
  return csv;
}

int RunSynth(const SynthArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  args.synth.Check();
  std::string label;
  const Scene scene = LoadSceneAtSample(args.scene, args.time_sample, &label);
  const Rig& rig = FindRigOption(scene, args.rig);
  const std::vector<int> cameras = ChosenCameras(rig, args.cameras);
  if (cameras.empty()) throw InputError("--rig", "", "rig " + rig.name + " has no enabled camera");
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::filesystem::path dir(args.out);
  // Staged first: a bad --out fails before the images are rendered.
  const std::string manifest_path = output.Stage((dir / "synth.json").string(), "--out");

  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const PreparedScene prepared(scene, *caster);
  nlohmann::json images = nlohmann::json::array();
  ProgressBar bar("synth", !args.quiet);
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const int c = cameras[i];
    const Camera& cam = rig.cameras[c];
    const auto t0 = std::chrono::steady_clock::now();
    const SynthImage image = RenderSynth(prepared, rig, c, args.synth);
    const std::string name = ColmapImageName(cam);
    const std::string stem = name.substr(0, name.size() - 4);
    output.Write((dir / "images" / name).string(), "--out",
                 EncodePngSrgb8(image.width, image.height, image.rgb));
    WriteExr(image.linear, output.Stage((dir / "depth" / (stem + ".exr")).string(), "--out"),
             static_cast<int>(rig.cameras.size()));
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    images.push_back({{"camera", cam.id},
                      {"image", "images/" + name},
                      {"depth", "depth/" + stem + ".exr"},
                      {"width", image.width},
                      {"height", image.height},
                      {"seconds", seconds}});
    bar.Update(double(i + 1) / cameras.size());
    if (!args.quiet)
      std::printf("synth: [%zu/%zu] %s %dx%d %.2f s\n", i + 1, cameras.size(), cam.id.c_str(),
                  image.width, image.height, seconds);
  }
  bar.Finish();

  const std::vector<CornerTruth> truth = FiducialCornerTruth(scene, rig, *caster);
  output.Write((dir / "corners.csv").string(), "--out", CornersCsv(scene, rig, truth));
  output.Write((dir / "rig.yaml").string(), "--out", RigToOpenCvYaml(rig));
  const ColmapText colmap = RigToColmap(rig);
  output.Write((dir / "colmap" / "cameras.txt").string(), "--out", colmap.cameras);
  output.Write((dir / "colmap" / "images.txt").string(), "--out", colmap.images);
  output.Write((dir / "colmap" / "points3D.txt").string(), "--out", colmap.points3d);
  std::size_t views = 0;
  for (const CornerTruth& t : truth) views += t.views.size();
  const nlohmann::json manifest = {{"pandora", "synth"},
                                   {"run_id", output.run_id()},
                                   {"scene", scene.path},
                                   {"scene_sha256", scene.sha256},
                                   {"rig", rig.name},
                                   {"time_sample", label},
                                   {"samples_per_pixel", args.synth.samples * args.synth.samples},
                                   {"exposure", args.synth.exposure},
                                   {"blur_px", args.synth.blur_px},
                                   {"noise_levels", args.synth.noise},
                                   {"seed", args.synth.seed},
                                   {"fiducials", scene.fiducials.size()},
                                   {"corners", truth.size()},
                                   {"corner_views", views},
                                   {"images", images}};
  WriteFileAtomically(manifest_path, manifest.dump(2) + "\n");
  output.Commit();
  if (!args.quiet)
    std::printf("synth: %zu images, %zu fiducial corners (%zu views) in %s (%.1f s)\n",
                cameras.size(), truth.size(), views, args.out.c_str(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}

}  // namespace

// Registers `pandora synth` and its options.
Command AddSynthCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<SynthArgs>();
  SynthArgs& a = *args;
  CLI::App* cmd = app.add_subcommand(
      "synth", "Synthetic images of every camera with their ground truth (rig, corners, depth)");
  cmd->add_option("scene", a.scene, "Scene file (JSON)")->required();
  cmd->add_option("--rig", a.rig, "Rig name (default: the first rig)");
  cmd->add_option("--out", a.out, "Output folder")->capture_default_str();
  cmd->add_option("--cameras", a.cameras, "Camera ids (default: every enabled camera)")
      ->delimiter(',');
  cmd->add_option("--samples", a.synth.samples, "Rays per pixel per axis (1 to 16)")
      ->capture_default_str()
      ->check(Number(1, 16, "samples", true));
  cmd->add_option("--exposure", a.synth.exposure, "Gain on the linear image")
      ->capture_default_str()
      ->check(Number(0, 1e6, "gain", false, true));
  cmd->add_option("--blur", a.synth.blur_px, "Gaussian optical blur, sigma in pixels")
      ->capture_default_str()
      ->check(Number(0, 100, "px"));
  cmd->add_option("--noise", a.synth.noise, "Gaussian sensor noise, sigma in 8-bit levels")
      ->capture_default_str()
      ->check(Number(0, 255, "levels"));
  cmd->add_option("--seed", a.synth.seed, "Seed of the noise")->capture_default_str();
  cmd->add_option("--time-sample", a.time_sample,
                  "Time sample of a scene with moving objects (default: the first)")
      ->check(Number(0, 1e6, "sample", true));
  cmd->add_flag("--quiet", a.quiet, "Print nothing but errors");
  cmd->add_option("--threads", common.threads, "Worker threads (default: all cores)")
      ->check(common.threads_check);
  return {cmd, [args] { return RunSynth(*args); }};
}

}  // namespace pandora::app
