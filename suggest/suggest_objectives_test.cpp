// The robustness objectives of suggest (issue 12): N-1 coverage equals disabling each camera and
// counting again; the calibration objective equals the calibration simulation's graph and an
// independent threshold search for the chain's strength; suggestions with either improve it and
// their "after" is what a fresh evaluation of the returned rig gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <numeric>
#include <random>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/calibration.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "suggest/suggest.h"
#include "suggest/suggest_internal.h"

namespace pandora {
namespace {

// Five cameras on a ring around a 1.2 m region with a pillar beside it. c5 looks past the region
// (`c5_look`), so it sees part of it, or none of it.
std::string SceneText(const std::string& c5_look, const std::string& calibration = "") {
  std::string t = R"({"pandora": 1, "units": "m",
  "objects": [
    {"name": "floor", "box": {"size": [8, 8, 0.1]}, "position": [0, 0, -0.05], "solid": true},
    {"name": "pillar", "box": {"size": [0.3, 0.3, 1.5]}, "position": [1.4, 1.4, 0.75], "solid": true}],
  "rigs": [{"name": "ring", "cameras": [
    {"id": "c1", "position": [4, 0, 2], "look_at": [0, 0, 0.5], "resolution": [640, 480], "hfov_deg": 50},
    {"id": "c2", "position": [0, 4, 2], "look_at": [0, 0, 0.5], "resolution": [640, 480], "hfov_deg": 50},
    {"id": "c3", "position": [-4, 0, 2], "look_at": [0, 0, 0.5], "resolution": [640, 480], "hfov_deg": 50},
    {"id": "c4", "position": [0, -4, 2], "look_at": [1.3, 0, 0.5], "resolution": [640, 480], "hfov_deg": 35},
    {"id": "c5", "position": [2.8, -2.8, 2], "look_at": )" +
                  c5_look + R"(, "resolution": [640, 480], "hfov_deg": 40}]}],
  "study": {"region": {"box": {"min": [-0.6, -0.6, 0], "max": [0.6, 0.6, 1.2]}}, "voxel_size": 0.05)" +
                  (calibration.empty() ? "" : ", \"calibration\": " + calibration) + "}}";
  return t;
}

struct Fixture {
  Scene scene;
  std::unique_ptr<RayCaster> caster;
  std::vector<TargetPoint> targets;
  explicit Fixture(const std::string& text, int points = 600)
      : scene(ParseScene(text, "objectives.json")) {
    caster = MakeEmbreeRayCaster(scene.AllTriangles());
    targets = SampleTargets(scene, points, {}, false, 11);
  }
  const Rig& rig() const { return scene.rigs[0]; }
};

// The brute force: disable each enabled camera in turn, count again, keep the worst.
std::pair<double, std::string> BruteForceN1(const Fixture& f, const Rig& rig, int k) {
  Objective cover;
  cover.k = k;
  double worst = 2;
  std::string id;
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    if (!rig.cameras[c].enabled) continue;
    Rig without = rig;
    without.cameras[c].enabled = false;
    const double share = EvaluateExact(f.scene, without, *f.caster, f.targets, cover).coverage_k;
    if (share < worst) {
      worst = share;
      id = rig.cameras[c].id;
    }
  }
  return {worst, id};
}

TEST(SuggestObjectives, NamesParseAndRoundTrip) {
  ASSERT_TRUE(ParseObjective("coverage3-n1"));
  EXPECT_EQ(ParseObjective("coverage3-n1")->kind, ObjectiveKind::kCoverageN1);
  EXPECT_EQ(ParseObjective("coverage3-n1")->k, 3);
  EXPECT_EQ(ParseObjective("coverage-n1")->k, 2);
  EXPECT_EQ(ObjectiveName(*ParseObjective("coverage-n1")), "coverage2-n1");
  EXPECT_EQ(ObjectiveName(*ParseObjective("coverage5-n1")), "coverage5-n1");
  EXPECT_EQ(ParseObjective("calibration")->kind, ObjectiveKind::kCalibration);
  EXPECT_EQ(ObjectiveName(*ParseObjective("calibration")), "calibration");
  EXPECT_TRUE(ObjectiveHigherIsBetter(*ParseObjective("coverage3-n1")));
  EXPECT_TRUE(ObjectiveHigherIsBetter(*ParseObjective("calibration")));
  for (const char* bad :
       {"sigma-mean-n1", "coverage0-n1", "-n1", "coverage3-n2", "n1", "calibrations"})
    EXPECT_FALSE(ParseObjective(bad)) << bad;
}

// N-1 from the counts equals disabling each camera and counting again, for the rig as placed and
// for selected cameras moved to random poses (their views combine with the fixed cameras' sets).
TEST(SuggestObjectives, N1EqualsDisablingEachCameraAndCountingAgain) {
  Fixture f(SceneText("[2, 0.5, 0.4]"));
  for (int k : {1, 2, 3}) {
    Objective o;
    o.kind = ObjectiveKind::kCoverageN1;
    o.k = k;
    const Metrics m = EvaluateExact(f.scene, f.rig(), *f.caster, f.targets, o);
    ASSERT_TRUE(m.n1);
    const auto [share, id] = BruteForceN1(f, f.rig(), k);
    EXPECT_EQ(m.n1->coverage_k, share) << "k " << k;
    EXPECT_EQ(m.objective, share);
    EXPECT_EQ(m.n1->worst_camera, id) << "k " << k;
    EXPECT_LE(m.objective, m.coverage_k);
  }
  // The shares are not trivial: k = 3 loses points with any of c1..c4.
  Objective o3 = *ParseObjective("coverage3-n1");
  const Metrics m3 = EvaluateExact(f.scene, f.rig(), *f.caster, f.targets, o3);
  EXPECT_GT(m3.coverage_k - m3.n1->coverage_k, 0.05);
  EXPECT_GT(m3.n1->coverage_k, 0.05);

  const std::vector<int> sel{1, 4};
  suggest_detail::ExactEvaluator ev(f.scene, f.rig(), *f.caster, f.targets, o3, sel);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    Rig moved = f.rig();
    std::vector<Eigen::Isometry3d> poses;
    std::vector<suggest_detail::CameraView> views(sel.size());
    std::vector<const suggest_detail::CameraView*> ptrs;
    for (std::size_t c = 0; c < sel.size(); ++c) {
      Eigen::Isometry3d p = f.rig().cameras[sel[c]].world_from_camera;
      p.translation() += 0.2 * Vec3(n01(rng), n01(rng), n01(rng));
      p.linear() = p.linear() * Eigen::AngleAxisd(0.15 * n01(rng),
                                                  Vec3(n01(rng), n01(rng), n01(rng)).normalized())
                                    .toRotationMatrix();
      poses.push_back(p);
      moved.cameras[sel[c]].world_from_camera = p;
      views[c] = ev.View(static_cast<int>(c), p);
      ptrs.push_back(&views[c]);
    }
    const Metrics a = ev.Evaluate(poses);
    const Metrics fast = ev.Combine(ptrs, /*objective_only=*/true);
    const auto [share, id] = BruteForceN1(f, moved, 3);
    ASSERT_TRUE(a.n1 && fast.n1);
    EXPECT_EQ(a.n1->coverage_k, share) << "trial " << trial;
    EXPECT_EQ(a.n1->worst_camera, id);
    EXPECT_EQ(fast.objective, a.objective);
    EXPECT_EQ(fast.n1->worst_camera, id);
  }
}

// The chain's strength by an independent route: the largest threshold w whose edges (shared >= w)
// connect every camera (union-find at each candidate threshold).
std::int64_t StrengthByThresholds(const std::vector<std::vector<std::int64_t>>& shared) {
  const std::size_t n = shared.size();
  if (n == 1) return shared[0][0];
  std::vector<std::int64_t> candidates;
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) candidates.push_back(shared[a][b]);
  std::sort(candidates.rbegin(), candidates.rend());
  for (std::int64_t w : candidates) {
    std::vector<std::size_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0);
    std::function<std::size_t(std::size_t)> find = [&](std::size_t x) {
      return parent[x] == x ? x : parent[x] = find(parent[x]);
    };
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a + 1; b < n; ++b)
        if (shared[a][b] >= w) parent[find(a)] = find(b);
    bool one = true;
    for (std::size_t a = 1; a < n; ++a) one = one && find(a) == find(0);
    if (one) return w;
  }
  return 0;
}

TEST(SuggestObjectives, CalibrationEqualsTheSimulationAndAThresholdSearch) {
  const std::string wand = R"({"target": "wand", "samples": 600, "seed": 3, "min_shared": 15})";
  for (const char* look : {"[0, 0, 0.6]", "[2, 0.5, 0.4]", "[6, 2, 2.5]"}) {
    Fixture f(SceneText(look, wand));
    const Objective o = *ParseObjective("calibration");
    const Metrics m = EvaluateExact(f.scene, f.rig(), *f.caster, f.targets, o);
    ASSERT_TRUE(m.calibration);
    const CalibrationResult sim =
        SimulateCalibration(f.scene, f.rig(), *f.caster, *f.scene.study.calibration);
    EXPECT_EQ(m.calibration->poses, sim.poses);
    EXPECT_EQ(m.calibration->weakest, StrengthByThresholds(sim.shared)) << look;
    EXPECT_EQ(m.objective, double(m.calibration->weakest));
    EXPECT_EQ(m.calibration->components, static_cast<int>(sim.graph.components.size())) << look;
    EXPECT_EQ(m.calibration->uncalibratable, static_cast<int>(sim.graph.uncalibratable.size()))
        << look;
    // Calibratable with the rest exactly when the chain is at least min_shared strong.
    EXPECT_EQ(sim.calibratable, m.calibration->weakest >= 15) << look;
    if (sim.calibratable) {
      EXPECT_EQ(m.calibration->weakest, sim.graph.weakest_links.front().shared);
    }
    if (std::string(look) == "[6, 2, 2.5]") {  // c5 looks away: the known disconnected camera
      EXPECT_EQ(m.calibration->weakest, 0);
      EXPECT_FALSE(sim.calibratable);
      EXPECT_GE(m.calibration->uncalibratable, 1);
      EXPECT_TRUE(m.calibration->weakest_a == "c5" || m.calibration->weakest_b == "c5");
    }
  }
}

TEST(SuggestObjectives, CalibrationWithoutTheStudyTargetIsAnInputError) {
  Fixture f(SceneText("[0, 0, 0.6]"));
  try {
    EvaluateExact(f.scene, f.rig(), *f.caster, f.targets, *ParseObjective("calibration"));
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("$.study.calibration"), std::string::npos) << e.what();
  }
}

SuggestOptions Select(int camera, double move, double rotate_deg, const std::string& objective) {
  SuggestOptions o;
  o.cameras = {camera};
  CameraLimits l;
  l.max_move = move;
  l.max_rotate_deg = rotate_deg;
  o.limits = {l};
  o.objective = *ParseObjective(objective);
  o.screening_candidates = 60;
  return o;
}

Rig Moved(const Rig& rig, const Suggestion& s) {
  Rig r = rig;
  for (const CameraChange& c : s.cameras) r.cameras[c.index].world_from_camera = c.after;
  return r;
}

// A camera that looks away from the calibration volume is turned back until it links to the rest;
// the simulation of the returned rig agrees.
TEST(SuggestObjectives, SuggestLinksACameraThatCannotBeCalibrated) {
  Fixture f(SceneText("[4.5, 1.5, 1.2]",
                      R"({"target": "wand", "samples": 600, "seed": 3, "min_shared": 15})"));
  const CalibrationResult start =
      SimulateCalibration(f.scene, f.rig(), *f.caster, *f.scene.study.calibration);
  ASSERT_FALSE(start.calibratable);
  const SuggestOptions o = Select(4, 0.3, 45, "calibration");
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  ASSERT_TRUE(s.improved) << s.message;
  ASSERT_TRUE(s.after.calibration);
  EXPECT_GE(s.after.calibration->weakest, 15);
  EXPECT_EQ(s.after.calibration->uncalibratable, 0);
  EXPECT_LE(s.cameras[0].rotate_deg, 45 + 1e-6);
  EXPECT_LE(s.cameras[0].move_m, 0.3 * (1 + 1e-9));
  // The wand's poses do not depend on the rig: the simulation of the new rig is the same graph.
  const CalibrationResult after =
      SimulateCalibration(f.scene, Moved(f.rig(), s), *f.caster, *f.scene.study.calibration);
  EXPECT_TRUE(after.calibratable);
  EXPECT_EQ(s.after.calibration->weakest, StrengthByThresholds(after.shared));
  const Metrics check =
      EvaluateExact(f.scene, Moved(f.rig(), s), *f.caster, f.targets, o.objective);
  EXPECT_EQ(check.objective, s.after.objective);
}

// The worst single failure is made less bad by turning the fifth camera onto the region; "after"
// equals the brute force on the returned rig.
TEST(SuggestObjectives, SuggestRaisesN1Coverage) {
  Fixture f(SceneText("[2, 0.5, 0.4]"));
  const SuggestOptions o = Select(4, 0.3, 30, "coverage3-n1");
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  ASSERT_TRUE(s.improved) << s.message;
  ASSERT_TRUE(s.before.n1 && s.after.n1);
  EXPECT_GT(s.after.n1->coverage_k, s.before.n1->coverage_k + 0.1);
  const auto [share, id] = BruteForceN1(f, Moved(f.rig(), s), 3);
  EXPECT_EQ(s.after.n1->coverage_k, share);
  EXPECT_EQ(s.after.n1->worst_camera, id);
  EXPECT_LE(s.cameras[0].rotate_deg, 30 + 1e-6);
}

}  // namespace
}  // namespace pandora
