// `pandora bench --render`: the renderer against raw Embree loops over the very same rays, measured
// in the same run (interleaved, best of each), so the ratio means something on a shared machine.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#include <nlohmann/json.hpp>

#include "analysis/error.h"
#include "analysis/ray_caster.h"
#include "analysis/scene.h"
#include "app/commands.h"
#include "app/output.h"
#include "render/render.h"

namespace pandora::app {

int RunRenderBench(const BenchArgs& args) {
  const auto [width, height] = ParseImageSize("--size", args.size);
  const Scene scene = LoadScene(args.scene);
  const Rig& rig = FindRigOption(scene, args.rig);
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string json_path = args.json_out.empty() ? "" : output.Stage(args.json_out, "--json");
  RenderView view;
  if (!args.view.empty()) {
    auto it = scene.views.find(args.view);
    if (it == scene.views.end())
      throw InputError("--view", "", "no view '" + args.view + "' in " + scene.path);
    view = ViewFromScene(it->second, width, height);
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
  const std::string view_name = args.view.empty() && !scene.views.empty() ? scene.views.begin()->first : args.view;
  const std::unique_ptr<RayCaster> caster = MakeEmbreeRayCaster(scene.AllTriangles());
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
  std::size_t hits = 0, occluded = 0;
  for (int r = 0; r < args.repeat; ++r) {
    RenderStats s;
    RenderWithStats(scene, rig, *caster, view, options, nullptr, &s);
    best_render = std::min(best_render, s.seconds);
    RenderWithStats(scene, rig, *caster, view, with_layers, nullptr, &s);
    best_layers = std::min(best_layers, s.seconds);
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
  std::printf("pandora bench --render: %s, rig %s (%d enabled cameras), %zu triangles, %dx%d, view %s, "
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
  std::printf("  %-58s %9.4f s\n", "raw Embree rtcIntersect1 loop, same primary rays", best_primary);
  std::printf("  %-58s %9.4f s\n", ("raw Embree rtcIntersect" + w + " packets, same primary rays").c_str(),
              best_primary_packet);
  std::printf("  %-58s %9.4f s\n", "raw Embree rtcOccluded1 loop, same shadow segments", best_single);
  std::printf("  %-58s %9.4f s\n", ("raw Embree rtcOccluded" + w + " packets, same shadow segments").c_str(),
              best_packet);
  std::printf("  ratio render / raw single-ray loops (rtcIntersect1 + rtcOccluded1) = %.3f "
              "(target <= 1.5)\n", ratio_single);
  std::printf("  ratio render / raw packet loops (rtcIntersect%d + rtcOccluded%d) = %.3f "
              "(our overhead over Embree itself)\n", packet_width, packet_width, ratio);
  std::printf("  with the EXR layers: ratio to the single-ray loops = %.3f, to the packet loops = %.3f\n",
              best_layers / raw_single, best_layers / raw);
  if (!args.json_out.empty()) {
    nlohmann::json j{{"scene", scene.path},
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
                     {"ratio_single_with_layers", best_layers / raw_single}};
    WriteFileAtomically(json_path, j.dump(2) + "\n");
    output.Commit();
  }
  return 0;
}

}  // namespace pandora::app
