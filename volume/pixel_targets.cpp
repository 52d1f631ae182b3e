#include "volume/pixel_targets.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

#include "analysis/geometry/visibility.h"
#include "analysis/util/error.h"
#include "volume/fields_vdb.h"

namespace pandora {

std::vector<PixelTargetSummary> EvaluatePixelTargets(const Scene& scene, const Rig& rig,
                                                     const Fields& fields, int min_cameras,
                                                     Fields* grids) {
  std::vector<PixelTargetSummary> out;
  if (scene.study.pixel_targets.empty()) return out;
  const Fields::Impl& g = fields.impl();
  if (g.visible.empty() || !g.coverage)
    throw InputError(scene.path, "$.study.pixel_targets",
                     "pixel targets need the coverage and cameras fields",
                     "add \"coverage\" and \"cameras\" to the study's fields");
  const int kmax = std::max(3, min_cameras);
  const auto t0 = std::chrono::steady_clock::now();
  // The caster is not used: the visibility is known; only TestGeometry's Jacobian is needed.
  const auto none = MakeBruteForceRayCaster(TriangleMesh());
  const VisibilityTester tester(rig.cameras, *none, scene.ContentBounds().diagonal());
  // Per target, the cameras meeting it at each voxel; each (voxel, camera) density computed once.
  const std::vector<PixelTarget>& targets = scene.study.pixel_targets;
  std::vector<openvdb::Int32Grid::Ptr> counts;
  for (std::size_t t = 0; t < targets.size(); ++t) counts.push_back(openvdb::Int32Grid::create(0));
  for (std::size_t c = 0; c < g.visible.size() && c < rig.cameras.size(); ++c) {
    if (!g.visible[c] || !rig.cameras[c].enabled) continue;
    std::vector<openvdb::Coord> voxels;
    for (auto it = g.visible[c]->cbeginValueOn(); it; ++it) voxels.push_back(it.getCoord());
    std::vector<double> density(voxels.size(), 0.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 1024), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const openvdb::Vec3d w = g.visible[c]->indexToWorld(voxels[i]);
        Mat23 J;
        if (tester.TestGeometry(int(c), Vec3(w.x(), w.y(), w.z()), nullptr, nullptr, &J) ==
            ViewResult::kSeen)
          density[i] = PixelDensity(J);
      }
    });
    for (std::size_t t = 0; t < targets.size(); ++t) {
      auto acc = counts[t]->getAccessor();
      for (std::size_t i = 0; i < voxels.size(); ++i)
        if (density[i] >= targets[t].px_per_m())
          acc.setValue(voxels[i], acc.getValue(voxels[i]) + 1);
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (std::size_t t = 0; t < targets.size(); ++t) {
    PixelTargetSummary s;
    s.target = targets[t];
    s.share_ge.assign(kmax, 0.0);
    std::int64_t voxels = 0;
    openvdb::FloatGrid::Ptr grid;
    if (grids) {
      grid = openvdb::FloatGrid::create(0.0f);
      grid->setTransform(g.coverage->transformPtr()->copy());
    }
    // Over the free voxels (the coverage grid's active set).
    auto count = counts[t]->getConstAccessor();
    ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int) {
      const int n = count.getValue(c);
      for (int j = 1; j <= std::min(n, kmax); ++j) s.share_ge[j - 1] += 1;
      if (grid) grid->tree().setValue(c, float(n));
      ++voxels;
    });
    for (double& v : s.share_ge) v = voxels > 0 ? v / double(voxels) : 0.0;
    if (grid) {
      grid->pruneGrid();
      grids->impl().extra["pixels_" + targets[t].name] = grid;
    }
    s.seconds = seconds;
    out.push_back(s);
  }
  return out;
}

DoriSummary EvaluateDori(const Scene& scene, const Fields& fields, Fields* grids) {
  const Fields::Impl& g = fields.impl();
  const openvdb::FloatGrid::Ptr resolution = g.Float("resolution");
  if (!resolution || !g.coverage)
    throw InputError(scene.path, "$.study.dori",
                     "DORI classes need the coverage and resolution fields",
                     "add \"coverage\" and \"resolution\" to the study's fields");
  DoriSummary s;
  std::int64_t& total = s.voxels;
  std::int64_t* reached = s.reached;
  openvdb::FloatGrid::Ptr grid;
  if (grids) {
    grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(g.coverage->transformPtr()->copy());
  }
  auto res = resolution->getConstAccessor();
  ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int) {
    ++total;
    const float d = res.isValueOn(c) ? res.getValue(c) : 0.0f;
    int cls = 0;
    for (int k = 0; k < 4; ++k)
      if (d >= kDoriPxPerM[k]) cls = k + 1, ++reached[k];
    if (grid) grid->tree().setValue(c, float(cls));
  });
  s.SetShares();
  if (grid) {
    grid->pruneGrid();
    grids->impl().extra["dori"] = grid;
  }
  return s;
}

}  // namespace pandora
