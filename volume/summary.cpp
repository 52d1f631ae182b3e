#include "volume/summary.h"

#include <algorithm>
#include <cmath>

#include "volume/fields_vdb.h"

namespace pandora {
namespace {

double Fraction(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

// Percentile p in [0, 100] by the nearest-rank method (a value that occurs in the data), or null
// when there is none.
nlohmann::json Percentile(std::vector<float> values, double p) {
  if (values.empty()) return nullptr;
  const std::size_t rank = static_cast<std::size_t>(
      std::clamp(std::ceil(p / 100.0 * values.size()), 1.0, double(values.size())));
  std::nth_element(values.begin(), values.begin() + (rank - 1), values.end());
  return values[rank - 1];
}

nlohmann::json Percentiles(const std::vector<float>& values) {
  return {{"p50", Percentile(values, 50)}, {"p90", Percentile(values, 90)},
          {"p99", Percentile(values, 99)}};
}

std::int64_t CountAtMost(const std::vector<float>& values, double limit) {
  return std::count_if(values.begin(), values.end(), [&](float v) { return v <= limit; });
}

}  // namespace

nlohmann::json GridPercentiles(const Fields& fields, const std::string& name,
                               const std::vector<int>& percentiles) {
  std::vector<float> values;
  if (const openvdb::FloatGrid::Ptr grid = fields.impl().Float(name)) {
    values.reserve(grid->activeVoxelCount());
    for (auto it = grid->cbeginValueOn(); it; ++it) {
      if (it.isVoxelValue())
        values.push_back(*it);
      else
        values.insert(values.end(), it.getVoxelCount(), *it);
    }
  }
  nlohmann::json j = nlohmann::json::object();
  for (int p : percentiles) j["p" + std::to_string(p)] = Percentile(values, p);
  return j;
}

nlohmann::json MakeSummary(const Scene& scene, const Rig& rig, const Fields& fields,
                           const std::vector<std::string>& field_names, int threads,
                           const std::vector<Warning>& warnings) {
  const FieldStats& st = fields.stats;
  const std::int64_t region = st.active_set.region_voxels;
  nlohmann::json j;
  j["scene"] = scene.path;
  j["scene_sha256"] = scene.sha256;
  j["rig"] = rig.name;
  j["cameras"] = rig.enabled_count();
  j["fields"] = field_names;
  j["voxel_size_m"] = fields.lattice.voxel_size;
  const Aabb& box = scene.study.region.box;
  j["region"] = {{"min", {box.min.x(), box.min.y(), box.min.z()}},
                 {"max", {box.max.x(), box.max.y(), box.max.z()}},
                 {"dims", {fields.lattice.dims.x(), fields.lattice.dims.y(), fields.lattice.dims.z()}},
                 {"kind", scene.study.region.kind == Region::Kind::kBox ? "box" : "mesh"}};
  j["region_voxels"] = region;
  j["solid_voxels"] = st.active_set.solid_voxels;
  j["active_voxels"] = st.seen_voxels;

  std::int64_t at_least[4] = {0, 0, 0, 0};
  for (std::size_t k = 0; k < st.coverage_histogram.size(); ++k)
    for (std::size_t m = 1; m <= 3; ++m)
      if (k >= m) at_least[m] += st.coverage_histogram[k];
  j["coverage"] = {{"ge1", Fraction(at_least[1], region)},
                   {"ge2", Fraction(at_least[2], region)},
                   {"ge3", Fraction(at_least[3], region)},
                   {"histogram", st.coverage_histogram}};
  if (std::find(field_names.begin(), field_names.end(), "resolution") != field_names.end())
    j["resolution_px_per_m"] = GridPercentiles(fields, "resolution", {10, 50, 90});

  nlohmann::json per_camera = nlohmann::json::array();
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& cam = rig.cameras[c];
    const std::int64_t seen = c < st.per_camera_seen.size() ? st.per_camera_seen[c] : 0;
    const LensCoverage lens = ComputeLensCoverage(cam.model);
    per_camera.push_back(
        {{"id", cam.id},
         {"name", cam.name},
         {"enabled", cam.enabled},
         {"visible_voxels", seen},
         {"visible_fraction", Fraction(seen, region)},
         {"fov_deg",
          {{"nominal", {lens.nominal_hfov_deg, lens.nominal_vfov_deg}},
           {"effective", {lens.hfov_deg, lens.vfov_deg}}}},
         {"unreachable_pixels", lens.unreachable_fraction}});
  }
  j["per_camera"] = per_camera;

  const bool uncertainty = std::any_of(field_names.begin(), field_names.end(), IsUncertaintyField);
  if (uncertainty) {
    // Fractions of the free region voxels; sigma in mm over the triangulable voxels.
    nlohmann::json u{{"triangulable", Fraction(st.triangulable_voxels, region)},
                     {"triangulable_voxels", st.triangulable_voxels},
                     {"unobservable_voxels", st.unobservable_voxels},
                     {"pixel_sigma", scene.study.pixel_sigma},
                     {"sigma_max_mm", Percentiles(st.sigma_max_mm)}};
    if (scene.study.max_sigma_mm) {
      u["max_sigma_mm"] = *scene.study.max_sigma_mm;
      u["meets_max_sigma"] = Fraction(CountAtMost(st.sigma_max_mm, *scene.study.max_sigma_mm), region);
    }
    // With a motion model the steady-state keys are always there: percentiles are null when no
    // voxel is triangulable (or the steady fields were not asked for), the share meeting the
    // target is then 0.
    if (scene.study.motion) {
      u["motion"] = {{"q", scene.study.motion->q},
                     {"rate_hz", scene.study.motion->rate_hz},
                     {"covariance", scene.study.steady_prior ? "prior" : "posterior"}};
      u["sigma_max_steady_mm"] = Percentiles(st.sigma_max_steady_mm);
      if (scene.study.max_sigma_mm)
        u["meets_max_sigma_steady"] =
            Fraction(CountAtMost(st.sigma_max_steady_mm, *scene.study.max_sigma_mm), region);
    }
    j["uncertainty"] = u;
  }

  nlohmann::json list = nlohmann::json::array();
  for (const Warning& w : warnings)
    list.push_back({{"kind", WarningKindName(w.kind)},
                    {"camera", w.camera},
                    {"path", w.json_path},
                    {"message", w.reason}});
  j["warnings"] = list;

  const double secs = st.seconds;
  j["timing"] = {{"seconds", secs},
                 {"active_set_seconds", st.active_set_seconds},
                 {"rays", st.rays},
                 {"rays_per_second", secs > 0 ? st.rays / secs : 0.0},
                 {"point_camera_tests", st.point_camera_tests},
                 {"tests_per_second", secs > 0 ? st.point_camera_tests / secs : 0.0},
                 {"threads", threads}};
  return j;
}

}  // namespace pandora
