// Suggesting over time (docs/time.md): target points on a moving person at every time sample, each
// tested against its own sample's scene.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/motion.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "suggest/suggest.h"

namespace pandora {
namespace {

// A person walks behind a screen: at t = 0 camera "a" sees them, at t = 4 the screen hides them
// from "a"; camera "b" looks 70 degrees away from their path and may turn.
Scene TestScene() {
  return ParseScene(R"({"pandora": 1,
    "objects": [
      {"name": "floor", "plane": {"size": [10, 10]}},
      {"name": "screen", "box": {"size": [0.1, 2.0, 2.2]}, "position": [1.0, 0, 1.1]},
      {"name": "body", "group": "p", "capsule": {"radius": 0.2, "length": 1.0}, "position": [0, -2, 0.8], "solid": true}],
    "motions": {"p": {"keyframes": [{"t": 0}, {"t": 4, "move": [2.0, 2.0, 0]}]}},
    "rigs": [{"name": "r", "cameras": [
      {"id": "a", "position": [-3, 0, 1.5], "look_at": [1, 0, 0.8], "resolution": [640, 480], "hfov_deg": 80},
      {"id": "b", "position": [3, -2.5, 1.5], "look_at": [3.58, -0.58, 1.0], "resolution": [640, 480], "hfov_deg": 60}]}],
    "study": {"region": {"box": {"min": [-2, -3, 0], "max": [3, 3, 2]}}, "voxel_size": 0.2,
              "time": {"samples": 3, "min_cameras": 1},
              "targets": {"objects": ["p"], "points": 300, "seed": 2}}})",
                    "suggest_time.json");
}

TEST(SuggestOverTime, ExactEvaluationTestsEachPointAgainstItsSample) {
  const Scene scene = TestScene();
  const Rig& rig = scene.rigs[0];
  const std::vector<TimeSample> samples = scene.TimeSamples();
  ASSERT_EQ(samples.size(), 3u);
  const std::vector<TargetPoint> targets = SampleTimeTargets(scene, samples, 300, 2);
  ASSERT_EQ(targets.size(), 900u);
  const auto parts = MakeSceneParts(scene);
  std::vector<std::unique_ptr<RayCaster>> casters;
  std::vector<const RayCaster*> pointers;
  for (const TimeSample& s : samples) {
    casters.push_back(parts->At(PartTransforms(scene, s)));
    pointers.push_back(casters.back().get());
  }
  Objective coverage;
  coverage.kind = ObjectiveKind::kCoverage;
  coverage.k = 1;
  const auto static_caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Metrics m = EvaluateExact(scene, rig, *static_caster, targets, coverage, pointers);
  // Brute force: each point against its sample's scene rebuilt from scratch.
  int seen = 0;
  std::vector<int> per_sample(3, 0);
  for (const TargetPoint& t : targets) {
    const Scene at = SceneAtSample(scene, samples[t.sample]);
    static thread_local std::vector<std::unique_ptr<RayCaster>> fresh;
    if (fresh.size() < 3) fresh.resize(3);
    if (!fresh[t.sample]) fresh[t.sample] = MakeEmbreeRayCaster(at.AllTriangles());
    const VisibilityTester tester(rig.cameras, *fresh[t.sample], scene.ContentBounds().diagonal());
    bool any = false;
    for (int c = 0; c < 2; ++c) {
      any |= tester.Test(c, t.p, &*t.normal) == ViewResult::kSeen;
    }
    seen += any;
    per_sample[t.sample] += any;
  }
  EXPECT_DOUBLE_EQ(m.coverage_k, seen / 900.0);
  // The screen hides the person from "a" at the last sample, not at the first.
  EXPECT_GT(per_sample[0], 100);
  EXPECT_LT(per_sample[2], per_sample[0] / 4);

  // Suggesting for "b" (free to turn) over time raises the share seen.
  SuggestOptions options;
  options.cameras = {1};
  CameraLimits limits;
  limits.max_move = 0.5;
  limits.max_rotate_deg = 120;
  options.limits = {limits};
  options.objective = coverage;
  options.sample_casters = pointers;
  options.scene_path = scene.path;
  const Suggestion s = Suggest(scene, rig, *static_caster, targets, options);
  EXPECT_GT(s.after.objective, s.before.objective + 0.1);
  EXPECT_DOUBLE_EQ(s.before.objective, m.coverage_k);

  // No targets in the study: a clear error.
  Scene bare = scene;
  bare.study.targets.reset();
  try {
    SampleTimeTargets(bare, samples, 10, 1);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "$.study.targets");
  }
}

}  // namespace
}  // namespace pandora
