// `pandora bench --render`: the renderer against raw Embree loops over the very same rays, measured
// in the same run (interleaved, best of each), so the ratio means something on a shared machine.
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/commands.h"
#include "app/options.h"
#include "app/output.h"
#include "app/session/study.h"
#include "render/prepared_scene.h"
#include "render/progressive.h"
#include "render/render.h"

namespace pandora::app {
namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// The best time of each measurement over the runs (seconds), the last run's hit and occluded
// counts, and the ratios of the render to the raw Embree loops.
struct RenderBenchTimes {
  double best_render = std::numeric_limits<double>::infinity(), best_layers = best_render;
  double best_primary = best_render, best_packet = best_render, best_single = best_render;
  double best_primary_packet = best_render;
  double best_prepared = best_render, best_with_bvh = best_render;
  double best_hidden_once = best_render, best_hidden_prepared = best_render;
  std::array<double, ProgressiveRender::kPasses> best_pass;
  double best_progressive = best_render, best_first_fresh = best_render;
  std::size_t hits = 0, occluded = 0;
  double raw = 0, raw_single = 0, ratio = 0, ratio_single = 0;
};

// Times the renderers and the raw Embree loops over the recorded rays, `repeat` runs interleaved;
// the best of each.
RenderBenchTimes TimeRenders(const Scene& scene, const Rig& rig, const RayCaster* caster,
                             const RenderView& view, const RenderOptions& options,
                             const RenderOptions& with_layers, const std::vector<Ray>& primary,
                             const std::vector<Ray>& shadow, int repeat) {
  RenderBenchTimes t;
  t.best_pass.fill(t.best_render);
  // The prepared renderer against the one-shot form, and the progressive passes.
  const PreparedScene prepared(scene, *caster);
  RenderOptions hidden_line = options;
  hidden_line.surface = Surface::kHiddenLine;
  // Progressive: after Restart (a viewer's steady state: buffers reused) and freshly constructed.
  ProgressiveRender restarted(prepared, rig, view, options);
  restarted.RunAll();
  for (int r = 0; r < repeat; ++r) {
    RenderStats s;
    RenderWithStats(scene, rig, *caster, view, options, nullptr, &s);
    t.best_render = std::min(t.best_render, s.seconds);
    RenderWithStats(scene, rig, *caster, view, with_layers, nullptr, &s);
    t.best_layers = std::min(t.best_layers, s.seconds);
    RenderWithStats(prepared, rig, view, options, nullptr, &s);
    t.best_prepared = std::min(t.best_prepared, s.seconds);
    {
      const auto t0 = std::chrono::steady_clock::now();
      const std::unique_ptr<RayCaster> own = MakeEmbreeRayCaster(scene.AllTriangles());
      Render(scene, rig, *own, view, options);
      t.best_with_bvh = std::min(t.best_with_bvh, Seconds(t0));
    }
    RenderWithStats(scene, rig, *caster, view, hidden_line, nullptr, &s);
    t.best_hidden_once = std::min(t.best_hidden_once, s.seconds);
    RenderWithStats(prepared, rig, view, hidden_line, nullptr, &s);
    t.best_hidden_prepared = std::min(t.best_hidden_prepared, s.seconds);
    {
      // Each pass from the call to its image (the first includes starting the frame).
      auto t0 = std::chrono::steady_clock::now();
      const auto start = t0;
      restarted.Restart(rig, view, options);
      for (int pass = 0; pass < ProgressiveRender::kPasses; ++pass) {
        restarted.RunPass();
        t.best_pass[pass] = std::min(t.best_pass[pass], Seconds(t0));
        t0 = std::chrono::steady_clock::now();
      }
      t.best_progressive = std::min(t.best_progressive, Seconds(start));
      t0 = std::chrono::steady_clock::now();
      ProgressiveRender fresh(prepared, rig, view, options);
      fresh.RunPass();
      t.best_first_fresh = std::min(t.best_first_fresh, Seconds(t0));
    }
    const RawOcclusionResult p = RawEmbreeIntersection(*caster, primary);
    t.best_primary = std::min(t.best_primary, p.seconds);
    t.hits = p.occluded;
    t.best_primary_packet = std::min(
        t.best_primary_packet, RawEmbreeIntersection(*caster, primary, RawMode::kPacket).seconds);
    const RawOcclusionResult sp = RawEmbreeOcclusion(*caster, shadow, RawMode::kPacket);
    t.best_packet = std::min(t.best_packet, sp.seconds);
    t.occluded = sp.occluded;
    t.best_single = std::min(t.best_single, RawEmbreeOcclusion(*caster, shadow).seconds);
  }
  t.raw = t.best_primary_packet + t.best_packet;
  t.raw_single = t.best_primary + t.best_single;
  t.ratio = t.best_render / t.raw;
  t.ratio_single = t.best_render / t.raw_single;
  return t;
}

// The results as `--json` writes them.
nlohmann::json RenderBenchJson(const BenchArgs& args, const Scene& scene, const Rig& rig,
                               const RayCaster* caster, const RenderView& view, int threads,
                               const std::vector<Ray>& primary, const std::vector<Ray>& shadow,
                               const RenderBenchTimes& t) {
  nlohmann::json j{
      {"scene", scene.path},
      {"rig", rig.name},
      {"cameras", rig.enabled_count()},
      {"triangles", caster->triangle_count()},
      {"width", view.width},
      {"height", view.height},
      {"threads", threads},
      {"repeat", args.repeat},
      {"primary_rays", primary.size()},
      {"shadow_rays", shadow.size()},
      {"render_seconds", t.best_render},
      {"raw_primary_seconds", t.best_primary},
      {"raw_primary_packet_seconds", t.best_primary_packet},
      {"raw_shadow_packet_seconds", t.best_packet},
      {"packet_width", EmbreePacketWidth(*caster)},
      {"raw_shadow_single_seconds", t.best_single},
      {"ratio", t.ratio},
      {"ratio_single", t.ratio_single},
      {"render_with_layers_seconds", t.best_layers},
      {"ratio_with_layers", t.best_layers / t.raw},
      {"ratio_single_with_layers", t.best_layers / t.raw_single},
      {"one_shot_seconds", t.best_render},
      {"one_shot_with_bvh_seconds", t.best_with_bvh},
      {"prepared_seconds", t.best_prepared},
      {"hidden_line_one_shot_seconds", t.best_hidden_once},
      {"hidden_line_prepared_seconds", t.best_hidden_prepared},
      {"ratio_prepared_to_one_shot", t.best_prepared / t.best_render},
      {"ratio_prepared_to_one_shot_with_bvh", t.best_prepared / t.best_with_bvh},
      {"ratio_hidden_line_prepared_to_one_shot", t.best_hidden_prepared / t.best_hidden_once},
      {"progressive_pass_seconds", t.best_pass},
      {"progressive_first_pass_fresh_seconds", t.best_first_fresh},
      {"ratio_first_pass_fresh_to_frame", t.best_first_fresh / t.best_prepared},
      {"ratio_first_pass_to_frame", t.best_pass[0] / t.best_prepared},
      {"ratio_all_passes_to_frame", t.best_progressive / t.best_prepared}};
  return j;
}

// Where the bench looks from: --view, else the scene's first view, else a corner of its bounds.
RenderView BenchView(const BenchArgs& args, const Scene& scene, int width, int height) {
  RenderView view;
  if (!args.view.empty()) {
    view = NamedView(scene, "--view", args.view, width, height);
  } else if (!scene.views.empty()) {
    view = ViewFromScene(scene.views.begin()->second, width, height);
  } else {
    // No views: look at the scene's centre from a corner of its bounds.
    const Aabb b = scene.Bounds();
    view.from = b.center() + Vec3(-0.6, -0.8, 0.5).cwiseProduct(b.size()) + Vec3(0, 0, 0.5);
    view.at = b.center();
    view.width = width;
    view.height = height;
  }
  return view;
}

}  // namespace

int RunRenderBench(const BenchArgs& args) {
  const auto [width, height] = ParseImageSize("--size", args.size);
  const auto study = session::Study::Load(args.scene);
  const Scene& scene = study->scene();
  const Rig& rig = study->FindRig(args.rig, "--rig");
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string json_path = args.json_out.empty() ? "" : output.Stage(args.json_out, "--json");
  const RenderView view = BenchView(args, scene, width, height);
  const std::string view_name =
      args.view.empty() && !scene.views.empty() ? scene.views.begin()->first : args.view;
  const RayCaster* caster = &study->caster();
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  RenderOptions options;  // the defaults `pandora render` uses for a PNG (no float layers)
  options.pixel_sigma = scene.study.pixel_sigma;
  options.layers = false;
  RenderOptions with_layers = options;  // ... and for an EXR
  with_layers.layers = true;

  // One recording pass gives the exact rays the renderer traces (and warms caches).
  std::vector<Ray> primary, shadow;
  RenderStats stats;
  RenderWithStats(scene, rig, *caster, view, options, nullptr, &stats, &primary, &shadow);

  const RenderBenchTimes t =
      TimeRenders(scene, rig, caster, view, options, with_layers, primary, shadow, args.repeat);
  std::printf(
      "pandora bench --render: %s, rig %s (%d enabled cameras), %zu triangles, %dx%d, view %s, "
      "%d threads\n",
      scene.path.c_str(), rig.name.c_str(), rig.enabled_count(), caster->triangle_count(),
      view.width, view.height, view_name.empty() ? "(from the bounds)" : view_name.c_str(),
      threads);
  std::printf("  primary rays %zu (%zu hit), shadow segments %zu (%zu occluded)\n", primary.size(),
              t.hits, shadow.size(), t.occluded);
  std::printf("  %-58s %9.4f s\n", "render, PNG defaults (best of runs)", t.best_render);
  std::printf("  %-58s %9.4f s\n", "render with the EXR layers (best of runs)", t.best_layers);
  const int packet_width = EmbreePacketWidth(*caster);
  const std::string w = std::to_string(packet_width);
  std::printf("  %-58s %9.4f s\n", "raw Embree rtcIntersect1 loop, same primary rays",
              t.best_primary);
  std::printf("  %-58s %9.4f s\n",
              ("raw Embree rtcIntersect" + w + " packets, same primary rays").c_str(),
              t.best_primary_packet);
  std::printf("  %-58s %9.4f s\n", "raw Embree rtcOccluded1 loop, same shadow segments",
              t.best_single);
  std::printf("  %-58s %9.4f s\n",
              ("raw Embree rtcOccluded" + w + " packets, same shadow segments").c_str(),
              t.best_packet);
  std::printf(
      "  ratio render / raw single-ray loops (rtcIntersect1 + rtcOccluded1) = %.3f "
      "(target <= 1.5)\n",
      t.ratio_single);
  std::printf(
      "  ratio render / raw packet loops (rtcIntersect%d + rtcOccluded%d) = %.3f "
      "(our overhead over Embree itself)\n",
      packet_width, packet_width, t.ratio);
  std::printf(
      "  with the EXR layers: ratio to the single-ray loops = %.3f, to the packet loops = %.3f\n",
      t.best_layers / t.raw_single, t.best_layers / t.raw);
  std::printf("  %-58s %9.4f s\n", "one-shot Render, caster given (preparation per call)",
              t.best_render);
  std::printf("  %-58s %9.4f s\n", "one-shot with its BVH build (as `pandora render`)",
              t.best_with_bvh);
  std::printf("  %-58s %9.4f s\n", "prepared Render, per frame", t.best_prepared);
  std::printf("  %-58s %9.4f s\n", "hidden-line: one-shot (edges found per call)",
              t.best_hidden_once);
  std::printf("  %-58s %9.4f s\n", "hidden-line: prepared, per frame", t.best_hidden_prepared);
  std::printf(
      "  ratio prepared frame / one-shot = %.3f (with the BVH build: %.3f; hidden-line: %.3f)\n",
      t.best_prepared / t.best_render, t.best_prepared / t.best_with_bvh,
      t.best_hidden_prepared / t.best_hidden_once);
  std::printf("  progressive passes after Restart (1 pixel per 8x8, 4x4, 2x2 block, then all):");
  for (int pass = 0; pass < ProgressiveRender::kPasses; ++pass)
    std::printf(" %.4f", t.best_pass[pass]);
  std::printf(" s\n");
  std::printf("  %-58s %9.4f s\n", "first pass of a new ProgressiveRender (fresh buffers)",
              t.best_first_fresh);
  std::printf(
      "  ratio first pass / prepared full frame = %.3f (new ProgressiveRender: %.3f); "
      "all passes / prepared full frame = %.3f\n",
      t.best_pass[0] / t.best_prepared, t.best_first_fresh / t.best_prepared,
      t.best_progressive / t.best_prepared);
  if (!args.json_out.empty()) {
    const nlohmann::json j =
        RenderBenchJson(args, scene, rig, caster, view, threads, primary, shadow, t);
    WriteFileAtomically(json_path, j.dump(2) + "\n");
    output.Commit();
  }
  return 0;
}

}  // namespace pandora::app
