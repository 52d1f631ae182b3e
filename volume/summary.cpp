#include "volume/summary.h"

namespace pandora {
namespace {

double Fraction(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

}  // namespace

nlohmann::json MakeSummary(const Scene& scene, const Rig& rig, const Fields& fields,
                           const std::vector<std::string>& field_names, int threads) {
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

  nlohmann::json per_camera = nlohmann::json::array();
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& cam = rig.cameras[c];
    const std::int64_t seen = c < st.per_camera_seen.size() ? st.per_camera_seen[c] : 0;
    per_camera.push_back({{"id", cam.id},
                          {"name", cam.name},
                          {"enabled", cam.enabled},
                          {"visible_voxels", seen},
                          {"visible_fraction", Fraction(seen, region)}});
  }
  j["per_camera"] = per_camera;

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
