#include "volume/pixel_targets.h"

#include <gtest/gtest.h>

#include <string>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/error.h"
#include "volume/fields_vdb.h"
#include "volume/summary.h"

namespace pandora {
namespace {

// Three cameras over a region with a post in it; two pixel targets and DORI.
Scene TestScene() {
  return ParseScene(R"({"pandora": 1,
    "objects": [{"name": "post", "box": {"size": [0.3, 0.3, 2]}, "position": [0, 0, 1]}],
    "rigs": [{"name": "r", "cameras": [
      {"id": "a", "position": [3, 0, 1.5], "look_at": [0, 0, 1], "resolution": [1280, 960], "hfov_deg": 60},
      {"id": "b", "position": [-3, 0.5, 1.5], "look_at": [0, 0, 1], "resolution": [640, 480], "hfov_deg": 60},
      {"id": "c", "position": [0, 3, 2.5], "look_at": [0, 0, 1], "resolution": [1920, 1080], "hfov_deg": 40,
       "distortion": {"model": "brown_conrady", "k1": -0.1}}]}],
    "study": {"region": {"box": {"min": [-1.5, -1.5, 0], "max": [1.5, 1.5, 2]}}, "voxel_size": 0.1,
              "fields": ["coverage", "cameras", "resolution"], "dori": true,
              "pixel_targets": [{"name": "marker", "size_m": 0.014, "min_px": 4},
                                {"name": "face", "size_m": 0.16, "min_px": 80}]}})",
                    "pixel_test.json");
}

// Against a brute-force loop over the free voxels: each camera's full visibility test (occlusion
// rays included, not the stored camera sets) and the pixel density of its projection Jacobian.
TEST(PixelTargets, EqualABruteForceLoopWithOcclusionRays) {
  const Scene scene = TestScene();
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = scene.study.fields;
  const Fields fields = EvaluateFields(scene, rig, *caster, options);
  Fields grids;
  const std::vector<PixelTargetSummary> result =
      EvaluatePixelTargets(scene, rig, fields, 3, &grids);
  ASSERT_EQ(result.size(), 2u);
  const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
  for (std::size_t t = 0; t < 2; ++t) {
    const double need = scene.study.pixel_targets[t].px_per_m();
    std::vector<double> share(3, 0.0);
    std::int64_t voxels = 0, differ = 0;
    auto acc =
        grids.impl().extra.at("pixels_" + scene.study.pixel_targets[t].name)->getConstAccessor();
    for (auto it = fields.impl().coverage->cbeginValueOn(); it; ++it) {
      openvdb::CoordBBox box;
      it.getBoundingBox(box);
      for (auto c = box.begin(); c; ++c) {
        const openvdb::Vec3d w = fields.impl().coverage->indexToWorld(*c);
        int n = 0;
        for (int cam = 0; cam < 3; ++cam) {
          Mat23 J;
          n += tester.Test(cam, Vec3(w.x(), w.y(), w.z()), nullptr, &J) == ViewResult::kSeen &&
               PixelDensity(J) >= need;
        }
        for (int j = 1; j <= std::min(n, 3); ++j) share[j - 1] += 1;
        differ += acc.getValue(*c) != float(n);
        ++voxels;
      }
    }
    EXPECT_EQ(differ, 0);
    for (int j = 0; j < 3; ++j)
      EXPECT_DOUBLE_EQ(result[t].share_ge[j], share[j] / double(voxels)) << j;
  }
  // The marker (286 px/m) is met more widely than the face (500 px/m), and neither everywhere.
  EXPECT_GT(result[0].share_ge[0], result[1].share_ge[0]);
  EXPECT_LT(result[1].share_ge[2], 0.5);
  EXPECT_GT(result[0].share_ge[0], 0.5);
}

TEST(PixelTargets, DoriClassesFromTheBestCamerasDensity) {
  const Scene scene = TestScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = scene.study.fields;
  const Fields fields = EvaluateFields(scene, scene.rigs[0], *caster, options);
  Fields grids;
  const DoriSummary d = EvaluateDori(scene, fields, &grids);
  // Against the resolution grid read directly: the share at or above each threshold.
  std::int64_t voxels = 0, reached[4] = {0, 0, 0, 0};
  auto res = fields.impl().Float("resolution")->getConstAccessor();
  auto cls = grids.impl().extra.at("dori")->getConstAccessor();
  for (auto it = fields.impl().coverage->cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto c = box.begin(); c; ++c) {
      const double v = res.isValueOn(*c) ? res.getValue(*c) : 0.0;
      int k = 0;
      while (k < 4 && v >= kDoriPxPerM[k]) reached[k++]++;
      EXPECT_EQ(cls.getValue(*c), float(k));
      ++voxels;
    }
  }
  EXPECT_DOUBLE_EQ(d.detection, double(reached[0]) / voxels);
  EXPECT_DOUBLE_EQ(d.identification, double(reached[3]) / voxels);
  EXPECT_GE(d.detection, d.observation);
  EXPECT_GE(d.observation, d.recognition);
  EXPECT_GE(d.recognition, d.identification);
  EXPECT_GT(d.identification, 0.0);
  EXPECT_LT(d.identification, d.detection);
  // Without the fields they need: an error naming the study key.
  FieldOptions coverage_only;
  coverage_only.fields = {"coverage"};
  const Fields bare = EvaluateFields(scene, scene.rigs[0], *caster, coverage_only);
  try {
    EvaluatePixelTargets(scene, scene.rigs[0], bare, 3, nullptr);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "$.study.pixel_targets");
  }
}

// Named sub-regions: two halves of the study region split at x = 0 (the one given as a closed
// mesh box) partition its voxels, their shares weighted by their voxels add up to the whole
// region's, and a region equal to the study region repeats the summary's coverage.
TEST(NamedRegions, PartitionTheStudyRegion) {
  Scene scene = TestScene();
  Region left, right, all;
  left.box.min = Vec3(-1.5, -1.5, 0);
  left.box.max = Vec3(-1e-9, 1.5, 2);
  right.kind = Region::Kind::kMesh;
  right.box.min = Vec3(1e-9, -1.5, 0);
  right.box.max = Vec3(1.5, 1.5, 2);
  right.mesh = MakeBox(right.box.size());
  for (Vec3& v : right.mesh.vertices) v += right.box.center();
  all.box = scene.study.region.box;
  scene.study.regions = {{"left", left}, {"right", right}, {"all", all}};
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "cameras", "resolution", "sigma_max"};
  const Fields fields = EvaluateFields(scene, scene.rigs[0], *caster, options);
  const Summary s = Summarize(scene, scene.rigs[0], fields, options.fields, 1);
  ASSERT_EQ(s.regions.size(), 3u);
  const RegionSummary &l = s.regions[0], &r = s.regions[1], &a = s.regions[2];
  EXPECT_EQ(a.voxels, s.region_voxels);
  EXPECT_EQ(l.voxels + r.voxels, s.region_voxels);
  EXPECT_GT(l.voxels, 0);
  EXPECT_GT(r.voxels, 0);
  EXPECT_DOUBLE_EQ(a.ge2, s.coverage.ge2);
  EXPECT_NEAR(l.ge1 * l.voxels + r.ge1 * r.voxels, s.coverage.ge1 * s.region_voxels, 1e-9);
  EXPECT_NEAR(l.ge3 * l.voxels + r.ge3 * r.voxels, s.coverage.ge3 * s.region_voxels, 1e-9);
  EXPECT_EQ(a.sigma_max_p90, s.uncertainty->sigma_max_mm.p90);
  // The halves differ: camera "a" (x = 3) sees more of the right half.
  EXPECT_NE(l.ge3, r.ge3);
}

}  // namespace
}  // namespace pandora
