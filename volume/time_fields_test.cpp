#include "volume/time_fields.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/surface_targets.h"
#include "volume/fields_test_util.h"
#include "volume/fields_vdb.h"
#include "volume/summary.h"

namespace pandora {
namespace {

// A room with two moving groups: a keyframed cart and a "person" (a capsule and a sphere, solid)
// that walks through the region, four cameras in the corners; the study samples five times and
// targets both groups' surfaces.
Scene TestScene() {
  return ParseScene(R"({"pandora": 1,
    "objects": [
      {"name": "floor", "plane": {"size": [8, 8]}},
      {"name": "cart", "box": {"size": [0.6, 0.4, 0.8]}, "position": [-1, 0.5, 0.4], "solid": true},
      {"name": "body", "group": "p", "capsule": {"radius": 0.2, "length": 1.0}, "position": [1, -0.5, 0.7], "solid": true},
      {"name": "head", "group": "p", "sphere": {"radius": 0.12}, "position": [1, -0.5, 1.55], "solid": true}],
    "motions": {
      "cart": {"keyframes": [{"t": 0}, {"t": 4, "move": [2, -0.5, 0], "yaw_deg": 60}]},
      "p": {"keyframes": [{"t": 0}, {"t": 2, "move": [-1.2, 0.8, 0], "yaw_deg": 90}, {"t": 4, "move": [-2, 0, 0], "yaw_deg": 180}]}},
    "rigs": [{"name": "r", "cameras": [
      {"id": "a", "position": [2.5, 2.5, 2.4], "look_at": [0, 0, 0.8], "resolution": [640, 480], "hfov_deg": 70},
      {"id": "b", "position": [-2.5, 2.5, 2.4], "look_at": [0, 0, 0.8], "resolution": [640, 480], "hfov_deg": 70},
      {"id": "c", "position": [-2.5, -2.5, 2.4], "look_at": [0, 0, 0.8], "resolution": [640, 480], "hfov_deg": 70},
      {"id": "d", "position": [2.5, -2.5, 0.6], "look_at": [0, 0, 0.8], "resolution": [640, 480], "hfov_deg": 70}]}],
    "study": {"region": {"box": {"min": [-1.8, -1.8, 0.05], "max": [1.8, 1.8, 1.85]}}, "voxel_size": 0.1,
              "time": {"samples": 5, "min_cameras": 2},
              "targets": {"objects": ["p", "cart"], "points": 400, "seed": 3}}})",
                    "time_test.json");
}

// Per voxel coordinate: the coverage of a sample's fields (free voxels only).
std::map<std::array<int, 3>, int> CoverageOf(const Fields& f) {
  std::map<std::array<int, 3>, int> out;
  for (auto it = f.impl().coverage->cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto c = box.begin(); c; ++c) out[std::array<int, 3>{(*c).x(), (*c).y(), (*c).z()}] = *it;
  }
  return out;
}

// The issue's "time fractions equal a brute-force loop over samples": each sample evaluated on its
// own (the scene moved, the caster of that sample), then combined voxel by voxel here.
TEST(TimeFields, EqualABruteForceLoopOverSamples) {
  const Scene scene = TestScene();
  const Rig& rig = scene.rigs[0];
  const std::vector<TimeSample> samples = scene.TimeSamples();
  ASSERT_EQ(samples.size(), 5u);
  const auto parts = MakeSceneParts(scene);
  FieldOptions options;
  options.fields = {"coverage", "sigma_max"};
  const int k = scene.TimeMinCameras();
  TimeFieldsResult result = EvaluateFieldsOverTime(scene, rig, *parts, samples, options, k);

  std::map<std::array<int, 3>, int> least, free, good;
  std::int64_t pairs = 0, good_pairs = 0;
  std::vector<float> sigmas;
  for (const TimeSample& s : samples) {
    const Scene at = SceneAtSample(scene, s);
    const auto caster = parts->At(PartTransforms(scene, s));
    const Fields f = EvaluateFields(at, rig, *caster, options);
    sigmas.insert(sigmas.end(), f.stats.sigma_max_mm.begin(), f.stats.sigma_max_mm.end());
    for (const auto& [c, n] : CoverageOf(f)) {
      least[c] = least.count(c) ? std::min(least[c], n) : n;
      free[c] += 1;
      good[c] += n >= k;
      ++pairs;
      good_pairs += n >= k;
    }
  }
  // The body moves through the region: some voxels are free in only some samples.
  int partly = 0;
  for (const auto& [c, n] : free) partly += n < 5;
  EXPECT_GT(partly, 20);

  auto min_acc = result.grids.impl().extra.at("coverage_min")->getConstAccessor();
  auto share_acc = result.grids.impl().extra.at("coverage_time_share")->getConstAccessor();
  std::int64_t always = 0;
  for (const auto& [c, n] : least) {
    const openvdb::Coord xyz(c[0], c[1], c[2]);
    ASSERT_TRUE(min_acc.isValueOn(xyz));
    EXPECT_EQ(min_acc.getValue(xyz), float(n));
    EXPECT_EQ(share_acc.getValue(xyz), float(double(good[c]) / free[c]));
    always += n >= k;
  }
  EXPECT_EQ(result.grids.impl().extra.at("coverage_min")->activeVoxelCount(),
            openvdb::Index64(least.size()));
  const TimeSummary& t = result.summary;
  EXPECT_EQ(t.voxels, std::int64_t(least.size()));
  EXPECT_DOUBLE_EQ(t.always, double(always) / double(least.size()));
  EXPECT_DOUBLE_EQ(t.mean, double(good_pairs) / double(pairs));
  EXPECT_EQ(t.sigma_max_p90, NearestRankPercentile(sigmas, 90));
  // The worst sample is the one with the lowest share.
  for (const TimeSampleSummary& r : t.samples) EXPECT_LE(t.samples[t.worst_sample].ge_k, r.ge_k);
  EXPECT_LT(t.always, t.mean);  // something is covered only part of the time
}

// Every field (the steady ones with a motion model, the per-camera sets too) of every sample,
// evaluated by difference from the previous sample, against a full evaluation of that sample's
// scene: voxel for voxel, bit for bit, statistics included. Two scenes: the test room (a cart and a
// solid person whose voxels leave and join the region) and the bundled mocap lab (two people in six
// poses); a repeated sample moves nothing and costs nothing.
TEST(TimeFields, SamplesByDifferenceEqualFullEvaluations) {
  for (const std::string& which : {std::string("test room"), std::string("mocap lab")}) {
    Scene scene = which == "test room" ? TestScene() : LoadScene("examples/mocap_lab/scene.json");
    scene.study.motion = MotionModel{};
    const Rig& rig = scene.rigs[0];
    std::vector<TimeSample> samples = scene.TimeSamples();
    ASSERT_GE(samples.size(), 5u);
    samples.insert(samples.begin() + 2, samples[1]);  // nothing moves from 1 to 2
    const auto parts = MakeSceneParts(scene);
    FieldOptions options;
    options.fields = FieldNames();
    std::vector<SampleCost> costs;
    std::int64_t full_rays = 0;
    EvaluateSamples(scene, rig, *parts, samples, options,
                    [&](std::size_t s, const Fields& f, const SampleCost& cost) {
                      const Scene at = SceneAtSample(scene, samples[s]);
                      const auto caster = CasterAtSample(*parts, scene, samples[s]);
                      const Fields full = EvaluateFields(at, rig, *caster, options);
                      testing::ExpectSameFields(f, full, which + " sample " + std::to_string(s));
                      costs.push_back(cost);
                      full_rays = std::max(full_rays, full.stats.rays);
                    });
    ASSERT_EQ(costs.size(), samples.size());
    EXPECT_TRUE(costs[0].full);
    EXPECT_EQ(costs[2].dirty_blocks, 0) << which;  // the repeated sample
    EXPECT_EQ(costs[2].rays, 0) << which;
    for (std::size_t s = 1; s < costs.size(); ++s) {
      EXPECT_FALSE(costs[s].full) << which << " " << s;
      EXPECT_LT(costs[s].rays, costs[0].rays) << which << " " << s;
      if (s != 2) {
        EXPECT_GT(costs[s].rays, 0) << which << " " << s;
      }
    }
    EXPECT_GT(full_rays, 0);
  }
}

// Surface targets against each sample's scene built from scratch (a fresh BVH of the moved scene,
// the points moved by the closed-form pose): the same camera counts but for rays that graze an
// edge (float rounding of the instance transform).
TEST(SurfaceTargets, EqualVisibilityTestsOnEachSamplesOwnScene) {
  const Scene scene = TestScene();
  const Rig& rig = scene.rigs[0];
  const std::vector<TimeSample> samples = scene.TimeSamples();
  const auto parts = MakeSceneParts(scene);
  const int k = scene.TimeMinCameras();
  const std::vector<SurfaceTargetResult> results =
      EvaluateSurfaceTargets(scene, rig, *parts, samples, k);
  ASSERT_EQ(results.size(), 2u);
  std::size_t differ = 0, total = 0;
  for (std::size_t g = 0; g < results.size(); ++g) {
    const SurfaceTargetResult& r = results[g];
    EXPECT_EQ(r.points, 400);
    EXPECT_EQ(r.samples, 5);
    // The points, as the evaluation draws them (seed + target index), on the rest surface.
    TriangleMesh mesh;
    for (const SceneObject& o : scene.objects)
      if (o.group == r.name || o.name == r.name) mesh.Append(o.mesh);
    std::vector<Vec3> points, normals;
    SampleSurface(mesh, 400, 3 + g, &points, &normals);
    const int motion = r.name == "cart" ? 0 : 1;
    std::vector<double> share(5, 0.0);
    for (std::size_t s = 0; s < samples.size(); ++s) {
      const Scene at = SceneAtSample(scene, samples[s]);
      const auto caster = MakeEmbreeRayCaster(at.AllTriangles());
      const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
      const Eigen::Isometry3d T =
          PoseTransform(samples[s].poses[motion], scene.motions[motion].anchor);
      for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3 X = T * points[i], n = T.linear() * normals[i];
        int count = 0;
        for (int c = 0; c < 4; ++c) count += tester.Test(c, X, &n) == ViewResult::kSeen;
        differ += count != r.cameras[s * points.size() + i];
        ++total;
        share[s] += (count >= k) / 400.0;
      }
      EXPECT_NEAR(r.sample_share[s], share[s], 0.005) << r.name << " " << samples[s].label;
    }
    // Shares are consistent: >= 1 is at least >= 2 is at least >= 3; "always" is at most every
    // sample's share.
    EXPECT_GE(r.share_ge[0], r.share_ge[1]);
    EXPECT_GE(r.share_ge[1], r.share_ge[2]);
    for (double v : r.sample_share) EXPECT_LE(r.always, v);
    EXPECT_GT(r.share_ge[0], 0.3);
  }
  std::printf("camera counts differ on %zu of %zu (point, sample) pairs\n", differ, total);
  EXPECT_LE(double(differ), 0.002 * double(total)) << differ << " of " << total;
}

TEST(SurfaceTargets, SamplesAreUniformByArea) {
  // Two unit squares, one four times the other's area: a fifth of the points on the small one.
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                   {5, 0, 0}, {7, 0, 0}, {7, 2, 0}, {5, 2, 0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  std::vector<Vec3> p, n;
  SampleSurface(mesh, 20000, 9, &p, &n);
  ASSERT_EQ(p.size(), 20000u);
  int small = 0;
  double mean_x = 0;
  for (const Vec3& v : p) {
    small += v.x() <= 1;
    if (v.x() <= 1) mean_x += v.x();
    EXPECT_NEAR(v.z(), 0, 1e-15);
  }
  EXPECT_NEAR(small / 20000.0, 0.2, 0.01);
  EXPECT_NEAR(mean_x / small, 0.5, 0.01);  // uniform within the square
  for (const Vec3& v : n) EXPECT_LT((v - Vec3::UnitZ()).norm(), 1e-15);
  std::vector<Vec3> again, again_n;
  SampleSurface(mesh, 20000, 9, &again, &again_n);
  EXPECT_EQ(p, again);  // reproducible from the seed
}

}  // namespace
}  // namespace pandora
