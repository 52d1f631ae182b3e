#include "volume/summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/util/text.h"
#include "volume/fields_vdb.h"
#include "volume/value_spill.h"

namespace pandora {
namespace {

double Fraction(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

// Nearest-rank percentiles of the values `for_each_chunk` passes (fn(values, count) per chunk, the
// same values each time it is called) without a copy of them: by counts of their order-preserving
// keys (volume/value_spill.h), two passes; equal to NearestRankPercentile.
template <typename ForEachChunk>
std::vector<std::optional<double>> CountedPercentiles(ForEachChunk&& for_each_chunk,
                                                      const std::vector<double>& p) {
  std::vector<std::int64_t> high(1 << 16, 0), low;
  for_each_chunk([&](const float* v, std::size_t n) { AddHighCounts(v, n, 1, high); });
  const PercentileBins selection = SelectPercentileBins(high, p);
  low.assign(selection.bins.size() << 16, 0);
  for_each_chunk(
      [&](const float* v, std::size_t n) { AddLowCounts(v, n, 1, selection.bins, low); });
  return ResolvePercentiles(selection, low, p.size());
}

// Passes a grid's active values to fn(values, count) in chunks of up to 4096 (a tile's value once
// per voxel it covers).
template <typename Fn>
void ForEachActiveChunk(const openvdb::FloatGrid& grid, Fn&& fn) {
  std::vector<float> chunk;
  chunk.reserve(4096);
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    const openvdb::Index64 n = it.isVoxelValue() ? 1 : it.getVoxelCount();
    for (openvdb::Index64 k = 0; k < n; ++k) {
      chunk.push_back(*it);
      if (chunk.size() == 4096) fn(chunk.data(), chunk.size()), chunk.clear();
    }
  }
  if (!chunk.empty()) fn(chunk.data(), chunk.size());
}

// The percentiles of a sigma list and, with `limit`, how many values are <= it: from the list, or
// from the field's grid where the evaluation left the list out (FieldOptions::value_lists: the
// grid is active exactly at the triangulable voxels, with the list's values). Counted, so neither
// is copied.
SigmaPercentiles SigmaValues(const Fields& fields, const std::vector<float>& list,
                             const std::string& grid_name, const std::optional<double>& limit,
                             std::int64_t* at_most) {
  // Read (back from its file when spilled) only when the list was left out.
  const openvdb::FloatGrid::Ptr grid = list.empty() && fields.stats.triangulable_voxels > 0
                                           ? fields.impl().Load(grid_name)
                                           : nullptr;
  const bool from_grid = grid != nullptr;
  const auto for_each_chunk = [&](auto&& fn) {
    if (from_grid)
      ForEachActiveChunk(*grid, fn);
    else
      fn(list.data(), list.size());
  };
  if (limit) {
    *at_most = 0;
    for_each_chunk([&](const float* v, std::size_t n) {
      *at_most += std::count_if(v, v + n, [&](float x) { return x <= *limit; });
    });
  }
  const std::vector<std::optional<double>> p = CountedPercentiles(for_each_chunk, {50, 90, 99});
  return {p[0], p[1], p[2]};
}

nlohmann::json Value(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

nlohmann::json Json(const SigmaPercentiles& p) {
  return {{"p50", Value(p.p50)}, {"p90", Value(p.p90)}, {"p99", Value(p.p99)}};
}

}  // namespace

std::optional<double> NearestRankPercentile(std::vector<float> values, double p) {
  if (values.empty()) return std::nullopt;
  const std::size_t rank = static_cast<std::size_t>(
      std::clamp(std::ceil(p / 100.0 * values.size()), 1.0, double(values.size())));
  std::nth_element(values.begin(), values.begin() + (rank - 1), values.end());
  return values[rank - 1];
}

std::vector<float> GridActiveValues(const Fields& fields, const std::string& name) {
  std::vector<float> values;
  if (const openvdb::FloatGrid::Ptr grid = fields.impl().Load(name)) {
    values.reserve(grid->activeVoxelCount());
    for (auto it = grid->cbeginValueOn(); it; ++it) {
      if (it.isVoxelValue())
        values.push_back(*it);
      else
        values.insert(values.end(), it.getVoxelCount(), *it);
    }
  }
  return values;
}

std::vector<std::optional<double>> GridPercentileValues(const Fields& fields,
                                                        const std::string& name,
                                                        const std::vector<int>& percentiles) {
  // Counted from the grid in chunks: no list of its values.
  const openvdb::FloatGrid::Ptr grid = fields.impl().Load(name);
  if (!grid) return std::vector<std::optional<double>>(percentiles.size());
  return CountedPercentiles([&](auto&& fn) { ForEachActiveChunk(*grid, fn); },
                            std::vector<double>(percentiles.begin(), percentiles.end()));
}

nlohmann::json GridPercentiles(const Fields& fields, const std::string& name,
                               const std::vector<int>& percentiles) {
  const std::vector<std::optional<double>> values = GridPercentileValues(fields, name, percentiles);
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t i = 0; i < percentiles.size(); ++i)
    j["p" + std::to_string(percentiles[i])] = Value(values[i]);
  return j;
}

std::vector<RegionCounts> CountRegions(const Scene& scene, const Fields& fields) {
  std::vector<RegionCounts> out;
  const Fields::Impl& g = fields.impl();
  if (scene.study.regions.empty() || !g.coverage) return out;
  const openvdb::FloatGrid::Ptr sigma = g.Load("sigma_max"), resolution = g.Load("resolution");
  for (const auto& [name, region] : scene.study.regions) {
    std::unique_ptr<InsideMesh> inside;
    if (region.kind == Region::Kind::kMesh && !region.mesh.triangles.empty())
      inside = std::make_unique<InsideMesh>(region.mesh);
    RegionCounts r;
    auto sa = sigma ? std::optional(sigma->getConstAccessor()) : std::nullopt;
    auto ra = resolution ? std::optional(resolution->getConstAccessor()) : std::nullopt;
    ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int n) {
      const openvdb::Vec3d w = g.coverage->indexToWorld(c);
      const Vec3 p(w.x(), w.y(), w.z());
      if (!region.box.Contains(p) || (inside && !inside->Inside(p))) return;
      ++r.voxels;
      for (int k = 0; k < 3; ++k) r.ge[k] += n >= k + 1;
      if (sa && sa->isValueOn(c)) r.sigmas.push_back(sa->getValue(c));
      if (ra && ra->isValueOn(c)) r.densities.push_back(ra->getValue(c));
    });
    out.push_back(std::move(r));
  }
  return out;
}

RegionSummary FinishRegion(const std::string& name, const RegionCounts& counts, bool has_resolution,
                           bool has_sigma, std::int64_t sigma_count,
                           std::optional<double> resolution_p10, std::optional<double> sigma_p50,
                           std::optional<double> sigma_p90) {
  RegionSummary r;
  r.name = name;
  r.voxels = counts.voxels;
  const double n = r.voxels > 0 ? double(r.voxels) : 1.0;
  r.ge1 = counts.ge[0] / n;
  r.ge2 = counts.ge[1] / n;
  r.ge3 = counts.ge[2] / n;
  if (has_resolution) r.resolution_p10 = resolution_p10;
  if (has_sigma) {
    r.triangulable = double(sigma_count) / n;
    r.sigma_max_p50 = sigma_p50;
    r.sigma_max_p90 = sigma_p90;
  }
  return r;
}

std::vector<RegionSummary> SummarizeRegions(const Scene& scene, const Fields& fields) {
  std::vector<RegionSummary> out;
  const std::vector<RegionCounts> counts = CountRegions(scene, fields);
  const Fields::Impl& g = fields.impl();
  const bool has_resolution = g.Has("resolution"), has_sigma = g.Has("sigma_max");
  for (std::size_t i = 0; i < counts.size(); ++i) {
    const RegionCounts& r = counts[i];
    out.push_back(FinishRegion(
        scene.study.regions[i].first, r, has_resolution, has_sigma,
        static_cast<std::int64_t>(r.sigmas.size()), NearestRankPercentile(r.densities, 10),
        NearestRankPercentile(r.sigmas, 50), NearestRankPercentile(r.sigmas, 90)));
  }
  return out;
}

Summary Summarize(const Scene& scene, const Rig& rig, const Fields& fields,
                  const std::vector<std::string>& field_names, int threads,
                  const std::vector<Warning>& warnings) {
  const FieldStats& st = fields.stats;
  const std::int64_t region = st.active_set.region_voxels;
  Summary s;
  s.scene = scene.path;
  s.scene_sha256 = scene.sha256;
  s.rig = rig.name;
  s.cameras = rig.enabled_count();
  s.fields = field_names;
  s.voxel_size_m = fields.lattice.voxel_size;
  s.region = scene.study.region.box;
  s.region_dims = fields.lattice.dims;
  s.region_kind = scene.study.region.kind;
  s.region_voxels = region;
  s.solid_voxels = st.active_set.solid_voxels;
  s.active_voxels = st.seen_voxels;

  std::int64_t at_least[4] = {0, 0, 0, 0};
  for (std::size_t k = 0; k < st.coverage_histogram.size(); ++k)
    for (std::size_t m = 1; m <= 3; ++m)
      if (k >= m) at_least[m] += st.coverage_histogram[k];
  s.coverage.ge1 = Fraction(at_least[1], region);
  s.coverage.ge2 = Fraction(at_least[2], region);
  s.coverage.ge3 = Fraction(at_least[3], region);
  s.coverage.histogram = st.coverage_histogram;
  if (std::find(field_names.begin(), field_names.end(), "resolution") != field_names.end()) {
    const std::vector<std::optional<double>> p =
        GridPercentileValues(fields, "resolution", {10, 50, 90});
    s.resolution_px_per_m = ResolutionPercentiles{p[0], p[1], p[2]};
  }

  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& cam = rig.cameras[c];
    CameraSummary pc;
    pc.id = cam.id;
    pc.name = cam.name;
    pc.enabled = cam.enabled;
    pc.visible_voxels = c < st.per_camera_seen.size() ? st.per_camera_seen[c] : 0;
    pc.visible_fraction = Fraction(pc.visible_voxels, region);
    pc.lens = ComputeLensCoverage(cam.model);
    s.per_camera.push_back(std::move(pc));
  }

  if (std::any_of(field_names.begin(), field_names.end(), IsUncertaintyField)) {
    UncertaintySummary u;
    u.triangulable = Fraction(st.triangulable_voxels, region);
    u.triangulable_voxels = st.triangulable_voxels;
    u.unobservable_voxels = st.unobservable_voxels;
    u.pixel_sigma = scene.study.pixel_sigma;
    const std::optional<double> limit = scene.study.max_sigma_mm;
    std::int64_t meets = 0;
    u.sigma_max_mm = SigmaValues(fields, st.sigma_max_mm, "sigma_max", limit, &meets);
    if (limit) {
      u.max_sigma_mm = *limit;
      u.meets_max_sigma = Fraction(meets, region);
    }
    if (scene.study.motion) {
      u.motion = *scene.study.motion;
      u.steady_prior = scene.study.steady_prior;
      u.sigma_max_steady_mm =
          SigmaValues(fields, st.sigma_max_steady_mm, "sigma_max_steady", limit, &meets);
      if (limit) u.meets_max_sigma_steady = Fraction(meets, region);
    }
    s.uncertainty = u;
  }
  s.warnings = warnings;
  s.timing.seconds = st.seconds;
  s.timing.active_set_seconds = st.active_set_seconds;
  s.timing.rays = st.rays;
  s.timing.point_camera_tests = st.point_camera_tests;
  s.timing.threads = threads;
  s.regions = SummarizeRegions(scene, fields);
  return s;
}

namespace {

// An optional value as JSON, null when absent.
nlohmann::json OptionalJson(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json();
}

// summary.json's "per_camera": each camera's visibility and lens coverage.
nlohmann::json PerCameraJson(const std::vector<CameraSummary>& cameras) {
  nlohmann::json per_camera = nlohmann::json::array();
  for (const CameraSummary& c : cameras)
    per_camera.push_back({{"id", c.id},
                          {"name", c.name},
                          {"enabled", c.enabled},
                          {"visible_voxels", c.visible_voxels},
                          {"visible_fraction", c.visible_fraction},
                          {"fov_deg",
                           {{"nominal", {c.lens.nominal_hfov_deg, c.lens.nominal_vfov_deg}},
                            {"effective", {c.lens.hfov_deg, c.lens.vfov_deg}}}},
                          {"unreachable_pixels", c.lens.unreachable_fraction}});
  return per_camera;
}

// summary.json's "uncertainty".
nlohmann::json UncertaintyJson(const UncertaintySummary& u) {
  nlohmann::json uj{{"triangulable", u.triangulable},
                    {"triangulable_voxels", u.triangulable_voxels},
                    {"unobservable_voxels", u.unobservable_voxels},
                    {"pixel_sigma", u.pixel_sigma},
                    {"sigma_max_mm", Json(u.sigma_max_mm)}};
  if (u.max_sigma_mm) uj["max_sigma_mm"] = *u.max_sigma_mm;
  if (u.meets_max_sigma) uj["meets_max_sigma"] = *u.meets_max_sigma;
  if (u.motion) {
    uj["motion"] = {{"q", u.motion->q},
                    {"rate_hz", u.motion->rate_hz},
                    {"covariance", u.steady_prior ? "prior" : "posterior"}};
    uj["sigma_max_steady_mm"] = Json(u.sigma_max_steady_mm);
    if (u.meets_max_sigma_steady) uj["meets_max_sigma_steady"] = *u.meets_max_sigma_steady;
  }
  return uj;
}

// summary.json's "warnings".
nlohmann::json WarningsJson(const std::vector<Warning>& warnings) {
  nlohmann::json list = nlohmann::json::array();
  for (const Warning& w : warnings)
    list.push_back({{"kind", WarningKindName(w.kind)},
                    {"camera", w.camera},
                    {"path", w.json_path},
                    {"message", w.reason}});
  return list;
}

// summary.json's "time": the time samples and their totals.
nlohmann::json TimeJson(const TimeSummary& t) {
  nlohmann::json rows = nlohmann::json::array();
  for (const TimeSampleSummary& r : t.samples)
    rows.push_back({{"label", r.label},
                    {"time", r.time},
                    {"region_voxels", r.region_voxels},
                    {"ge1", r.ge1},
                    {"ge2", r.ge2},
                    {"ge3", r.ge3},
                    {"ge_k", r.ge_k},
                    {"sigma_max_p50_mm", OptionalJson(r.sigma_max_p50)},
                    {"sigma_max_p90_mm", OptionalJson(r.sigma_max_p90)},
                    {"seconds", r.seconds}});
  return {{"min_cameras", t.min_cameras},
          {"samples", rows},
          {"voxels", t.voxels},
          {"always", t.always},
          {"mean", t.mean},
          {"worst_sample",
           t.samples.empty() ? nlohmann::json() : nlohmann::json(t.samples[t.worst_sample].label)},
          {"sigma_max_mm",
           {{"p50", OptionalJson(t.sigma_max_p50)},
            {"p90", OptionalJson(t.sigma_max_p90)},
            {"p99", OptionalJson(t.sigma_max_p99)}}},
          {"seconds", t.seconds},
          {"parts_seconds", t.parts_seconds}};
}

// summary.json's "targets": each surface target's shares per sample and per camera.
nlohmann::json TargetsJson(const Summary& s) {
  nlohmann::json targets = nlohmann::json::array();
  for (const SurfaceTargetResult& r : s.targets) {
    nlohmann::json per_sample = nlohmann::json::array();
    for (std::size_t k = 0; k < r.sample_share.size(); ++k)
      per_sample.push_back(
          {{"label", k < s.sample_labels.size() ? s.sample_labels[k] : "as placed"},
           {"share", r.sample_share[k]}});
    nlohmann::json per_camera = nlohmann::json::array();
    for (std::size_t c = 0; c < r.per_camera.size() && c < s.per_camera.size(); ++c)
      per_camera.push_back({{"id", s.per_camera[c].id}, {"share", r.per_camera[c]}});
    targets.push_back(
        {{"name", r.name},
         {"points", r.points},
         {"samples", r.samples},
         {"share_ge", r.share_ge},
         {"always", r.always},
         {"worst_sample", per_sample.empty() ? nlohmann::json() : per_sample[r.worst_sample]},
         {"per_sample", per_sample},
         {"per_camera", per_camera},
         {"seconds", r.seconds}});
    if (!r.pixel_share.empty()) {
      nlohmann::json pixel = nlohmann::json::object();
      for (std::size_t p = 0; p < r.pixel_share.size() && p < s.pixel_targets.size(); ++p)
        pixel[s.pixel_targets[p].target.name] = r.pixel_share[p];
      targets.back()["pixel_share"] = pixel;
    }
  }
  return targets;
}

// summary.json's "pixel_targets".
nlohmann::json PixelTargetsJson(const std::vector<PixelTargetSummary>& pixel_targets) {
  nlohmann::json list = nlohmann::json::array();
  for (const PixelTargetSummary& p : pixel_targets)
    list.push_back({{"name", p.target.name},
                    {"size_m", p.target.size_m},
                    {"min_px", p.target.min_px},
                    {"px_per_m", p.target.px_per_m()},
                    {"share_ge", p.share_ge},
                    {"seconds", p.seconds}});
  return list;
}

// summary.json's "regions": the named regions' coverage and uncertainty.
nlohmann::json RegionsJson(const std::vector<RegionSummary>& regions) {
  nlohmann::json list = nlohmann::json::array();
  for (const RegionSummary& r : regions)
    list.push_back({{"name", r.name},
                    {"voxels", r.voxels},
                    {"ge1", r.ge1},
                    {"ge2", r.ge2},
                    {"ge3", r.ge3},
                    {"resolution_p10_px_per_m", OptionalJson(r.resolution_p10)},
                    {"triangulable", r.triangulable},
                    {"sigma_max_p50_mm", OptionalJson(r.sigma_max_p50)},
                    {"sigma_max_p90_mm", OptionalJson(r.sigma_max_p90)}});
  return list;
}

}  // namespace

void to_json(nlohmann::json& j, const Summary& s) {
  j = nlohmann::json::object();
  j["scene"] = s.scene;
  j["scene_sha256"] = s.scene_sha256;
  j["rig"] = s.rig;
  j["cameras"] = s.cameras;
  j["fields"] = s.fields;
  j["voxel_size_m"] = s.voxel_size_m;
  const Aabb& box = s.region;
  j["region"] = {{"min", {box.min.x(), box.min.y(), box.min.z()}},
                 {"max", {box.max.x(), box.max.y(), box.max.z()}},
                 {"dims", {s.region_dims.x(), s.region_dims.y(), s.region_dims.z()}},
                 {"kind", s.region_kind == Region::Kind::kBox ? "box" : "mesh"}};
  j["region_voxels"] = s.region_voxels;
  j["solid_voxels"] = s.solid_voxels;
  j["active_voxels"] = s.active_voxels;
  j["coverage"] = {{"ge1", s.coverage.ge1},
                   {"ge2", s.coverage.ge2},
                   {"ge3", s.coverage.ge3},
                   {"histogram", s.coverage.histogram}};
  if (s.resolution_px_per_m)
    j["resolution_px_per_m"] = {{"p10", Value(s.resolution_px_per_m->p10)},
                                {"p50", Value(s.resolution_px_per_m->p50)},
                                {"p90", Value(s.resolution_px_per_m->p90)}};
  j["per_camera"] = PerCameraJson(s.per_camera);
  if (s.uncertainty) j["uncertainty"] = UncertaintyJson(*s.uncertainty);
  j["warnings"] = WarningsJson(s.warnings);
  if (s.time) j["time"] = TimeJson(*s.time);
  if (!s.targets.empty()) j["targets"] = TargetsJson(s);
  if (!s.pixel_targets.empty()) j["pixel_targets"] = PixelTargetsJson(s.pixel_targets);
  if (s.dori)
    j["dori"] = {{"detection", s.dori->detection},
                 {"observation", s.dori->observation},
                 {"recognition", s.dori->recognition},
                 {"identification", s.dori->identification},
                 {"px_per_m", {kDoriPxPerM[0], kDoriPxPerM[1], kDoriPxPerM[2], kDoriPxPerM[3]}}};
  if (!s.regions.empty()) j["regions"] = RegionsJson(s.regions);
  j["timing"] = {{"seconds", s.timing.seconds},
                 {"active_set_seconds", s.timing.active_set_seconds},
                 {"rays", s.timing.rays},
                 {"rays_per_second", s.timing.rays_per_second()},
                 {"point_camera_tests", s.timing.point_camera_tests},
                 {"tests_per_second", s.timing.tests_per_second()},
                 {"threads", s.timing.threads}};
  if (s.calibration) j["calibration"] = *s.calibration;
  if (s.robustness) j["robustness"] = *s.robustness;
  if (s.ptz) j["ptz"] = *s.ptz;
}

nlohmann::json MakeSummary(const Scene& scene, const Rig& rig, const Fields& fields,
                           const std::vector<std::string>& field_names, int threads,
                           const std::vector<Warning>& warnings) {
  nlohmann::json j;
  to_json(j, Summarize(scene, rig, fields, field_names, threads, warnings));
  return j;
}

namespace {

// "  p10    1134  p50    1229 ..." with "-" where a percentile has no value.
std::string PercentileCells(const std::vector<std::pair<const char*, std::optional<double>>>& cells,
                            const char* format) {
  std::string line;
  for (const auto& [key, value] : cells) {
    char text[24] = "-";
    if (value) std::snprintf(text, sizeof text, format, *value);
    line += Format("  %s %7s", key, text);
  }
  return line;
}

}  // namespace

std::string FormatSummary(const Summary& s) {
  std::string out =
      Format("rig %s: %d cameras, voxel %.4g m, %lld free region voxels (and %lld inside solids)\n",
             s.rig.c_str(), s.cameras, s.voxel_size_m, static_cast<long long>(s.region_voxels),
             static_cast<long long>(s.solid_voxels));
  out += Format("coverage  >=1 %5.1f%%   >=2 %5.1f%%   >=3 %5.1f%%\n", 100 * s.coverage.ge1,
                100 * s.coverage.ge2, 100 * s.coverage.ge3);
  if (s.resolution_px_per_m) {
    const ResolutionPercentiles& r = *s.resolution_px_per_m;
    out += "resolution px/m  " +
           PercentileCells({{"p10", r.p10}, {"p50", r.p50}, {"p90", r.p90}}, "%.0f") +
           "   (voxels seen by >= 1 camera, best camera)\n";
  }
  if (s.uncertainty) {
    const SigmaPercentiles& p = s.uncertainty->sigma_max_mm;
    out += "sigma_max mm     " +
           PercentileCells({{"p50", p.p50}, {"p90", p.p90}, {"p99", p.p99}}, "%.3g") +
           Format("   (triangulable voxels: %.1f%% of the region)\n",
                  100 * s.uncertainty->triangulable);
  }
  out += Format("%-12s %-20s %8s   %-15s %s\n", "camera", "name", "sees", "FOV h x v deg",
                "(nominal, no distortion)");
  for (const CameraSummary& c : s.per_camera) {
    const std::string fov = Format("%.1f x %.1f", c.lens.hfov_deg, c.lens.vfov_deg);
    const std::string nominal =
        Format("(%.1f x %.1f)", c.lens.nominal_hfov_deg, c.lens.nominal_vfov_deg);
    out += Format("%-12s %-20s %7.1f%%   %-15s %s%s\n", c.id.c_str(), c.name.c_str(),
                  100 * c.visible_fraction, fov.c_str(), nominal.c_str(),
                  c.enabled ? "" : "  (disabled)");
  }
  if (s.time) {
    const TimeSummary& t = *s.time;
    out += Format(
        "over %zu time samples (seen by >= %d cameras): always %.1f%%, on average %.1f%%, worst %s "
        "%.1f%%; %.2f s\n",
        t.samples.size(), t.min_cameras, 100 * t.always, 100 * t.mean,
        t.samples.empty() ? "-" : t.samples[t.worst_sample].label.c_str(),
        t.samples.empty() ? 0.0 : 100 * t.samples[t.worst_sample].ge_k, t.seconds);
    for (const TimeSampleSummary& r : t.samples)
      out += Format(
          "  %-24s >=1 %5.1f%%  >=2 %5.1f%%  >=3 %5.1f%%%s\n", r.label.c_str(), 100 * r.ge1,
          100 * r.ge2, 100 * r.ge3,
          r.sigma_max_p90 ? Format("  sigma_max p90 %.3g mm", *r.sigma_max_p90).c_str() : "");
  }
  for (const RegionSummary& r : s.regions)
    out += Format(
        "region    %-12s %lld voxels: >=1 %.1f%%, >=2 %.1f%%, >=3 %.1f%%%s\n", r.name.c_str(),
        static_cast<long long>(r.voxels), 100 * r.ge1, 100 * r.ge2, 100 * r.ge3,
        r.sigma_max_p90
            ? Format("; sigma_max p50 %.3g, p90 %.3g mm", *r.sigma_max_p50, *r.sigma_max_p90)
                  .c_str()
            : "");
  for (const PixelTargetSummary& p : s.pixel_targets)
    out += Format(
        "pixels    %-12s (%.4g m over >= %.4g px: >= %.0f px/m) by >=1 %.1f%%, >=2 %.1f%%, >=3 "
        "%.1f%% of the region\n",
        p.target.name.c_str(), p.target.size_m, p.target.min_px, p.target.px_per_m(),
        100 * p.share_ge[0], 100 * p.share_ge[1], 100 * p.share_ge[2]);
  if (s.dori)
    out += Format(
        "DORI      detection %.1f%%, observation %.1f%%, recognition %.1f%%, identification %.1f%% "
        "of the region\n",
        100 * s.dori->detection, 100 * s.dori->observation, 100 * s.dori->recognition,
        100 * s.dori->identification);
  for (const SurfaceTargetResult& r : s.targets) {
    const int k = s.time ? s.time->min_cameras : 3;
    out += Format(
        "target %-16s %d points x %d samples: >=1 %.1f%%, >=2 %.1f%%, >=3 %.1f%%; >= %d in every "
        "sample %.1f%%",
        r.name.c_str(), r.points, r.samples, 100 * r.share_ge[0], 100 * r.share_ge[1],
        100 * r.share_ge[2], k, 100 * r.always);
    for (std::size_t p = 0; p < r.pixel_share.size() && p < s.pixel_targets.size(); ++p)
      out += Format("; %s size by >= %d: %.1f%%", s.pixel_targets[p].target.name.c_str(), k,
                    100 * r.pixel_share[p]);
    if (r.samples > 1)
      out += Format(", worst %s %.1f%%",
                    r.worst_sample < int(s.sample_labels.size())
                        ? s.sample_labels[r.worst_sample].c_str()
                        : "-",
                    100 * r.sample_share[r.worst_sample]);
    out += "\n";
  }
  out += Format("%.3f s, %.3g rays (%.3g rays/s), %.3g point-camera tests\n", s.timing.seconds,
                static_cast<double>(s.timing.rays), s.timing.rays_per_second(),
                static_cast<double>(s.timing.point_camera_tests));
  if (s.calibration) out += FormatCalibration(*s.calibration);
  if (s.robustness) out += FormatCriticality(*s.robustness);
  if (s.ptz) out += FormatPtzFields(*s.ptz);
  return out;
}

}  // namespace pandora
