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

}  // namespace

int RunRenderBench(const BenchArgs& args) {
  const auto [width, height] = ParseImageSize("--size", args.size);
  const auto study = session::Study::Load(args.scene);
  const Scene& scene = study->scene();
  const Rig& rig = study->FindRig(args.rig, "--rig");
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string json_path = args.json_out.empty() ? "" : output.Stage(args.json_out, "--json");
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

  double best_render = std::numeric_limits<double>::infinity(), best_layers = best_render;
  double best_primary = best_render, best_packet = best_render, best_single = best_render;
  double best_primary_packet = best_render;
  // The prepared renderer against the one-shot form, and the progressive passes.
  const PreparedScene prepared(scene, *caster);
  RenderOptions hidden_line = options;
  hidden_line.surface = Surface::kHiddenLine;
  double best_prepared = best_render, best_with_bvh = best_render;
  double best_hidden_once = best_render, best_hidden_prepared = best_render;
  // Progressive: after Restart (a viewer's steady state: buffers reused) and freshly constructed.
  std::array<double, ProgressiveRender::kPasses> best_pass;
  best_pass.fill(best_render);
  double best_progressive = best_render, best_first_fresh = best_render;
  ProgressiveRender restarted(prepared, rig, view, options);
  restarted.RunAll();
  std::size_t hits = 0, occluded = 0;
  for (int r = 0; r < args.repeat; ++r) {
    RenderStats s;
    RenderWithStats(scene, rig, *caster, view, options, nullptr, &s);
    best_render = std::min(best_render, s.seconds);
    RenderWithStats(scene, rig, *caster, view, with_layers, nullptr, &s);
    best_layers = std::min(best_layers, s.seconds);
    RenderWithStats(prepared, rig, view, options, nullptr, &s);
    best_prepared = std::min(best_prepared, s.seconds);
    {
      const auto t0 = std::chrono::steady_clock::now();
      const std::unique_ptr<RayCaster> own = MakeEmbreeRayCaster(scene.AllTriangles());
      Render(scene, rig, *own, view, options);
      best_with_bvh = std::min(best_with_bvh, Seconds(t0));
    }
    RenderWithStats(scene, rig, *caster, view, hidden_line, nullptr, &s);
    best_hidden_once = std::min(best_hidden_once, s.seconds);
    RenderWithStats(prepared, rig, view, hidden_line, nullptr, &s);
    best_hidden_prepared = std::min(best_hidden_prepared, s.seconds);
    {
      // Each pass from the call to its image (the first includes starting the frame).
      auto t0 = std::chrono::steady_clock::now();
      const auto start = t0;
      restarted.Restart(rig, view, options);
      for (int pass = 0; pass < ProgressiveRender::kPasses; ++pass) {
        restarted.RunPass();
        best_pass[pass] = std::min(best_pass[pass], Seconds(t0));
        t0 = std::chrono::steady_clock::now();
      }
      best_progressive = std::min(best_progressive, Seconds(start));
      t0 = std::chrono::steady_clock::now();
      ProgressiveRender fresh(prepared, rig, view, options);
      fresh.RunPass();
      best_first_fresh = std::min(best_first_fresh, Seconds(t0));
    }
    const RawOcclusionResult p = RawEmbreeIntersection(*caster, primary);
    best_primary = std::min(best_primary, p.seconds);
    hits = p.occluded;
    best_primary_packet = std::min(
        best_primary_packet, RawEmbreeIntersection(*caster, primary, RawMode::kPacket).seconds);
    const RawOcclusionResult sp = RawEmbreeOcclusion(*caster, shadow, RawMode::kPacket);
    best_packet = std::min(best_packet, sp.seconds);
    occluded = sp.occluded;
    best_single = std::min(best_single, RawEmbreeOcclusion(*caster, shadow).seconds);
  }
  const double raw = best_primary_packet + best_packet;
  const double raw_single = best_primary + best_single;
  const double ratio = best_render / raw;
  const double ratio_single = best_render / raw_single;
  std::printf(
      "pandora bench --render: %s, rig %s (%d enabled cameras), %zu triangles, %dx%d, view %s, "
      "%d threads\n",
      scene.path.c_str(), rig.name.c_str(), rig.enabled_count(), caster->triangle_count(),
      view.width, view.height, view_name.empty() ? "(from the bounds)" : view_name.c_str(),
      threads);
  std::printf("  primary rays %zu (%zu hit), shadow segments %zu (%zu occluded)\n", primary.size(),
              hits, shadow.size(), occluded);
  std::printf("  %-58s %9.4f s\n", "render, PNG defaults (best of runs)", best_render);
  std::printf("  %-58s %9.4f s\n", "render with the EXR layers (best of runs)", best_layers);
  const int packet_width = EmbreePacketWidth(*caster);
  const std::string w = std::to_string(packet_width);
  std::printf("  %-58s %9.4f s\n", "raw Embree rtcIntersect1 loop, same primary rays",
              best_primary);
  std::printf("  %-58s %9.4f s\n",
              ("raw Embree rtcIntersect" + w + " packets, same primary rays").c_str(),
              best_primary_packet);
  std::printf("  %-58s %9.4f s\n", "raw Embree rtcOccluded1 loop, same shadow segments",
              best_single);
  std::printf("  %-58s %9.4f s\n",
              ("raw Embree rtcOccluded" + w + " packets, same shadow segments").c_str(),
              best_packet);
  std::printf(
      "  ratio render / raw single-ray loops (rtcIntersect1 + rtcOccluded1) = %.3f "
      "(target <= 1.5)\n",
      ratio_single);
  std::printf(
      "  ratio render / raw packet loops (rtcIntersect%d + rtcOccluded%d) = %.3f "
      "(our overhead over Embree itself)\n",
      packet_width, packet_width, ratio);
  std::printf(
      "  with the EXR layers: ratio to the single-ray loops = %.3f, to the packet loops = %.3f\n",
      best_layers / raw_single, best_layers / raw);
  std::printf("  %-58s %9.4f s\n", "one-shot Render, caster given (preparation per call)",
              best_render);
  std::printf("  %-58s %9.4f s\n", "one-shot with its BVH build (as `pandora render`)",
              best_with_bvh);
  std::printf("  %-58s %9.4f s\n", "prepared Render, per frame", best_prepared);
  std::printf("  %-58s %9.4f s\n", "hidden-line: one-shot (edges found per call)",
              best_hidden_once);
  std::printf("  %-58s %9.4f s\n", "hidden-line: prepared, per frame", best_hidden_prepared);
  std::printf(
      "  ratio prepared frame / one-shot = %.3f (with the BVH build: %.3f; hidden-line: %.3f)\n",
      best_prepared / best_render, best_prepared / best_with_bvh,
      best_hidden_prepared / best_hidden_once);
  std::printf("  progressive passes after Restart (1 pixel per 8x8, 4x4, 2x2 block, then all):");
  for (int pass = 0; pass < ProgressiveRender::kPasses; ++pass)
    std::printf(" %.4f", best_pass[pass]);
  std::printf(" s\n");
  std::printf("  %-58s %9.4f s\n", "first pass of a new ProgressiveRender (fresh buffers)",
              best_first_fresh);
  std::printf(
      "  ratio first pass / prepared full frame = %.3f (new ProgressiveRender: %.3f); "
      "all passes / prepared full frame = %.3f\n",
      best_pass[0] / best_prepared, best_first_fresh / best_prepared,
      best_progressive / best_prepared);
  if (!args.json_out.empty()) {
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
        {"render_seconds", best_render},
        {"raw_primary_seconds", best_primary},
        {"raw_primary_packet_seconds", best_primary_packet},
        {"raw_shadow_packet_seconds", best_packet},
        {"packet_width", EmbreePacketWidth(*caster)},
        {"raw_shadow_single_seconds", best_single},
        {"ratio", ratio},
        {"ratio_single", ratio_single},
        {"render_with_layers_seconds", best_layers},
        {"ratio_with_layers", best_layers / raw},
        {"ratio_single_with_layers", best_layers / raw_single},
        {"one_shot_seconds", best_render},
        {"one_shot_with_bvh_seconds", best_with_bvh},
        {"prepared_seconds", best_prepared},
        {"hidden_line_one_shot_seconds", best_hidden_once},
        {"hidden_line_prepared_seconds", best_hidden_prepared},
        {"ratio_prepared_to_one_shot", best_prepared / best_render},
        {"ratio_prepared_to_one_shot_with_bvh", best_prepared / best_with_bvh},
        {"ratio_hidden_line_prepared_to_one_shot", best_hidden_prepared / best_hidden_once},
        {"progressive_pass_seconds", best_pass},
        {"progressive_first_pass_fresh_seconds", best_first_fresh},
        {"ratio_first_pass_fresh_to_frame", best_first_fresh / best_prepared},
        {"ratio_first_pass_to_frame", best_pass[0] / best_prepared},
        {"ratio_all_passes_to_frame", best_progressive / best_prepared}};
    WriteFileAtomically(json_path, j.dump(2) + "\n");
    output.Commit();
  }
  return 0;
}

}  // namespace pandora::app
