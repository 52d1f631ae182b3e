#include "suggest/propose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/rig/calibration.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "tests/temp_dir.h"

namespace pandora {
namespace {

// A 6 x 4 m room with a pillar and a 2 x 1.5 x 1.5 m region round its middle.
Scene Room() {
  return ParseScene(R"({"objects": [
    {"name": "room", "room": {"footprint": [[-3, -2], [3, -2], [3, 2], [-3, 2]], "height": 3}},
    {"name": "pillar", "box": {"size": [0.3, 0.3, 3]}, "position": [0, 0.9, 1.5], "solid": true}],
    "rigs": [{"name": "r", "cameras": [{"id": "c", "position": [2.5, 1.5, 2.5],
      "look_at": [0, 0, 1], "resolution": [640, 480], "hfov_deg": 60}]}],
    "study": {"region": {"box": {"min": [-1, -0.75, 0.2], "max": [1, 0.75, 1.7]}}}})",
                    "room.json");
}

ProposeOptions Options(const Scene& scene) {
  ProposeOptions o;
  ProposeLens lens;
  lens.intrinsics = scene.rigs[0].cameras[0].model.intrinsics();
  lens.hfov_deg = 60;
  o.lenses = {lens};
  o.terms = {ProposeTerm()};
  o.terms[0].k = 2;
  o.iterations = 20000;
  return o;
}

TEST(Propose, TheAnnealingFindsTheBruteForceOptimum) {
  const Scene scene = Room();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 400, {}, true, 3);
  ProposeOptions o = Options(scene);
  // Ten mounts round the walls at 2.4 m, each aimed at the targets' centre only: 120 layouts of 3.
  o.aims = 0;
  for (const MountPoint& m : WallMounts(scene, {2.4}, 1.9, 0.1)) o.mounts.push_back(m);
  ASSERT_GE(o.mounts.size(), 9u);
  o.mounts.resize(std::min<std::size_t>(o.mounts.size(), 10));
  // A narrow lens: no camera sees the whole region, so which three matters.
  o.lenses[0].hfov_deg = 35;
  o.lenses[0].intrinsics.fx = o.lenses[0].intrinsics.fy =
      FocalFromHfov(35 * kRadPerDeg, 640, LensModel::kPinhole);
  o.cameras = 3;
  o.proposals = 1;
  const ProposeResult r = Propose(scene, *caster, {}, targets, o);
  ASSERT_EQ(r.candidates.size(), o.mounts.size());
  const int n = int(r.candidates.size());
  double best = -1;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      for (int c = b + 1; c < n; ++c) {
        const std::vector<Camera> cams = {r.candidates[a], r.candidates[b], r.candidates[c]};
        best = std::max(best, ScoreCameras(scene, *caster, {}, targets, cams, o.terms).objective);
      }
  ASSERT_EQ(r.proposals.size(), 1u);
  EXPECT_DOUBLE_EQ(r.proposals[0].objective, best);
  EXPECT_GT(best, 0.3);  // a real choice: neither nothing nor everything
  EXPECT_LT(best, 0.999);
  // The proposal's rig, judged by suggest's exact evaluation, has the same share.
  const Rig rig = ProposalRig(r, r.proposals[0], "p");
  Objective coverage2;
  coverage2.kind = ObjectiveKind::kCoverage;
  coverage2.k = 2;
  const Metrics m = EvaluateExact(scene, rig, *caster, targets, coverage2);
  EXPECT_DOUBLE_EQ(m.coverage_k, r.proposals[0].coverage_k);
  EXPECT_EQ(rig.cameras[0].id, "p_1");
}

TEST(Propose, NMinusOneIsTheWorstSingleFailure) {
  const Scene scene = Room();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 300, {}, true, 5);
  ProposeOptions o = Options(scene);
  o.terms[0].n1 = true;
  o.mounts = WallMounts(scene, {2.2, 2.6}, 0.8, 0.1);
  o.cameras = 5;
  o.proposals = 3;
  const ProposeResult r = Propose(scene, *caster, {}, targets, o);
  ASSERT_EQ(r.proposals.size(), 3u);
  std::set<std::vector<int>> layouts;
  for (const Proposal& p : r.proposals) {
    const Rig rig = ProposalRig(r, p, "p");
    double worst = 1;
    for (std::size_t f = 0; f < rig.cameras.size(); ++f) {
      std::vector<Camera> rest = rig.cameras;
      rest.erase(rest.begin() + std::ptrdiff_t(f));
      std::vector<ProposeTerm> k2 = o.terms;
      k2[0].n1 = false;
      worst = std::min(worst, ScoreCameras(scene, *caster, {}, targets, rest, k2).coverage_k);
    }
    EXPECT_DOUBLE_EQ(p.n1, worst);
    EXPECT_DOUBLE_EQ(p.objective, p.n1);
    std::vector<int> sorted = p.candidates;
    std::sort(sorted.begin(), sorted.end());
    layouts.insert(sorted);
  }
  EXPECT_EQ(layouts.size(), 3u);  // three different layouts
  EXPECT_GE(r.proposals[0].objective, r.proposals[2].objective);
}

TEST(Propose, ABudgetBoundsThePrice) {
  const Scene scene = Room();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 200, {}, true, 7);
  ProposeOptions o = Options(scene);
  ProposeLens cheap = o.lenses[0], dear = o.lenses[0];
  cheap.price = 300, dear.price = 1000;
  dear.hfov_deg = 90;
  dear.intrinsics.fx = dear.intrinsics.fy =
      FocalFromHfov(90 * kRadPerDeg, dear.intrinsics.width, dear.intrinsics.model);
  o.lenses = {cheap, dear};
  o.mounts = WallMounts(scene, {2.4}, 1.0, 0.1);
  o.cameras = 6;
  o.budget = 2500;
  o.proposals = 1;
  const ProposeResult r = Propose(scene, *caster, {}, targets, o);
  EXPECT_LE(r.proposals[0].price, 2500);
  EXPECT_GE(r.proposals[0].candidates.size(), 3u);
}

TEST(Propose, TheCatalogueGivesEveryZoom) {
  testing::TempDir dir;
  const std::string path = dir.File("cameras.json");
  std::ofstream(path) << R"({"models": [
    {"name": "fixed", "resolution": [2048, 1536], "hfov_deg": 66, "price": 2500},
    {"name": "zoom", "resolution": [1920, 1080], "focal_mm": [4, 8], "sensor_width_mm": 5.6,
     "price": 900, "distortion": {"model": "brown_conrady", "k1": -0.05}}]})";
  const std::vector<ProposeLens> lenses = ReadCameraCatalogue(path, 3);
  ASSERT_EQ(lenses.size(), 4u);
  EXPECT_EQ(lenses[0].model, "fixed");
  EXPECT_NEAR(lenses[0].intrinsics.fx, 1024 / std::tan(33 * kRadPerDeg), 1e-9);
  for (int z = 0; z < 3; ++z) {
    const double f = 4 + 2 * z;
    EXPECT_NEAR(lenses[1 + z].hfov_deg, 2 * std::atan(5.6 / (2 * f)) * kDegPerRad, 1e-9);
    EXPECT_NEAR(lenses[1 + z].intrinsics.fx, f * 1920 / 5.6, 1e-9);
    EXPECT_EQ(lenses[1 + z].intrinsics.model, LensModel::kBrownConrady);
    EXPECT_DOUBLE_EQ(lenses[1 + z].price, 900);
  }
  std::ofstream(path) << R"({"models": [{"name": "x", "resolution": [640, 480]}]})";
  try {
    ReadCameraCatalogue(path);
    ADD_FAILURE() << "no lens accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("$.models[0]"), std::string::npos) << e.what();
  }
}

// A weighted objective with a density term: each proposal's objective is the weighted sum of its
// terms, and each term equals the same layout judged by that term alone; the parser's forms.
TEST(Propose, WeightedTermsAndDensities) {
  const Scene scene = Room();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 300, {}, true, 9);
  ProposeOptions o = Options(scene);
  o.terms = ParseProposeObjective("0.7*coverage2+0.3*coverage1@250", scene);
  ASSERT_EQ(o.terms.size(), 2u);
  EXPECT_DOUBLE_EQ(o.terms[1].min_px_per_m, 250);
  EXPECT_EQ(o.terms[1].k, 1);
  o.mounts = WallMounts(scene, {2.4}, 0.8, 0.1);
  o.cameras = 4;
  o.proposals = 1;
  const ProposeResult r = Propose(scene, *caster, {}, targets, o);
  const Proposal& p = r.proposals[0];
  ASSERT_EQ(p.terms.size(), 2u);
  EXPECT_NEAR(p.objective, 0.7 * p.terms[0] + 0.3 * p.terms[1], 1e-12);
  const Rig rig = ProposalRig(r, p, "p");
  for (std::size_t t = 0; t < 2; ++t) {
    std::vector<ProposeTerm> alone = {o.terms[t]};
    alone[0].weight = 1;
    EXPECT_DOUBLE_EQ(ScoreCameras(scene, *caster, {}, targets, rig.cameras, alone).objective,
                     p.terms[t]);
  }
  // The density term by hand: points seen by a camera at >= 250 px/m.
  const double scale = scene.ContentBounds().diagonal();
  const VisibilityTester tester(rig.cameras, *caster, scale);
  int dense = 0;
  for (const TargetPoint& t : targets) {
    bool any = false;
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
      Mat23 J;
      any |= tester.Test(int(c), t.p, nullptr, &J) == ViewResult::kSeen && PixelDensity(J) >= 250;
    }
    dense += any;
  }
  EXPECT_DOUBLE_EQ(p.terms[1], double(dense) / targets.size());
  EXPECT_GT(p.terms[1], 0.05);
  EXPECT_LT(p.terms[1], 0.999);
  EXPECT_DOUBLE_EQ(ParseProposeObjective("coverage3-n1@identification", scene)[0].min_px_per_m,
                   250);
  EXPECT_TRUE(ParseProposeObjective("coverage3-n1@identification", scene)[0].n1);
  for (const char* bad :
       {"sigma-mean", "coverage0", "2*coverage3+", "coverage2@far", "-1*coverage2"})
    EXPECT_THROW(ParseProposeObjective(bad, scene), InputError) << bad;
}

// The calibration term of fixed cameras is the calibration simulation's own verdict: its weakest
// spanning-tree link over min_shared (at most 1), on the same poses.
TEST(Propose, CalibrationTermIsTheSimulationsWeakestLink) {
  const Scene scene = ParseScene(R"({"objects": [
    {"name": "room", "room": {"footprint": [[-3, -2], [3, -2], [3, 2], [-3, 2]], "height": 3}}],
    "rigs": [{"name": "r", "cameras": [
      {"id": "a", "position": [2.7, 1.7, 2.5], "look_at": [0, 0, 1], "resolution": [640, 480], "hfov_deg": 60},
      {"id": "b", "position": [0, 1.85, 2.5], "look_at": [0, 0, 1], "resolution": [640, 480], "hfov_deg": 60},
      {"id": "c", "position": [-2.7, 1.7, 2.5], "look_at": [0, 0, 1], "resolution": [640, 480], "hfov_deg": 60}]}],
    "study": {"region": {"box": {"min": [-1, -0.75, 0.5], "max": [1, 0.75, 1.7]}},
      "calibration": {"target": "board", "samples": 600, "seed": 3, "min_shared": 500,
        "board": {"squares": [7, 5], "square_m": 0.05}}}})",
                                 "cal.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 100, {}, true, 1);
  const std::vector<ProposeTerm> terms = ParseProposeObjective("calibration", scene);
  const Proposal p = ScoreCameras(scene, *caster, {}, targets, scene.rigs[0].cameras, terms);
  const CalibrationResult sim =
      SimulateCalibration(scene, scene.rigs[0], *caster, *scene.study.calibration);
  // Three cameras: the maximum spanning tree keeps the two strongest pairs; its weakest edge is
  // the middle shared count (min_shared 500 of 600 poses keeps it below 1).
  const std::int64_t ab = sim.shared[0][1], ac = sim.shared[0][2], bc = sim.shared[1][2];
  const std::int64_t weakest = ab + ac + bc - std::min({ab, ac, bc}) - std::max({ab, ac, bc});
  ASSERT_GT(weakest, 0);
  EXPECT_DOUBLE_EQ(p.terms[0], std::min(1.0, double(weakest) / 500));
  EXPECT_LT(p.terms[0], 1);
  const Scene plain = Room();  // no "calibration" in its study
  const auto plain_caster = MakeEmbreeRayCaster(plain.AllTriangles());
  EXPECT_THROW(ScoreCameras(plain, *plain_caster, {}, targets, plain.rigs[0].cameras,
                            ParseProposeObjective("calibration", plain)),
               InputError);
}

}  // namespace
}  // namespace pandora
