// pandora_gl_render: one picture on the GPU renderer (viewer/gl/renderer.h), what `pandora render
// --gpu` runs (the GL code stays out of `pandora`): the viewpoint and options come resolved from
// it, the PNG goes where it says (its staged output), and unless --no-compare the exact CPU
// renderer draws the same view and the agreement is printed (docs/viewer.md, "pandora render
// --gpu").
//
//   pandora_gl_render SCENE --rig NAME --out X.png --size WxH (--camera-index N |
//       --from X,Y,Z --at X,Y,Z --up X,Y,Z --fov DEG [--clip-near M]) [--disabled I,J]
//       [--pattern uniform|grid] [--grid N] [--surface S] [--brightness B] [--shadow-map N]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "analysis/util/error.h"
#include "render/prepared_scene.h"
#include "render/render.h"
#include "viewer/gl/compare.h"
#include "viewer/gl/context.h"
#include "viewer/gl/renderer.h"

using namespace pandora;

namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Vec3 Triple(const std::vector<double>& v) { return Vec3(v.at(0), v.at(1), v.at(2)); }

// The GPU frame as an Image for WritePng (linear RGB).
Image ToImage(const GlImage& g) {
  Image image;
  image.width = g.width;
  image.height = g.height;
  image.rgb = g.rgb;
  return image;
}

// Prints how far the GPU frame is from the exact CPU renderer's of the same view.
void PrintComparison(const PreparedScene& prepared, const Rig& rig, const RenderView& view,
                     const RenderOptions& cpu_options, const GlImage& gpu, double gpu_seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  const Image cpu = Render(prepared, rig, view, cpu_options);
  const double cpu_seconds = Seconds(t0);
  const bool sampled = rig.cameras.size() > std::size_t(Image::kMaxMaskCameras);
  const GlComparison c = sampled ? CompareSampled(PixelPicker(prepared, rig, view), cpu, gpu, 20000)
                                 : Compare(cpu, gpu);
  std::printf(
      "against the exact CPU renderer (%.3f s, %.1f times the GPU frame): camera sets differ on "
      "%.4f %% of the %s pixels off the one-pixel edge band (%.3f %% of all), (pixel, camera) "
      "pairs on %.4f %%; colour where the sets agree: mean %.2e, largest %.2e\n",
      cpu_seconds, cpu_seconds / std::max(gpu_seconds, 1e-9), 100 * c.mask_share(),
      sampled ? "sampled" : "compared", 100 * c.mask_share_all(), 100 * c.pair_share(), c.rgb_mean,
      c.rgb_max);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("One picture on the GPU renderer (what `pandora render --gpu` runs)");
  std::string scene_path, rig_name, out, size = "1280x720", pattern = "uniform";
  std::string surface = "material";
  int camera = -1, grid = 32, shadow_map = 2048;
  std::vector<double> from, at, up{0, 0, 1};
  std::vector<int> disabled;
  double fov = 60, clip_near = 0, brightness = std::nan("");
  bool no_compare = false;
  app.add_option("scene", scene_path, "scene.json")->required();
  app.add_option("--rig", rig_name, "rig (default: the first)");
  app.add_option("--out", out, "PNG to write")->required();
  app.add_option("--size", size, "WxH");
  app.add_option("--camera-index", camera, "a camera's-eye view of this rig camera");
  app.add_option("--from", from)->expected(3)->delimiter(',');
  app.add_option("--at", at)->expected(3)->delimiter(',');
  app.add_option("--up", up)->expected(3)->delimiter(',');
  app.add_option("--fov", fov);
  app.add_option("--clip-near", clip_near);
  app.add_option("--disabled", disabled, "rig camera indices to disable")->delimiter(',');
  app.add_option("--pattern", pattern);
  app.add_option("--grid", grid);
  app.add_option("--surface", surface);
  app.add_option("--brightness", brightness);
  app.add_option("--shadow-map", shadow_map);
  app.add_flag("--no-compare", no_compare, "skip the exact CPU renderer's picture");
  CLI11_PARSE(app, argc, argv);
  try {
    const Scene scene = LoadScene(scene_path);
    Rig rig = scene.FindRig(rig_name);
    for (int i : disabled)
      if (i >= 0 && i < int(rig.cameras.size())) rig.cameras[std::size_t(i)].enabled = false;
    RenderView view;
    if (std::sscanf(size.c_str(), "%dx%d", &view.width, &view.height) != 2)
      throw std::invalid_argument("--size must be WxH");
    if (camera >= 0) {
      view.camera = camera;
    } else {
      view.from = Triple(from);
      view.at = Triple(at);
      view.up = Triple(up);
      view.fov_deg = fov;
      view.clip_near = clip_near;
    }
    const std::optional<Pattern> p = PatternFromName(pattern);
    const std::optional<Surface> s = SurfaceFromName(surface);
    if (!p || !s) throw std::invalid_argument("unknown --pattern or --surface");
    GlRenderOptions options;
    options.pattern = *p;
    options.surface = *s;
    options.grid_pixels = grid;
    options.brightness = brightness;
    options.shadow_map_size = shadow_map;

    const PreparedScene prepared(scene);
    GlContext context;
    GlRenderer renderer(scene, &prepared);
    renderer.Render(rig, view, options);  // programs, targets and the lens table, once
    GlFrameStats stats;
    const GlImage gpu = renderer.Render(rig, view, options, &stats);
    WritePng(ToImage(gpu), out);
    std::printf("GPU (%s): %dx%d in %.1f ms a frame (maps %.1f ms, light %.1f ms), maps %d\n",
                context.Description().c_str(), gpu.width, gpu.height, 1e3 * stats.total_seconds,
                1e3 * stats.shadow_seconds, 1e3 * stats.light_seconds, shadow_map);
    if (!no_compare) {
      RenderOptions cpu_options;
      cpu_options.pattern = options.pattern;
      cpu_options.surface = options.surface;
      cpu_options.grid_pixels = grid;
      cpu_options.brightness = brightness;
      cpu_options.layers = false;
      cpu_options.overlays.cameras = false;
      cpu_options.overlays.key = false;
      PrintComparison(prepared, rig, view, cpu_options, gpu, stats.total_seconds);
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "pandora_gl_render: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pandora_gl_render: %s\n", e.what());
    return 1;
  }
  return 0;
}
