#include "volume/pixel_targets.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <map>

#include "analysis/error.h"
#include "analysis/visibility.h"
#include "volume/fields_vdb.h"

namespace pandora {

std::vector<PixelTargetSummary> EvaluatePixelTargets(const Scene& scene, const Rig& rig, const Fields& fields,
                                                    int min_cameras, Fields* grids) {
  std::vector<PixelTargetSummary> out;
  if (scene.study.pixel_targets.empty()) return out;
  const Fields::Impl& g = fields.impl();
  if (g.visible.empty() || !g.coverage)
    throw InputError(scene.path, "$.study.pixel_targets", "pixel targets need the coverage and cameras fields",
                     "add \"coverage\" and \"cameras\" to the study's fields");
  const int kmax = std::max(3, min_cameras);
  // The caster is not used: the visibility is known; only TestGeometry's Jacobian is needed.
  const auto none = MakeBruteForceRayCaster(TriangleMesh());
  const VisibilityTester tester(rig.cameras, *none, scene.ContentBounds().diagonal());
  // The free voxels (the coverage grid's active set, tiles included) get an index each.
  std::map<openvdb::Coord, std::int64_t> index;
  for (auto it = g.coverage->cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto c = box.begin(); c; ++c) index.emplace(*c, 0);
  }
  std::int64_t next = 0;
  for (auto& [c, i] : index) i = next++;
  for (const PixelTarget& target : scene.study.pixel_targets) {
    const auto t0 = std::chrono::steady_clock::now();
    const double need = target.px_per_m();
    std::vector<std::uint16_t> count(std::size_t(next), 0);
    for (std::size_t c = 0; c < g.visible.size() && c < rig.cameras.size(); ++c) {
      if (!g.visible[c] || !rig.cameras[c].enabled) continue;
      std::vector<openvdb::Coord> voxels;
      for (auto it = g.visible[c]->cbeginValueOn(); it; ++it) voxels.push_back(it.getCoord());
      std::vector<std::uint8_t> meets(voxels.size(), 0);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const openvdb::Vec3d w = g.visible[c]->indexToWorld(voxels[i]);
          Mat23 J;
          if (tester.TestGeometry(int(c), Vec3(w.x(), w.y(), w.z()), nullptr, nullptr, &J) == ViewResult::kSeen &&
              PixelDensity(J) >= need)
            meets[i] = 1;
        }
      });
      for (std::size_t i = 0; i < voxels.size(); ++i)
        if (meets[i]) {
          const auto it = index.find(voxels[i]);
          if (it != index.end()) ++count[std::size_t(it->second)];
        }
    }
    PixelTargetSummary s;
    s.target = target;
    s.share_ge.assign(kmax, 0.0);
    for (std::uint16_t n : count)
      for (int j = 1; j <= std::min<int>(n, kmax); ++j) s.share_ge[j - 1] += 1;
    for (double& v : s.share_ge) v = next > 0 ? v / double(next) : 0.0;
    if (grids) {
      auto grid = openvdb::FloatGrid::create(0.0f);
      grid->setTransform(g.coverage->transformPtr()->copy());
      auto acc = grid->getAccessor();
      for (const auto& [c, i] : index) acc.setValue(c, float(count[std::size_t(i)]));
      grid->pruneGrid();
      grids->impl().extra["pixels_" + target.name] = grid;
    }
    s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.push_back(s);
  }
  return out;
}

DoriSummary EvaluateDori(const Scene& scene, const Fields& fields, Fields* grids) {
  const Fields::Impl& g = fields.impl();
  const openvdb::FloatGrid::Ptr resolution = g.Float("resolution");
  if (!resolution || !g.coverage)
    throw InputError(scene.path, "$.study.dori", "DORI classes need the coverage and resolution fields",
                     "add \"coverage\" and \"resolution\" to the study's fields");
  DoriSummary s;
  std::int64_t total = 0, reached[4] = {0, 0, 0, 0};
  openvdb::FloatGrid::Ptr grid;
  if (grids) {
    grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(g.coverage->transformPtr()->copy());
  }
  auto res = resolution->getConstAccessor();
  for (auto it = g.coverage->cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto c = box.begin(); c; ++c) {
      ++total;
      const float d = res.isValueOn(*c) ? res.getValue(*c) : 0.0f;
      int cls = 0;
      for (int k = 0; k < 4; ++k)
        if (d >= kDoriPxPerM[k]) cls = k + 1, ++reached[k];
      if (grid) grid->tree().setValue(*c, float(cls));
    }
  }
  const double n = total > 0 ? double(total) : 1.0;
  s.detection = reached[0] / n;
  s.observation = reached[1] / n;
  s.recognition = reached[2] / n;
  s.identification = reached[3] / n;
  if (grid) {
    grid->pruneGrid();
    grids->impl().extra["dori"] = grid;
  }
  return s;
}

}  // namespace pandora
