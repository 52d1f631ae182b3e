#include "volume/pixel_targets.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "analysis/geometry/visibility.h"
#include "analysis/util/error.h"
#include "volume/fields_vdb.h"

namespace pandora {

SummaryParts PixelTargetParts(const Scene& scene, const Rig& rig, const Fields& fields,
                              int min_cameras, Fields* grids) {
  SummaryParts out;
  if (scene.study.pixel_targets.empty()) return out;
  const Fields::Impl& g = fields.impl();
  if (g.visible.empty() || !g.coverage)
    throw InputError(scene.path, "$.study.pixel_targets",
                     "pixel targets need the coverage and cameras fields",
                     "add \"coverage\" and \"cameras\" to the study's fields");
  const int kmax = std::max(3, min_cameras);
  const auto t0 = std::chrono::steady_clock::now();
  // The projection alone: no ray is cast (the camera sets already hold the occlusion).
  const auto none = MakeBruteForceRayCaster(TriangleMesh());
  const VisibilityTester tester(rig.cameras, *none, scene.ContentBounds().diagonal());
  // Per target: how many cameras meet it at each voxel.
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
  // Per target: the free region voxels, then those met by >= 1 .. kmax cameras.
  out.counts.assign(targets.size() * std::size_t(1 + kmax), 0);
  for (std::size_t t = 0; t < targets.size(); ++t) {
    std::int64_t* row = &out.counts[t * std::size_t(1 + kmax)];
    openvdb::FloatGrid::Ptr grid;
    if (grids) {
      grid = openvdb::FloatGrid::create(0.0f);
      grid->setTransform(g.coverage->transformPtr()->copy());
    }
    // Every free region voxel (coverage is active on them), met or not.
    auto count = counts[t]->getConstAccessor();
    ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int) {
      const int n = count.getValue(c);
      for (int j = 1; j <= std::min(n, kmax); ++j) ++row[j];
      if (grid) grid->tree().setValue(c, float(n));
      ++row[0];
    });
    if (grid) {
      grid->pruneGrid();
      grids->impl().extra["pixels_" + targets[t].name] = grid;
    }
  }
  out.seconds = {std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
  return out;
}

std::vector<PixelTargetSummary> FinishPixelTargets(const Scene& scene, int min_cameras,
                                                   const SummaryParts& parts) {
  std::vector<PixelTargetSummary> out;
  const std::vector<PixelTarget>& targets = scene.study.pixel_targets;
  const int kmax = std::max(3, min_cameras);
  if (targets.empty()) return out;
  if (parts.counts.size() != targets.size() * std::size_t(1 + kmax))
    throw std::invalid_argument("FinishPixelTargets: the parts are of another study");
  for (std::size_t t = 0; t < targets.size(); ++t) {
    const std::int64_t* row = &parts.counts[t * std::size_t(1 + kmax)];
    PixelTargetSummary s;
    s.target = targets[t];
    for (int j = 1; j <= kmax; ++j)
      s.share_ge.push_back(row[0] > 0 ? double(row[j]) / double(row[0]) : 0.0);
    s.seconds = parts.seconds.empty() ? 0.0 : parts.seconds[0];
    out.push_back(s);
  }
  return out;
}

std::vector<PixelTargetSummary> EvaluatePixelTargets(const Scene& scene, const Rig& rig,
                                                     const Fields& fields, int min_cameras,
                                                     Fields* grids) {
  return FinishPixelTargets(scene, min_cameras,
                            PixelTargetParts(scene, rig, fields, min_cameras, grids));
}

DoriSummary EvaluateDori(const Scene& scene, const Fields& fields, Fields* grids) {
  const Fields::Impl& g = fields.impl();
  const openvdb::FloatGrid::Ptr resolution = g.Load("resolution");
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
