// The suggestion against the random-search baselines (app/report/suggest_comparison.h).
#include "app/report/suggest_comparison.h"

#include <gtest/gtest.h>

#include <limits>
#include <sstream>

#include "analysis/geometry/ray_caster.h"
#include "tests/fixtures.h"

namespace pandora::report {
namespace {

TEST(SuggestComparison, TimeToReach) {
  const std::vector<TracePoint> rising{{0.1, 10, 0.5}, {0.2, 20, 0.7}, {0.4, 30, 0.9}};
  EXPECT_EQ(TimeToReach(rising, 0.7, true), 0.2);
  EXPECT_EQ(TimeToReach(rising, 0.5, true), 0.1);
  EXPECT_EQ(TimeToReach(rising, 0.95, true), std::numeric_limits<double>::infinity());
  const std::vector<TracePoint> falling{{0.1, 10, 5}, {0.3, 20, 3}, {0.5, 30, 2}};
  EXPECT_EQ(TimeToReach(falling, 3, false), 0.3);
  EXPECT_EQ(TimeToReach(falling, 1, false), std::numeric_limits<double>::infinity());
  EXPECT_EQ(TimeToReach({}, 0, true), std::numeric_limits<double>::infinity());
}

TEST(SuggestComparison, SameBudgetTracesAndOutputs) {
  // Four cameras round the region; c3 looks away, so coverage >= 4 has room to improve.
  Scene scene = testing::BoxRoom(Vec3(6, 6, 3), 0.1);
  Rig rig = testing::RingRig(4, 2.0, 1.2, Vec3(0, 0, 0.5));
  rig.cameras[3] =
      testing::TestCamera("c3", rig.cameras[3].world_from_camera.translation(), Vec3(0, -2, 0.5));
  scene.rigs = {rig};
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 150, {}, false, 3);
  SuggestOptions options;
  options.objective = *ParseObjective("coverage4");
  options.cameras = {3};
  CameraLimits limits;
  limits.max_move = 0.3;
  limits.max_rotate_deg = 40;
  options.limits = {limits};
  options.screening_candidates = 20;
  options.outer_iterations = 2;
  const Suggestion s = Suggest(scene, rig, *caster, targets, options);
  ASSERT_GT(s.evaluations, 0);

  const SuggestComparison c =
      CompareWithBaselines(scene, rig, *caster, targets, options, s, 5, 0.9);
  ASSERT_EQ(c.runs.size(), 3u);
  EXPECT_EQ(c.runs[0].name, "ceres");
  EXPECT_EQ(c.runs[0].result.after.objective, s.after.objective);
  std::size_t points = 0;
  for (const SuggestRun& run : c.runs) {
    points += run.result.trace.size();
    // The same evaluation budget, and a best-so-far trace that never gets worse.
    if (run.name != "ceres") {
      EXPECT_LE(run.result.evaluations, s.evaluations) << run.name;
    }
    for (std::size_t i = 1; i < run.result.trace.size(); ++i)
      EXPECT_GE(run.result.trace[i].objective, run.result.trace[i - 1].objective) << run.name;
  }
  // One CSV line per trace point under the header, each starting with its method.
  std::istringstream csv(c.csv);
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "method,seconds,evaluations,best_objective");
  std::size_t lines = 0;
  while (std::getline(csv, line)) {
    ++lines;
    EXPECT_TRUE(line.rfind("ceres,", 0) == 0 || line.rfind("random,", 0) == 0 ||
                line.rfind("random_adaptive,", 0) == 0)
        << line;
  }
  EXPECT_EQ(lines, points);
  // The plot has the three methods and the original poses' line; the table a row per method.
  for (const char* label : {"screening + Ceres nudge", "random search, fixed step",
                            "random search, 1/5 rule", "original poses"})
    EXPECT_NE(c.svg.find(label), std::string::npos) << label;
  for (const SuggestRun& run : c.runs)
    EXPECT_NE(c.table.find(run.label), std::string::npos) << run.label;
}

}  // namespace
}  // namespace pandora::report
