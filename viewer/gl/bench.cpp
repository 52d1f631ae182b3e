// pandora_gl_bench: the GPU renderer's frame time and its agreement with the exact CPU renderer
// per shadow-map size, with the CPU frame time for the same view as the baseline (docs/viewer.md).
//
//   pandora_gl_bench examples/trauma_room/scene.json --rig octagon --view overview --size 1280x720
//   pandora_gl_bench lens_room --size 1280x720       (the generated scene of gl_test_scenes.h)
//   pandora_gl_bench lens_room --gl egl              (headless: a GPU server without X)
//   pandora_gl_bench examples/capture_stage/scene.json --cameras 200   (a rig of 200 cameras)
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <sstream>
#include <vector>

#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "render/prepared_scene.h"
#include "render/render.h"
#include "viewer/gl/compare.h"
#include "viewer/gl/context.h"
#include "viewer/gl/renderer.h"
#include "viewer/gl/test_scenes.h"

using namespace pandora;

namespace {
double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Median seconds of `frames` GPU frames (after one that allocates) drawing every map, of their
// parts, and of frames that move only the eye (maps kept: GlRenderOptions::reuse_maps).
struct GpuTimes {
  double total = 0, shadow = 0, light = 0, readback = 0, eye_only = 0;
};
GpuTimes TimeFrames(GlRenderer& renderer, const Rig& rig, const RenderView& view,
                    const GlRenderOptions& options, int frames, GlImage* last) {
  std::vector<double> total, shadow, light, readback, eye_only;
  for (int i = 0; i < frames + 1; ++i) {
    GlFrameStats stats;
    *last = renderer.Render(rig, view, options, &stats);
    if (i == 0) continue;  // allocation of the targets and maps
    total.push_back(stats.total_seconds);
    shadow.push_back(stats.shadow_seconds);
    light.push_back(stats.light_seconds);
    readback.push_back(stats.readback_seconds);
  }
  GlRenderOptions keep = options;
  keep.reuse_maps = true;
  RenderView moved = view;
  for (int i = 0; i < frames + 1; ++i) {
    moved.from = view.from + 0.01 * (i % 2) * (view.at - view.from);
    GlFrameStats stats;
    renderer.Render(rig, moved, keep, &stats);
    if (i > 0) eye_only.push_back(stats.total_seconds);
  }
  return {Median(total), Median(shadow), Median(light), Median(readback), Median(eye_only)};
}

// --verbose: per camera, the compared lit pairs where the GPU misses / adds it; the largest
// colour difference.
void PrintDetails(const Rig& rig, const Image& cpu, const GlImage& gpu, const GlComparison& c) {
  std::printf("   per camera, compared (pixel, camera) pairs where the GPU misses / adds it:");
  for (std::size_t k = 0; k < rig.cameras.size() && k < c.gpu_missing.size(); ++k)
    std::printf(" %s %zu/%zu", rig.cameras[k].id.c_str(), c.gpu_missing[k], c.gpu_extra[k]);
  std::printf("\n");
  if (c.rgb_max_x >= 0) {
    const std::size_t q = std::size_t(c.rgb_max_y) * cpu.width + std::size_t(c.rgb_max_x);
    std::printf("   largest colour difference at (%d, %d): CPU %g %g %g, GPU %g %g %g, object %d\n",
                c.rgb_max_x, c.rgb_max_y, cpu.rgb[3 * q], cpu.rgb[3 * q + 1], cpu.rgb[3 * q + 2],
                gpu.rgb[3 * q], gpu.rgb[3 * q + 1], gpu.rgb[3 * q + 2], cpu.object[q]);
  }
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app("GPU projective-light renderer: frame time and agreement with the CPU renderer");
  std::string scene_path, rig_name, view_name, size = "1280x720", png_dir;
  std::vector<int> maps = {512, 1024, 2048, 4096};
  int frames = 5, cpu_frames = 3;
  double bias = 1.0;
  std::string pattern = "uniform";
  app.add_option("scene", scene_path, "scene.json, or lens_room (generated)")->required();
  app.add_option("--rig", rig_name, "rig (default: the first)");
  app.add_option("--view", view_name, "named view (default: the first)");
  app.add_option("--size", size, "WxH");
  app.add_option("--maps", maps, "shadow-map sizes")->delimiter(',');
  app.add_option("--frames", frames, "GPU frames timed per map size (median)");
  app.add_option("--cpu-frames", cpu_frames, "CPU frames timed (median)");
  app.add_option("--bias", bias, "GlRenderOptions::shadow_bias_scale");
  app.add_option("--pattern", pattern, "uniform or grid");
  bool verbose = false;
  int shadow_mode = 2;
  app.add_option("--shadow-mode", shadow_mode, "0 distance, 1 plane, 2 either");
  app.add_flag("--verbose", verbose, "per-camera disagreement");
  app.add_option("--png", png_dir, "write CPU | GPU comparison PNGs into this folder");
  std::string gl_backend = "auto";
  app.add_option("--gl", gl_backend,
                 "GL context: egl (headless, no display), glfw (hidden window, needs a display) "
                 "or auto (PANDORA_GL, else glfw with a display, egl without)")
      ->check(CLI::IsMember({"auto", "egl", "glfw"}));
  std::string map_draws = "one-pass";
  app.add_option("--map-draws", map_draws,
                 "one-pass (every map of a frame in one layered, instanced draw) or per-map (one "
                 "draw and a CPU depth range per map)")
      ->check(CLI::IsMember({"one-pass", "per-map"}));
  int grow = 0;
  app.add_option("--cameras", grow,
                 "grow the rig to this many cameras: its cameras turned about the vertical through "
                 "the scene's centre by multiples of the golden angle (rigs of hundreds)");
  std::size_t samples = 20000;
  app.add_option("--samples", samples,
                 "rigs of over 64 cameras: pixels whose exact camera sets are picked on the CPU "
                 "for the comparison (CompareSampled)");
  std::string csv_path;
  app.add_option(
      "--csv", csv_path,
      "also write map,gpu_ms,eye_only_ms,cpu_ms,differ_compared_pct,differ_all_pct per map size "
      "(what `pandora accuracy --gpu` reads)");
  CLI11_PARSE(app, argc, argv);
  try {
    const Scene scene = scene_path == "lens_room" ? testing::LensRoom() : LoadScene(scene_path);
    const Rig rig = grow > 0 ? testing::TurnedCopies(scene.FindRig(rig_name), grow,
                                                     scene.ContentBounds().center())
                             : scene.FindRig(rig_name);
    if (scene.views.empty()) throw std::runtime_error("the scene has no views");
    const View& named = view_name.empty() ? scene.views.begin()->second : scene.views.at(view_name);
    int width = 0, height = 0;
    if (std::sscanf(size.c_str(), "%dx%d", &width, &height) != 2)
      throw std::runtime_error("--size must be WxH");
    const RenderView view = ViewFromScene(named, width, height);

    RenderOptions cpu_options;
    cpu_options.surface = Surface::kMaterial;
    cpu_options.pattern = PatternFromName(pattern).value_or(Pattern::kUniform);
    cpu_options.layers = false;
    cpu_options.overlays.cameras = false;
    cpu_options.overlays.key = false;
    const PreparedScene prepared(scene);
    Image cpu;
    std::vector<double> cpu_times;
    for (int i = 0; i < cpu_frames + 1; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      cpu = Render(prepared, rig, view, cpu_options);
      if (i > 0)  // the first frame warms caches and TBB
        cpu_times.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }

    GlBackend backend = GlBackend::kAuto;
    ParseGlBackend(gl_backend, &backend);
    GlContext context(backend);
    GlRenderer renderer(scene, &prepared);
    std::printf("device: %s\n", context.Description().c_str());
    std::printf("scene: %s (%zu triangles), rig %s (%d enabled cameras), %dx%d, pattern %s\n",
                scene_path.c_str(), renderer.triangle_count(), rig.name.c_str(),
                rig.enabled_count(), width, height, pattern.c_str());
    std::printf("CPU exact renderer: %.1f ms per frame (median of %d)\n", 1e3 * Median(cpu_times),
                cpu_frames);
    // Over 64 cameras the CPU image holds no per-pixel sets: they are picked at sampled pixels.
    const bool sampled = rig.cameras.size() > std::size_t(Image::kMaxMaskCameras);
    std::unique_ptr<PixelPicker> picker;
    if (sampled) {
      picker = std::make_unique<PixelPicker>(prepared, rig, view);
      std::printf("camera sets compared on %zu sampled pixels (exact CPU sets picked there)\n",
                  std::min(samples, std::size_t(width) * height));
    }
    std::printf("\n");
    std::printf(
        "| Map | GPU frame ms | maps ms | light ms | eye-only frame ms | read-back ms | CPU / GPU "
        "| differ (compared) | differ (all) | excluded | pairs differ | pairs compared | RGB max | "
        "RGB > 1e-3 | RGB mean | RGB mean all |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::string csv = "map,gpu_ms,eye_only_ms,cpu_ms,differ_compared_pct,differ_all_pct\n";
    for (int map : maps) {
      GlRenderOptions options;
      options.pattern = cpu_options.pattern;
      options.shadow_map_size = map;
      options.reuse_maps = false;  // every frame draws every map
      options.shadow_bias_scale = bias;
      options.shadow_test = GlRenderOptions::ShadowTest(shadow_mode);
      options.one_pass_maps = map_draws == "one-pass";
      GlImage gpu;
      const GpuTimes t = TimeFrames(renderer, rig, view, options, frames, &gpu);
      const GlComparison c =
          sampled ? CompareSampled(*picker, cpu, gpu, samples) : Compare(cpu, gpu);
      std::printf(
          "| %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.4f %% | %.3f %% | %.2f %% | %.4f %% "
          "| "
          "%.1f %% | %.2e | %.4f %% | %.2e | %.2e |\n",
          map, 1e3 * t.total, 1e3 * t.shadow, 1e3 * t.light, 1e3 * t.eye_only, 1e3 * t.readback,
          Median(cpu_times) / t.total, 100 * c.mask_share(), 100 * c.mask_share_all(),
          100 * c.excluded_share(), 100 * c.pair_share(), 100 * c.compared_pair_share(), c.rgb_max,
          100 * c.rgb_over_share(), c.rgb_mean, c.rgb_mean_all);
      if (verbose) PrintDetails(rig, cpu, gpu, c);
      if (!png_dir.empty() && !sampled)
        WriteComparisonPng(cpu, gpu, png_dir + "/compare_" + std::to_string(map) + ".png");
      char row[256];
      std::snprintf(row, sizeof row, "%d,%.6g,%.6g,%.6g,%.6g,%.6g\n", map, 1e3 * t.total,
                    1e3 * t.eye_only, 1e3 * Median(cpu_times), 100 * c.mask_share(),
                    100 * c.mask_share_all());
      csv += row;
    }
    if (!csv_path.empty()) WriteFileAtomically(csv_path, csv);
  } catch (const InputError& e) {
    std::fprintf(stderr, "pandora_gl_bench: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pandora_gl_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
