// pandora_gl_bench: the GPU renderer's frame time and its agreement with the exact CPU renderer
// per shadow-map size, with the CPU frame time for the same view as the baseline (docs/viewer.md).
//
//   pandora_gl_bench examples/trauma_room/scene.json --rig octagon --view overview --size 1280x720
//   pandora_gl_bench lens_room --size 1280x720       (the generated scene of gl_test_scenes.h)
//   pandora_gl_bench lens_room --gl egl              (headless: a GPU server without X)
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
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
  std::string csv_path;
  app.add_option(
      "--csv", csv_path,
      "also write map,gpu_ms,eye_only_ms,cpu_ms,differ_compared_pct,differ_all_pct per map size "
      "(what `pandora accuracy --gpu` reads)");
  CLI11_PARSE(app, argc, argv);
  try {
    const Scene scene = scene_path == "lens_room" ? testing::LensRoom() : LoadScene(scene_path);
    const Rig& rig = scene.FindRig(rig_name);
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
    std::printf("CPU exact renderer: %.1f ms per frame (median of %d)\n\n", 1e3 * Median(cpu_times),
                cpu_frames);
    std::printf(
        "| Map | GPU frame ms | maps ms | light ms | eye-only frame ms | read-back ms | CPU / GPU "
        "| differ (compared) | differ (all) | excluded | RGB max | RGB > 1e-3 | RGB mean | RGB "
        "mean all |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::string csv = "map,gpu_ms,eye_only_ms,cpu_ms,differ_compared_pct,differ_all_pct\n";
    for (int map : maps) {
      GlRenderOptions options;
      options.pattern = cpu_options.pattern;
      options.shadow_map_size = map;
      options.reuse_maps = false;  // every frame draws every map
      options.shadow_bias_scale = bias;
      options.shadow_test = GlRenderOptions::ShadowTest(shadow_mode);
      GlImage gpu;
      std::vector<double> total, shadow, light, readback;
      for (int i = 0; i < frames + 1; ++i) {
        GlFrameStats stats;
        gpu = renderer.Render(rig, view, options, &stats);
        if (i == 0) continue;  // allocation of the targets and maps
        total.push_back(stats.total_seconds);
        shadow.push_back(stats.shadow_seconds);
        light.push_back(stats.light_seconds);
        readback.push_back(stats.readback_seconds);
      }
      // Frames that move only the eye: the maps are kept (GlRenderOptions::reuse_maps).
      std::vector<double> eye_only;
      {
        GlRenderOptions keep = options;
        keep.reuse_maps = true;
        RenderView moved = view;
        for (int i = 0; i < frames + 1; ++i) {
          moved.from = view.from + 0.01 * (i % 2) * (view.at - view.from);
          GlFrameStats stats;
          renderer.Render(rig, moved, keep, &stats);
          if (i > 0) eye_only.push_back(stats.total_seconds);
        }
      }
      const GlComparison c = Compare(cpu, gpu);
      std::printf(
          "| %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.4f %% | %.3f %% | %.2f %% | %.2e | "
          "%.4f %% | %.2e | %.2e |\n",
          map, 1e3 * Median(total), 1e3 * Median(shadow), 1e3 * Median(light),
          1e3 * Median(eye_only), 1e3 * Median(readback), Median(cpu_times) / Median(total),
          100 * c.mask_share(), 100 * c.mask_share_all(), 100 * c.excluded_share(), c.rgb_max,
          100 * c.rgb_over_share(), c.rgb_mean, c.rgb_mean_all);
      if (verbose) {
        std::printf("   per camera, compared pixels where the GPU misses / adds it:");
        for (std::size_t k = 0; k < rig.cameras.size() && k < 64; ++k)
          std::printf(" %s %zu/%zu", rig.cameras[k].id.c_str(), c.gpu_missing[k], c.gpu_extra[k]);
        std::printf("\n");
        if (c.rgb_max_x >= 0) {
          const std::size_t q = std::size_t(c.rgb_max_y) * width + c.rgb_max_x;
          std::printf(
              "   largest colour difference at (%d, %d): CPU %g %g %g, GPU %g %g %g, object %d\n",
              c.rgb_max_x, c.rgb_max_y, cpu.rgb[3 * q], cpu.rgb[3 * q + 1], cpu.rgb[3 * q + 2],
              gpu.rgb[3 * q], gpu.rgb[3 * q + 1], gpu.rgb[3 * q + 2], cpu.object[q]);
        }
      }
      if (!png_dir.empty())
        WriteComparisonPng(cpu, gpu, png_dir + "/compare_" + std::to_string(map) + ".png");
      char row[256];
      std::snprintf(row, sizeof row, "%d,%.6g,%.6g,%.6g,%.6g,%.6g\n", map, 1e3 * Median(total),
                    1e3 * Median(eye_only), 1e3 * Median(cpu_times), 100 * c.mask_share(),
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
