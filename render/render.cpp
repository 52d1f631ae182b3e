// The projective-light renderer's entry points (render/render.h): the one-shot and prepared Render,
// RenderWithStats, and the small helpers of the public header. The per-frame work is in frame.cpp.
#include "render/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>

#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "render/frame.h"
#include "render/prepared_scene.h"

namespace pandora {

std::string FieldUnitLabel(const std::string& field) {
  std::string base = field;
  const std::string steady = "_steady";
  if (base.size() > steady.size() &&
      base.compare(base.size() - steady.size(), steady.size(), steady) == 0)
    base.resize(base.size() - steady.size());
  if (base == "coverage") return field + " [cameras]";
  if (base == "resolution") return field + " [px/m]";
  if (base == "sigma_max" || base == "sigma_mean") return field + " [mm]";
  if (base == "triangulation_angle") return field + " [deg]";
  if (base == "condition") return field + " [1]";
  return field;
}

std::optional<RenderView> PlanView(const Aabb& bounds, const std::string& side, int width,
                                   int height, double cut, double* metres_per_pixel) {
  // Towards the eye, and the image's up.
  Vec3 out, up;
  if (side == "plan") {
    out = Vec3::UnitZ();
    up = Vec3::UnitY();
  } else if (side == "north") {
    out = Vec3::UnitY();
    up = Vec3::UnitZ();
  } else if (side == "south") {
    out = -Vec3::UnitY();
    up = Vec3::UnitZ();
  } else if (side == "east") {
    out = Vec3::UnitX();
    up = Vec3::UnitZ();
  } else if (side == "west") {
    out = -Vec3::UnitX();
    up = Vec3::UnitZ();
  } else {
    return std::nullopt;
  }
  const Vec3 size = bounds.size().cwiseMax(Vec3::Constant(1e-3));
  const double diagonal = size.norm();
  const double distance = kPlanDistance * diagonal;
  const Vec3 right = up.cross(out);  // image x
  const double half_w = 0.5 * std::abs(right.dot(size)), half_h = 0.5 * std::abs(up.dot(size));
  const double half = 1.05 * std::max(half_w, half_h * double(width) / double(height));
  RenderView v;
  v.at = bounds.center();
  v.from = v.at + distance * out;
  v.up = up;
  v.fov_deg = 2.0 * std::atan(half / distance) * 180.0 / kPi;
  v.width = width;
  v.height = height;
  if (metres_per_pixel) *metres_per_pixel = 2.0 * half / width;
  // The cut: its distance from the eye along the axis (out is a unit axis).
  if (std::isfinite(cut)) v.clip_near = std::max(0.0, out.dot(v.from) - cut * out.sum());
  return v;
}

double PlanDefaultCut(const Aabb& region, const std::string& side) {
  if (side == "plan") return region.max.z();
  if (side == "north") return region.max.y();
  if (side == "south") return region.min.y();
  if (side == "east") return region.max.x();
  if (side == "west") return region.min.x();
  return std::numeric_limits<double>::quiet_NaN();
}

RenderView ViewFromScene(const View& view, int width, int height, double default_fov_deg) {
  RenderView v;
  v.from = view.from;
  v.at = view.at;
  v.up = view.up;
  v.fov_deg = view.fov_deg.value_or(default_fov_deg);
  v.width = width;
  v.height = height;
  return v;
}

Image RenderWithStats(const PreparedScene& scene, const Rig& rig, const RenderView& view,
                      const RenderOptions& options, const PreparedOverlays* overlays,
                      RenderStats* stats, std::vector<Ray>* primary_out,
                      std::vector<Ray>* shadow_out) {
  const auto start = std::chrono::steady_clock::now();
  const internal::FrameRenderer frame(scene, rig, view, options, overlays);
  internal::FrameBuffers buffers = frame.Allocate();
  const int tiles = frame.tiles();
  const bool record_rays = primary_out || shadow_out;
  std::vector<internal::TileRecord> records(stats || record_rays ? tiles : 0);
  // Every tile's groups in level order (see frame.h): the same calls ProgressiveRender makes.
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& r) {
    const auto scratch = internal::MakeScratch();
    for (int tile = r.begin(); tile != r.end(); ++tile)
      for (int level = 0; level < internal::kLevels; ++level)
        frame.RenderGroup(tile, level, &buffers, scratch.get(),
                          records.empty() ? nullptr : &records[tile], record_rays);
  });
  frame.Finish(&buffers);
  if (stats) {
    stats->primary_rays = 0;
    stats->shadow_rays = 0;
    for (const internal::TileRecord& t : records) {
      stats->primary_rays += t.primary;
      stats->shadow_rays += t.shadow;
    }
  }
  if (primary_out) {
    primary_out->clear();
    for (const auto& t : records)
      primary_out->insert(primary_out->end(), t.primary_rays.begin(), t.primary_rays.end());
  }
  if (shadow_out) {
    shadow_out->clear();
    for (const auto& t : records)
      shadow_out->insert(shadow_out->end(), t.shadow_rays.begin(), t.shadow_rays.end());
  }
  if (stats)
    stats->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return std::move(buffers.image);
}

Image Render(const PreparedScene& scene, const Rig& rig, const RenderView& view,
             const RenderOptions& options, const PreparedOverlays* overlays) {
  return RenderWithStats(scene, rig, view, options, overlays, nullptr);
}

Image RenderWithStats(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const RenderView& view, const RenderOptions& options, const Fields* fields,
                      RenderStats* stats, std::vector<Ray>* primary_out,
                      std::vector<Ray>* shadow_out) {
  const auto start = std::chrono::steady_clock::now();
  internal::CheckView(view, rig);  // the view's errors first, as the command line reads them
  const PreparedScene prepared(scene, caster);
  const OverlayOptions& ov = options.overlays;
  std::unique_ptr<PreparedOverlays> overlays;
  if (!ov.slice_field.empty() || !ov.iso_field.empty()) {
    if (!fields)
      throw InputError("{fields}", "", "the slice and isosurface overlays need a fields file",
                       "run `pandora analyze` and pass its fields.vdb");
    overlays = std::make_unique<PreparedOverlays>(*fields, ov);
  }
  Image image =
      RenderWithStats(prepared, rig, view, options, overlays.get(), stats, primary_out, shadow_out);
  if (stats)
    stats->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return image;
}

Image Render(const Scene& scene, const Rig& rig, const RayCaster& caster, const RenderView& view,
             const RenderOptions& options, const Fields* fields) {
  return RenderWithStats(scene, rig, caster, view, options, fields, nullptr);
}

}  // namespace pandora
