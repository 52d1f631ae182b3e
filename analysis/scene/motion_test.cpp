#include "analysis/scene/motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

// A floor, a static post and a box "cart" (0.4 x 0.4 x 0.5, 0.1 m above the floor: its anchor is
// (0, 0, 0.1)) with
// `motion` (JSON of the motion) and `time` (JSON of the study's time axis, or empty).
std::string SceneText(const std::string& motion, const std::string& time = "",
                      const std::string& extra_objects = "") {
  return R"({"pandora": 1,
    "objects": [
      {"name": "floor", "plane": {"size": [20, 20]}},
      {"name": "post", "box": {"size": [0.2, 0.2, 1]}, "position": [-3, -3, 0.5]},
      {"name": "cart", "box": {"size": [0.4, 0.4, 0.5]}, "position": [0, 0, 0.35]})" +
         extra_objects + R"(],
    "motions": {)" +
         motion + R"(},
    "rigs": [{"name": "r", "cameras": [{"id": "top", "position": [0, 0, 3], "look_at": [0, 0, 0],
              "up": [0, 1, 0], "resolution": [800, 800], "hfov_deg": 120}]}],
    "study": {"region": {"box": {"min": [-2, -2, 0], "max": [2, 2, 1]}})" +
         (time.empty() ? "" : ", \"time\": " + time) + "}}";
}

TEST(Motion, KeyframesInterpolateAndDefineTheSamples) {
  const Scene scene = ParseScene(
      SceneText(R"("cart": {"keyframes": [{"t": 0}, {"t": 2, "move": [2, 0, 0], "yaw_deg": 90},
                                          {"t": 4, "move": [2, 1, 0], "yaw_deg": 90}]})"),
      "s.json");
  ASSERT_EQ(scene.motions.size(), 1u);
  const ObjectMotion& m = scene.motions[0];
  EXPECT_EQ(m.objects, std::vector<int>{2});
  EXPECT_LT((m.anchor - Vec3(0, 0, 0.1)).norm(), 1e-12);  // the bottom centre of the placed box
  const GroupPose p = m.AtTime(1.0);
  EXPECT_LT((p.move - Vec3(1, 0, 0)).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(p.yaw_deg, 45);
  EXPECT_LT((m.AtTime(3.0).move - Vec3(2, 0.5, 0)).norm(), 1e-12);
  EXPECT_LT((m.AtTime(-5).move).norm(), 1e-12);                 // held before the first
  EXPECT_LT((m.AtTime(9).move - Vec3(2, 1, 0)).norm(), 1e-12);  // and after the last
  // No time axis: the keyframe times.
  const std::vector<TimeSample> s = scene.TimeSamples();
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[1].label, "t=2 s");
  // A pose turns about the anchor then moves: the box's corner (0.2, 0.2, 0.1) at t = 2 goes to
  // (2, 0, 0.1) + Rz(90) (0.2, 0.2, 0) = (1.8, 0.2, 0.1).
  const Scene at = SceneAtSample(scene, s[1]);
  EXPECT_TRUE(at.motions.empty());
  bool found = false;
  for (const Vec3& v : at.objects[2].mesh.vertices)
    found |= (v - Vec3(1.8, 0.2, 0.1)).norm() < 1e-12;
  EXPECT_TRUE(found);
  EXPECT_EQ(at.objects[1].mesh.vertices, scene.objects[1].mesh.vertices);  // the post stays
  // "samples": uniform over the keyframes' span.
  const Scene five =
      ParseScene(SceneText(R"("cart": {"keyframes": [{"t": 0}, {"t": 2, "move": [2, 0, 0]}]})",
                           R"({"samples": 5})"),
                 "s.json");
  const std::vector<TimeSample> s5 = five.TimeSamples();
  ASSERT_EQ(s5.size(), 5u);
  EXPECT_DOUBLE_EQ(s5[3].time, 1.5);
  EXPECT_LT((s5[3].poses[0].move - Vec3(1.5, 0, 0)).norm(), 1e-12);
}

TEST(Motion, GroupsNamedPosesAndRandomDraws) {
  const std::string people = R"(,
      {"name": "a_body", "group": "a", "capsule": {"radius": 0.2, "length": 1.2}, "position": [1, 0, 0.8]},
      {"name": "a_head", "group": "a", "sphere": {"radius": 0.12}, "position": [1, 0, 1.6]})";
  const Scene scene = ParseScene(
      SceneText(R"("a": {"poses": {"stand": {}, "walk": {"move": [0, 1, 0], "yaw_deg": 30}}},
                   "cart": {"random": {"box": {"min": [-1, -1, 0], "max": [1, 1, 0]}, "yaw_deg": [0, 90], "seed": 7}})",
                R"({"poses": ["walk", "stand"], "min_cameras": 2})", people),
      "s.json");
  ASSERT_EQ(scene.motions.size(), 2u);
  EXPECT_EQ(scene.motions[0].objects, (std::vector<int>{3, 4}));
  EXPECT_EQ(scene.TimeMinCameras(), 2);
  const std::vector<TimeSample> s = scene.TimeSamples();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].label, "pose 'walk'");
  EXPECT_DOUBLE_EQ(s[0].poses[0].yaw_deg, 30);
  EXPECT_DOUBLE_EQ(s[1].poses[0].yaw_deg, 0);
  // Random draws: inside the box and the yaw range, the same for the same index whatever the count.
  for (const TimeSample& t : s) {
    const Vec3 at = scene.motions[1].anchor + t.poses[1].move;
    EXPECT_TRUE(scene.motions[1].box.Contains(at));
    EXPECT_GE(t.poses[1].yaw_deg, 0);
    EXPECT_LE(t.poses[1].yaw_deg, 90);
  }
  EXPECT_EQ(scene.motions[1].RandomDraw(1).move, s[1].poses[1].move);
  EXPECT_NE(scene.motions[1].RandomDraw(0).move, scene.motions[1].RandomDraw(1).move);
  // 2000 draws fill the box: mean near its centre, spread near a uniform's.
  double mean = 0, var = 0;
  for (int i = 0; i < 2000; ++i) {
    const double x = scene.motions[1].RandomDraw(i).move.x();
    mean += x / 2000;
    var += x * x / 2000;
  }
  EXPECT_NEAR(mean, 0, 0.05);
  EXPECT_NEAR(var - mean * mean, 4.0 / 12, 0.03);
}

void ExpectError(const std::string& text, const std::string& path) {
  try {
    ParseScene(text, "s.json");
    ADD_FAILURE() << "no error for " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), path) << e.what();
  }
}

TEST(Motion, BadMotionsNameTheirJsonPath) {
  ExpectError(SceneText(R"("nobody": {"keyframes": [{"t": 0}]})"), "$.motions.nobody");
  ExpectError(SceneText(R"("cart": {"keyframes": [{"t": 1}, {"t": 1}]})"),
              "$.motions.cart.keyframes[1].t");
  ExpectError(SceneText(R"("cart": {"poses": {"a": {}}})", R"({"poses": ["b"]})"),
              "$.motions.cart.poses");
  ExpectError(SceneText(R"("cart": {"keyframes": [{"t": 0}]})", R"({"poses": ["b"]})"),
              "$.motions.cart");
  ExpectError(SceneText(R"("cart": {"poses": {"a": {}}})", R"({"samples": 3})"), "$.study.time");
  ExpectError(SceneText(R"("cart": {"random": {"box": {"min": [0, 0, 0], "max": [1, -1, 0]}}})"),
              "$.motions.cart.random.box.max[1]");
  ExpectError(
      SceneText(R"("cart": {"keyframes": [{"t": 0}]})", R"({"times": [0, 1], "samples": 2})"),
      "$.study.time");
  ExpectError(SceneText(R"("cart": {"keyframes": [{"t": 0, "turn": 3}]})"),
              "$.motions.cart.keyframes[0].turn");
}

TEST(Motion, PartsCasterEqualsABvhOfTheMovedScene) {
  const Scene scene = ParseScene(
      SceneText(
          R"("cart": {"keyframes": [{"t": 0}, {"t": 1, "move": [0.7, -0.4, 0.1], "yaw_deg": 37}]})"),
      "s.json");
  const auto parts = MakeSceneParts(scene);
  ASSERT_EQ(parts->part_count(), 2u);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const TimeSample& sample : scene.TimeSamples()) {
    const auto moved = parts->At(PartTransforms(scene, sample));
    const auto fresh = MakeEmbreeRayCaster(SceneAtSample(scene, sample).AllTriangles());
    int differ = 0, hits = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 a(u(rng), u(rng), 0.02 + 0.6 * std::abs(u(rng)));
      const Vec3 b(u(rng), u(rng), 2.0 * std::abs(u(rng)));
      const Ray ray{a, (b - a).normalized(), 0.0, (b - a).norm()};
      differ += moved->Occluded(ray) != fresh->Occluded(ray);
      const Ray down{a, Vec3(0.3 * u(rng), 0.3 * u(rng), -1).normalized(), 0.0, 10.0};
      const auto h1 = moved->Intersect(down), h2 = fresh->Intersect(down);
      ASSERT_EQ(bool(h1), bool(h2));
      if (!h1) continue;
      ++hits;
      EXPECT_EQ(h1->triangle, h2->triangle);
      EXPECT_NEAR(h1->t, h2->t, 1e-5);
      EXPECT_LT((h1->normal - h2->normal).norm(), 1e-5);
    }
    // Float rounding of the instance transform can flip a ray grazing an edge.
    EXPECT_LE(differ, 2) << sample.label;
    EXPECT_GT(hits, 10000);
  }
}

// A keyframed box crosses under a camera; its shadow on the floor is where the closed form puts it.
// Camera at height H above the origin, the box spanning x in [c - 0.2, c + 0.2] (|y| <= 0.2) and
// z in [z0, z1]: a floor point (X, 0, 0), X > 0, is hidden when the segment to the camera, at
// x = X (1 - z / H), meets the box: X (1 - z0 / H) >= c - 0.2 and X (1 - z1 / H) <= c + 0.2.
TEST(Motion, AKeyframedOccludersShadowMovesAsPredicted) {
  const Scene scene = ParseScene(
      SceneText(
          R"("cart": {"keyframes": [{"t": 0, "move": [0.5, 0, 0]}, {"t": 10, "move": [1.5, 0, 0]}]})",
          R"({"times": [0, 2.5, 5, 7.5, 10]})"),
      "s.json");
  const double H = 3.0, z0 = 0.1, z1 = 0.6;
  const auto parts = MakeSceneParts(scene);
  const Rig& rig = scene.rigs[0];
  int checked = 0;
  for (const TimeSample& sample : scene.TimeSamples()) {
    const double c = 0.5 + sample.time / 10.0;
    const auto caster = parts->At(PartTransforms(scene, sample));
    const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
    const double lo = (c - 0.2) * H / (H - z0), hi = (c + 0.2) * H / (H - z1);
    for (double X = 0.05; X < 2.0; X += 0.01) {
      if (std::abs(X - lo) < 2e-3 || std::abs(X - hi) < 2e-3) continue;  // the shadow's edges
      const bool hidden = X >= lo && X <= hi;
      const Vec3 up = Vec3::UnitZ();
      const ViewResult r = tester.Test(0, Vec3(X, 0, 0), &up);
      EXPECT_EQ(r == ViewResult::kOccluded, hidden)
          << sample.label << " X=" << X << " " << ViewResultName(r);
      ++checked;
    }
  }
  EXPECT_GT(checked, 900);
}

}  // namespace
}  // namespace pandora
