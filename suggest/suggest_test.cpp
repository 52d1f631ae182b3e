// Suggest and accept (issue 5): recovery, limits and mounts, stability cases, the exact evaluation
// against a direct count, and the accept cycle on real files.
#include "suggest/suggest.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/sha256.h"
#include "analysis/util/units.h"
#include "suggest/suggest_internal.h"
#include "suggest/suggestion_file.h"

namespace pandora {
namespace {

namespace fs = std::filesystem;

std::string Num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string Vec(double x, double y, double z, double s) {
  return "[" + Num(x * s) + ", " + Num(y * s) + ", " + Num(z * s) + "]";
}

// Four cameras on a ring around a 1 m region with a pillar beside it; every length times `s`.
// Camera c4 looks past the region (26.6 degrees off, half its 50 degree field of view), so a nudge
// can bring it back. `c4_look` overrides where c4 looks (unscaled).
std::string SceneText(double s, Vec3 c4_look = Vec3(2.0, 0.0, 0.5),
                      const std::string& units = "m") {
  std::string t = "{\n  \"pandora\": 1,\n  \"units\": \"" + units + "\",\n  \"objects\": [\n";
  t += "    {\"name\": \"floor\", \"box\": {\"size\": " + Vec(8, 8, 0.1, s) +
       "}, \"position\": " + Vec(0, 0, -0.05, s) + ", \"solid\": true},\n";
  t += "    {\"name\": \"pillar\", \"box\": {\"size\": " + Vec(0.3, 0.3, 1.5, s) +
       "}, \"position\": " + Vec(1.6, 1.6, 0.75, s) + ", \"solid\": true}\n  ],\n";
  t += "  \"rigs\": [\n    {\"name\": \"ring\", \"cameras\": [\n";
  const double pos[4][2] = {{4, 0}, {0, 4}, {-4, 0}, {0, -4}};
  for (int c = 0; c < 4; ++c) {
    const Vec3 look = c == 3 ? c4_look : Vec3(0, 0, 0.5);
    t += "      {\"id\": \"c" + std::to_string(c + 1) +
         "\", \"position\": " + Vec(pos[c][0], pos[c][1], 2.0, s) +
         ", \"look_at\": " + Vec(look.x(), look.y(), look.z(), s) +
         ", \"resolution\": [640, 480], \"hfov_deg\": 50, \"range\": {\"near\": " + Num(0.2 * s) +
         ", \"far\": " + Num(12 * s) + "}}" + (c < 3 ? ",\n" : "\n");
  }
  t += "    ]}\n  ],\n";
  t += "  \"study\": {\"region\": {\"box\": {\"min\": " + Vec(-0.5, -0.5, 0, s) +
       ", \"max\": " + Vec(0.5, 0.5, 1.0, s) + "}}, \"voxel_size\": " + Num(0.05 * s) + "}\n}\n";
  return t;
}

struct Fixture {
  Scene scene;
  std::unique_ptr<RayCaster> caster;
  std::vector<TargetPoint> targets;
  explicit Fixture(const std::string& text, int points = 300, const std::string& path = "test.json")
      : scene(ParseScene(text, path)) {
    caster = MakeEmbreeRayCaster(scene.AllTriangles());
    targets = SampleTargets(scene, points, {}, false, 7);
  }
  const Rig& rig() const { return scene.rigs[0]; }
};

SuggestOptions Options(std::vector<int> cameras, double move, double rotate_deg) {
  SuggestOptions o;
  o.objective.k = 4;  // the ring's three other cameras see the whole region: c4 decides coverage4
  o.cameras = std::move(cameras);
  CameraLimits l;
  l.max_move = move;
  l.max_rotate_deg = rotate_deg;
  o.limits = {l};
  return o;
}

Rig WithPoses(const Rig& rig, const Suggestion& s) {
  Rig r = rig;
  for (const CameraChange& c : s.cameras) {
    r.cameras[c.index].world_from_camera = c.after;
    Intrinsics k = r.cameras[c.index].model.intrinsics();
    k.fx *= c.focal_scale;
    k.fy *= c.focal_scale;
    if (c.focal_scale != 1.0) r.cameras[c.index].model = CameraModel(k);
  }
  return r;
}

// Checks what every suggestion must satisfy: never worse, the limits hold, and `after` is what the
// exact evaluation of the returned rig gives.
void CheckContract(const Fixture& f, const SuggestOptions& o, const Suggestion& s) {
  const bool higher = ObjectiveHigherIsBetter(o.objective);
  if (s.improved && std::isinf(s.after.objective))  // sigma percentile on an untriangulable point
    EXPECT_LT(s.after.untriangulable, s.before.untriangulable);
  else if (s.improved)
    EXPECT_TRUE(higher ? s.after.objective > s.before.objective
                       : s.after.objective < s.before.objective);
  else
    EXPECT_EQ(s.after.objective, s.before.objective);
  EXPECT_FALSE(s.message.empty());
  ASSERT_EQ(s.cameras.size(), o.cameras.size());
  for (std::size_t c = 0; c < s.cameras.size(); ++c) {
    const CameraLimits& l = o.limits.size() == 1 ? o.limits[0] : o.limits[c];
    const CameraChange& ch = s.cameras[c];
    EXPECT_LE(ch.move_m, l.max_move * (1 + 1e-9) + 1e-15);
    EXPECT_LE(ch.rotate_deg, l.max_rotate_deg + 1e-6);
    EXPECT_NEAR(ch.move_m, (ch.after.translation() - ch.before.translation()).norm(),
                1e-12 * (1 + ch.move_m));
    EXPECT_TRUE(ch.after.matrix().allFinite());
    if (!s.improved) {
      EXPECT_TRUE(ch.after.isApprox(ch.before, 0.0)) << "not improved, yet a pose changed";
    }
  }
  const Metrics check =
      EvaluateExact(f.scene, WithPoses(f.rig(), s), *f.caster, f.targets, o.objective);
  if (o.objective.kind != ObjectiveKind::kMix) {
    EXPECT_DOUBLE_EQ(check.objective, s.after.objective);
    EXPECT_DOUBLE_EQ(check.coverage2, s.after.coverage2);
  }
}

TEST(SuggestObjective, ParsesNamesAndRejectsOthers) {
  ASSERT_TRUE(ParseObjective("coverage2"));
  EXPECT_EQ(ParseObjective("coverage2")->k, 2);
  EXPECT_EQ(ParseObjective("coverage")->k, 2);
  EXPECT_EQ(ParseObjective("coverage3")->k, 3);
  EXPECT_EQ(ParseObjective("sigma-p95")->kind, ObjectiveKind::kSigmaPercentile);
  EXPECT_EQ(ParseObjective("sigma-p95")->percentile, 95);
  EXPECT_EQ(ParseObjective("sigma-mean")->kind, ObjectiveKind::kSigmaMean);
  EXPECT_EQ(ParseObjective("resolution")->kind, ObjectiveKind::kResolution);
  EXPECT_EQ(ParseObjective("mix")->kind, ObjectiveKind::kMix);
  EXPECT_FALSE(ParseObjective("coverage0"));
  EXPECT_FALSE(ParseObjective("coverage2.5"));
  EXPECT_FALSE(ParseObjective("sigma-p0"));
  EXPECT_FALSE(ParseObjective("sigma-p101"));
  EXPECT_FALSE(ParseObjective("covrage2"));
  EXPECT_EQ(ObjectiveName(*ParseObjective("sigma-p90")), "sigma-p90");
  EXPECT_EQ(ObjectiveName(*ParseObjective("coverage4")), "coverage4");
}

TEST(SuggestExact, CoverageEqualsDirectCount) {
  Fixture f(SceneText(1.0), 500);
  Objective o;
  const Metrics m = EvaluateExact(f.scene, f.rig(), *f.caster, f.targets, o);
  const VisibilityTester tester(f.rig().cameras, *f.caster, f.scene.Bounds().diagonal());
  int two = 0, four = 0;
  for (const TargetPoint& t : f.targets) {
    int n = 0;
    for (int c = 0; c < 4; ++c) n += tester.Test(c, t.p) == ViewResult::kSeen;
    two += n >= 2;
    four += n >= 4;
  }
  EXPECT_DOUBLE_EQ(m.coverage2, double(two) / f.targets.size());
  EXPECT_DOUBLE_EQ(m.objective, m.coverage2);
  Objective o4 = o;
  o4.k = 4;
  const double share4 = EvaluateExact(f.scene, f.rig(), *f.caster, f.targets, o4).objective;
  EXPECT_DOUBLE_EQ(share4, double(four) / f.targets.size());
  // Target points are inside the region and outside the solids.
  for (const TargetPoint& t : f.targets) EXPECT_TRUE(f.scene.study.region.box.Contains(t.p));
  EXPECT_GT(share4, 0.1);
  EXPECT_LT(share4, 0.9);  // c4 looks past the region: room for a nudge
}

// The screening's per-camera views, combined, give exactly what Evaluate gives at the same poses
// (every metric, bit for bit: the sums are made in the same order), and the objective-only path
// gives the same objective.
TEST(SuggestExact, CombinedCameraViewsEqualEvaluate) {
  Fixture f(SceneText(1.0), 500);
  const std::vector<int> sel{1, 3};
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (const char* name : {"coverage2", "coverage4", "sigma-mean", "resolution"}) {
    const Objective o = *ParseObjective(name);
    suggest_detail::ExactEvaluator ev(f.scene, f.rig(), *f.caster, f.targets, o, sel);
    for (int trial = 0; trial < 4; ++trial) {
      std::vector<Eigen::Isometry3d> poses;
      std::vector<double> scales;
      std::vector<suggest_detail::CameraView> views(sel.size());
      std::vector<const suggest_detail::CameraView*> ptrs;
      for (std::size_t c = 0; c < sel.size(); ++c) {
        Eigen::Isometry3d p = f.rig().cameras[sel[c]].world_from_camera;
        p.translation() += 0.1 * Vec3(n01(rng), n01(rng), n01(rng));
        p.linear() = p.linear() * Eigen::AngleAxisd(0.1 * n01(rng),
                                                    Vec3(n01(rng), n01(rng), n01(rng)).normalized())
                                      .toRotationMatrix();
        poses.push_back(p);
        scales.push_back(trial == 3 ? 1.2 : 1.0);  // a zoom too
        views[c] = ev.View(static_cast<int>(c), p, scales[c]);
        ptrs.push_back(&views[c]);
      }
      const Metrics a = ev.Evaluate(poses, scales);
      const std::int64_t before = ev.evaluations();
      const Metrics b = ev.Combine(ptrs);
      const Metrics fast = ev.Combine(ptrs, /*objective_only=*/true);
      EXPECT_EQ(ev.evaluations(), before + 2);  // each Combine is one evaluation
      const Metrics full = ev.Summary(ptrs);
      EXPECT_EQ(ev.evaluations(), before + 2);  // Summary is not counted again
      for (const Metrics* m : {&b, &full}) {
        EXPECT_EQ(m->objective, a.objective) << name;
        EXPECT_EQ(m->coverage_k, a.coverage_k);
        EXPECT_EQ(m->coverage2, a.coverage2);
        EXPECT_EQ(m->sigma_mean, a.sigma_mean);
        EXPECT_EQ(m->sigma_p50, a.sigma_p50);
        EXPECT_EQ(m->sigma_p90, a.sigma_p90);
        EXPECT_EQ(m->untriangulable, a.untriangulable);
        EXPECT_EQ(m->min_resolution, a.min_resolution);
      }
      EXPECT_EQ(fast.objective, a.objective) << name;
      EXPECT_EQ(ev.Score(fast), ev.Score(a));
    }
  }
}

TEST(SuggestTargets, SurfacePointsLieOnTheSurfaceWithOutwardNormals) {
  const Scene scene = ParseScene(SceneText(1.0), "test.json");
  const Vec3 centre(1.6, 1.6, 0.75), half(0.15, 0.15, 0.75);
  const std::vector<TargetPoint> t = SampleTargets(scene, 200, {"pillar"}, false, 3);
  ASSERT_EQ(t.size(), 200u);
  int faces[6] = {0, 0, 0, 0, 0, 0};
  for (const TargetPoint& p : t) {
    ASSERT_TRUE(p.normal.has_value());
    const Vec3 d = p.p - centre;
    EXPECT_TRUE((d.cwiseAbs().array() <= half.array() + 1e-9).all()) << p.p.transpose();
    // The normal is the outward axis of the face the point lies on.
    int axis = -1;
    p.normal->cwiseAbs().maxCoeff(&axis);
    EXPECT_NEAR(p.normal->norm(), 1.0, 1e-12);
    EXPECT_NEAR(std::abs((*p.normal)[axis]), 1.0, 1e-12);
    EXPECT_NEAR(std::abs(d[axis]), half[axis], 1e-9) << p.p.transpose();
    EXPECT_GT((*p.normal)[axis] * d[axis], 0.0);
    ++faces[2 * axis + ((*p.normal)[axis] > 0 ? 1 : 0)];
  }
  // Area-weighted: the four tall sides (0.3 x 1.5) get most points, top and bottom (0.3 x 0.3) few.
  for (int f = 0; f < 4; ++f) EXPECT_GT(faces[f], 25) << f;
  EXPECT_LT(faces[4] + faces[5], 30);
  // Half and half with the region; an unknown name is an input error.
  const std::vector<TargetPoint> mixed = SampleTargets(scene, 200, {"pillar"}, true, 3);
  int with_normal = 0;
  for (const TargetPoint& p : mixed) with_normal += p.normal.has_value();
  EXPECT_EQ(with_normal, 100);
  EXPECT_THROW(SampleTargets(scene, 100, {"bed"}, false, 3), InputError);
  EXPECT_THROW(SampleTargets(scene, 0, {}, false, 3), InputError);
}

TEST(Suggest, SurfaceTargetsEndCleanly) {
  Fixture f(SceneText(1.0));
  f.targets = SampleTargets(f.scene, 300, {"pillar"}, false, 3);
  SuggestOptions o = Options({0, 3}, 0.3, 20);
  o.objective.k = 2;
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
}

TEST(Suggest, RecoversTheObjectiveLostByATurnedCamera) {
  // The same rig with c4 looking at the region is the reference; from the turned pose the nudge
  // must recover at least 80% of the lost coverage.
  Fixture good(SceneText(1.0, Vec3(0, 0, 0.5)));
  Fixture f(SceneText(1.0));
  const SuggestOptions o = Options({3}, 0.3, 30);
  const double reference =
      EvaluateExact(good.scene, good.rig(), *good.caster, f.targets, o.objective).objective;
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
  ASSERT_TRUE(s.improved) << s.message;
  const double lost = reference - s.before.objective;
  ASSERT_GT(lost, 0.05);
  EXPECT_GE(s.after.objective - s.before.objective, 0.8 * lost)
      << "before " << s.before.objective << " after " << s.after.objective << " reference "
      << reference;
  EXPECT_GT(s.cameras[0].rotate_deg, 5.0);
  EXPECT_GT(s.iterations, 0);
  EXPECT_FALSE(s.trace.empty());
  for (std::size_t i = 1; i < s.trace.size(); ++i)
    EXPECT_GE(s.trace[i].objective, s.trace[i - 1].objective);
}

TEST(Suggest, TraumaRoomRecoveryFromPerturbedCameras) {
  const Scene scene = LoadScene("examples/trauma_room/scene.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 400, {}, false, 1);
  for (const char* name : {"octagon", "grid4x2"}) {
    const Rig& rig = scene.FindRig(name);
    const std::vector<int> sel{2, 5};
    const Rig perturbed = PerturbCameras(rig, sel, 0.3, 25, 1);
    Objective o;
    const double original = EvaluateExact(scene, rig, *caster, targets, o).objective;
    SuggestOptions opt = Options(sel, 0.4, 30);
    opt.objective = o;  // coverage2, the default
    const Suggestion s = Suggest(scene, perturbed, *caster, targets, opt);
    ASSERT_TRUE(s.improved) << name << ": " << s.message;
    // Recovers the loss: at least the original objective (the nudge often beats the original).
    EXPECT_GE(s.after.objective, original) << name << " perturbed " << s.before.objective;
  }
}

// The screening's best start is polished, never lost (after >= screened >= before); on the trauma
// room's perturbed cameras the result beats the Ceres nudge alone from the current poses.
TEST(Suggest, ScreeningThenPolishBeatsTheNudgeAlone) {
  const Scene scene = LoadScene("examples/trauma_room/scene.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<TargetPoint> targets = SampleTargets(scene, 400, {}, false, 2);
  double gain = 0;
  for (const char* name : {"octagon", "grid4x2"}) {
    const Rig& rig = scene.FindRig(name);
    const std::vector<int> sel{2, 5};
    const Rig perturbed = PerturbCameras(rig, sel, 0.3, 25, 2);
    SuggestOptions opt = Options(sel, 0.4, 30);
    opt.objective = Objective{};  // coverage2
    SuggestOptions alone = opt;
    alone.screening_candidates = 0;
    const Suggestion with = Suggest(scene, perturbed, *caster, targets, opt);
    const Suggestion without = Suggest(scene, perturbed, *caster, targets, alone);
    ASSERT_TRUE(with.improved) << name << ": " << with.message;
    EXPECT_EQ(without.screened, 0);
    EXPECT_GT(with.screened, 3 * 2 * 3 * opt.screening_candidates);  // 3 chains, 2 cameras, 3 radii
    EXPECT_GE(with.screened_objective, with.before.objective);
    EXPECT_GE(with.after.objective, with.screened_objective);
    EXPECT_GE(with.after.objective, without.after.objective) << name;
    gain += with.after.objective - without.after.objective;
    for (std::size_t i = 1; i < with.trace.size(); ++i)
      EXPECT_GE(with.trace[i].objective, with.trace[i - 1].objective) << name;
  }
  EXPECT_GT(gain, 0.0);
}

// SuggestOptions::cancel stops the search where it is and returns the best judged so far (the
// contract holds: `after` is the exact objective at the returned poses); progress rises to 1.
TEST(Suggest, CancelStopsEarlyWithTheBestSoFarAndProgressRises) {
  Fixture f(SceneText(1.0));
  SuggestOptions o = Options({3}, 0.3, 30);
  std::vector<double> fractions;
  o.progress = [&fractions](double v) { fractions.push_back(v); };
  const Suggestion full = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  ASSERT_FALSE(fractions.empty());
  EXPECT_EQ(fractions.back(), 1.0);
  for (std::size_t i = 1; i < fractions.size(); ++i) EXPECT_GE(fractions[i], fractions[i - 1]);
  EXPECT_FALSE(full.stopped);

  // Cancelled before it starts: nothing searched, nothing offered.
  std::atomic<bool> cancel{true};
  o.progress = nullptr;
  o.cancel = &cancel;
  const Suggestion none = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  EXPECT_TRUE(none.stopped);
  EXPECT_FALSE(none.improved);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_LT(none.evaluations, full.evaluations / 10);
  EXPECT_NE(none.message.find("stopped early"), std::string::npos) << none.message;

  // Cancelled once the screening is done: the screening's best comes back, judged and within the
  // limits, without the nudge.
  cancel = false;
  o.progress = [&cancel](double v) {
    if (v >= 0.3) cancel = true;
  };
  const Suggestion screened = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  EXPECT_TRUE(screened.stopped);
  EXPECT_EQ(screened.iterations, 0);
  EXPECT_GT(screened.screened, 0);
  EXPECT_LE(screened.after.objective, full.after.objective);
  CheckContract(f, o, screened);
}

TEST(Suggest, ZeroLimitsReturnTheSamePoses) {
  Fixture f(SceneText(1.0));
  const SuggestOptions o = Options({1, 3}, 0.0, 0.0);
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
  EXPECT_FALSE(s.improved);
  EXPECT_NE(s.message.find("limits are zero"), std::string::npos) << s.message;
  for (const CameraChange& c : s.cameras) {
    EXPECT_TRUE(c.after.matrix() == c.before.matrix());
    EXPECT_EQ(c.move_m, 0.0);
    EXPECT_EQ(c.rotate_deg, 0.0);
  }
}

TEST(Suggest, RotationOnlyKeepsTheCentre) {
  Fixture f(SceneText(1.0));
  const SuggestOptions o = Options({3}, 0.0, 30);
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
  ASSERT_TRUE(s.improved) << s.message;
  EXPECT_TRUE(s.cameras[0].after.translation() == s.cameras[0].before.translation());
}

TEST(Suggest, RailPlaneBoxAndKeepOutHold) {
  Fixture f(SceneText(1.0));
  const Rig& rig = f.rig();
  const Vec3 c0 = rig.cameras[3].center();
  {  // A rail along x: the centre moves only along x.
    SuggestOptions o = Options({3}, 0.5, 30);
    o.limits[0].mount.kind = MountConstraint::Kind::kLine;
    o.limits[0].mount.axis = Vec3(2, 0, 0);
    const Suggestion s = Suggest(f.scene, rig, *f.caster, f.targets, o);
    CheckContract(f, o, s);
    ASSERT_TRUE(s.improved) << s.message;
    const Vec3 d = s.cameras[0].after.translation() - c0;
    EXPECT_LT(std::hypot(d.y(), d.z()), 1e-12) << d.transpose();
    EXPECT_GT(std::abs(d.x()), 1e-3);  // it did use the rail
  }
  {  // A ceiling plane (normal z): the height stays.
    SuggestOptions o = Options({3}, 0.5, 30);
    o.limits[0].mount.kind = MountConstraint::Kind::kPlane;
    o.limits[0].mount.axis = Vec3(0, 0, 1);
    const Suggestion s = Suggest(f.scene, rig, *f.caster, f.targets, o);
    CheckContract(f, o, s);
    EXPECT_NEAR(s.cameras[0].after.translation().z(), c0.z(), 1e-12);
  }
  {  // A mounting box, and a keep-out box on the side the rail result went to.
    SuggestOptions o = Options({3}, 0.5, 30);
    o.limits[0].mount.kind = MountConstraint::Kind::kBox;
    o.limits[0].mount.box.min = c0 - Vec3(0.1, 0.05, 0.02);
    o.limits[0].mount.box.max = c0 + Vec3(0.1, 0.05, 0.02);
    Aabb keep;
    keep.min = c0 + Vec3(0.02, -1, -1);
    keep.max = c0 + Vec3(1, 1, 1);
    // Without the keep-out box the nudge goes into it, so the check below can fail.
    const Suggestion free = Suggest(f.scene, rig, *f.caster, f.targets, o);
    ASSERT_TRUE(free.improved) << free.message;
    EXPECT_TRUE(keep.Contains(free.cameras[0].after.translation()))
        << free.cameras[0].after.translation().transpose();
    o.keep_out = {keep};
    const Suggestion s = Suggest(f.scene, rig, *f.caster, f.targets, o);
    CheckContract(f, o, s);
    const Vec3 p = s.cameras[0].after.translation();
    EXPECT_TRUE(o.limits[0].mount.box.Contains(p)) << p.transpose();
    EXPECT_FALSE(keep.Contains(p)) << p.transpose();
  }
}

TEST(Suggest, ZoomOnlyStaysInItsRangeAndKeepsThePose) {
  // c4 looks 26.6 degrees past the region with a 50 degree field of view: zooming out to 80
  // degrees alone brings the region in.
  Fixture f(SceneText(1.0));
  SuggestOptions o = Options({3}, 0.0, 0.0);
  o.limits[0].min_hfov_deg = 40;
  o.limits[0].max_hfov_deg = 80;
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
  ASSERT_TRUE(s.improved) << s.message;
  const CameraChange& c = s.cameras[0];
  EXPECT_TRUE(c.after.matrix() == c.before.matrix());
  EXPECT_NEAR(c.hfov_before_deg, 50.0, 1e-9);
  EXPECT_GT(c.hfov_after_deg, 55.0);
  EXPECT_LE(c.hfov_after_deg, 80.0 + 1e-9);
  EXPECT_LT(c.focal_scale, 1.0);
  // The reported metrics are those of the zoomed camera.
  Rig zoomed = f.rig();
  Intrinsics k = zoomed.cameras[3].model.intrinsics();
  k.fx *= c.focal_scale;
  k.fy *= c.focal_scale;
  zoomed.cameras[3].model = CameraModel(k);
  EXPECT_DOUBLE_EQ(EvaluateExact(f.scene, zoomed, *f.caster, f.targets, o.objective).objective,
                   s.after.objective);
  // A range that does not hold the current field of view is refused.
  o.limits[0].min_hfov_deg = 60;
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, o), InputError);
}

TEST(Suggest, SnapRoundsToInstallableSteps) {
  Fixture f(SceneText(1.0));
  SuggestOptions o = Options({3}, 0.3, 30);
  o.snap_move = 0.05;
  o.snap_rotate_deg = 1.0;
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
  ASSERT_TRUE(s.unsnapped.has_value());
  ASSERT_TRUE(s.improved) << s.message;  // this scene improves; the snapped result must be checked
  const CameraChange& c = s.cameras[0];
  const Vec3 d = c.after.translation() - c.before.translation();
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR(d[a] / 0.05, std::round(d[a] / 0.05), 1e-9) << d.transpose();
  const Vec3 y0 = YawPitchRollDeg(c.before.linear()), y1 = YawPitchRollDeg(c.after.linear());
  for (int a = 0; a < 3; ++a) {
    double delta = std::remainder(y1[a] - y0[a], 360.0);
    EXPECT_NEAR(delta, std::round(delta), 1e-7) << (y1 - y0).transpose();
  }
  // From a start off the 5 cm grid, a free camera lands on it: every coordinate k * 0.05 m.
  nlohmann::json j = nlohmann::json::parse(SceneText(1.0));
  j["rigs"][0]["cameras"][3]["position"] = {0.013, -4.021, 2.007};
  Fixture g(j.dump());
  const Suggestion t = Suggest(g.scene, g.rig(), *g.caster, g.targets, o);
  CheckContract(g, o, t);
  ASSERT_TRUE(t.improved) << t.message;
  const Vec3 p = t.cameras[0].after.translation();
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR(p[a] / 0.05, std::round(p[a] / 0.05), 1e-9) << p.transpose();
  // On an oblique rail the camera stays on the rail and moves a multiple of the step along it.
  SuggestOptions r = o;
  r.limits[0].mount.kind = MountConstraint::Kind::kLine;
  r.limits[0].mount.axis = Vec3(1, 1, 0);
  const Suggestion u = Suggest(g.scene, g.rig(), *g.caster, g.targets, r);
  CheckContract(g, r, u);
  const Vec3 m = u.cameras[0].after.translation() - u.cameras[0].before.translation();
  EXPECT_NEAR(m.normalized().cwiseAbs().dot(Vec3(1, 1, 0).normalized()) * m.norm(), m.norm(),
              1e-9 + 1e-9 * m.norm());
  EXPECT_NEAR(m.norm() / 0.05, std::round(m.norm() / 0.05), 1e-9) << m.transpose();
}

// A camera 0.25 m in front of a wall (a solid box whose face is the plane y = -1.85), looking
// through a narrow lens at a region it sees only part of; a camera overhead sees all of it. Backing
// up towards the wall widens its view, so coverage2 pulls it back as far as it may go: through the
// wall it would see nothing. `start_y` places it (the wall face is at -1.85).
std::string WallText(double start_y) {
  return R"({"objects": [
    {"name": "floor", "box": {"size": [6, 6, 0.1]}, "position": [0, 0, -0.05], "solid": true},
    {"name": "wall", "box": {"size": [6, 0.2, 3]}, "position": [0, -1.95, 1.5], "solid": true}],
  "rigs": [{"name": "r", "cameras": [
    {"id": "top", "position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0], "resolution": [640, 480], "hfov_deg": 60},
    {"id": "back", "position": [0, )" +
         Num(start_y) +
         R"(, 0.5], "look_at": [0, 0, 0.5], "resolution": [640, 480], "hfov_deg": 40}]}],
  "study": {"region": {"box": {"min": [-1, -1, 0], "max": [1, 1, 1]}}, "voxel_size": 0.1}})";
}

TEST(Suggest, ClearanceKeepsTheCentreOffTheWall) {
  const double wall = -1.85;
  auto run = [&](double start_y, double clearance) {
    Fixture f(WallText(start_y), 400);
    SuggestOptions o;
    o.objective.k = 2;
    o.cameras = {1};
    CameraLimits l;
    l.max_move = 0.3;
    l.max_rotate_deg = 5;
    o.limits = {l};
    o.clearance = clearance;
    const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
    CheckContract(f, o, s);
    return s;
  };
  // No clearance: the objective takes the camera to within 10 cm of the wall, so the test below can
  // fail.
  const Suggestion free = run(-1.6, 0.0);
  ASSERT_TRUE(free.improved) << free.message;
  const double free_gap = free.cameras[0].after.translation().y() - wall;
  EXPECT_LT(free_gap, 0.1) << "the objective no longer pushes the camera towards the wall";
  EXPECT_GT(free_gap, 0.0);
  EXPECT_NEAR(free.cameras[0].surface_distance_after, free_gap, 1e-9);
  // 10 cm: improved, and the centre at least 10 cm from every surface (the wall is the nearest).
  const Suggestion kept = run(-1.6, 0.1);
  ASSERT_TRUE(kept.improved) << kept.message;
  const double gap = kept.cameras[0].after.translation().y() - wall;
  EXPECT_GE(gap, 0.1 - 1e-12);
  EXPECT_NEAR(kept.cameras[0].surface_distance_before, 0.25, 1e-9);
  EXPECT_NEAR(kept.cameras[0].surface_distance_after, gap, 1e-9);
  EXPECT_LT(kept.cameras[0].after.translation().y(), -1.6) << "it did back up";
  // A camera that starts 5 cm from the wall may stay or move away, never closer.
  const Suggestion close = run(wall + 0.05, 0.1);
  EXPECT_GE(close.cameras[0].after.translation().y() - wall, 0.05 - 1e-12);
  EXPECT_GE(close.cameras[0].surface_distance_after, 0.05 - 1e-12);
  // A clearance that is not a finite length >= 0 is refused.
  Fixture f(WallText(-1.6), 50);
  SuggestOptions bad = Options({1}, 0.3, 5);
  bad.clearance = -0.1;
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, bad), InputError);
}

TEST(Suggest, CameraThatSeesNothingEndsCleanly) {
  // c4 turned completely away (looks outward): no gradient; with a small rotation limit it stays.
  Fixture f(SceneText(1.0, Vec3(0, -8, 2.0)));
  const SuggestOptions o = Options({3}, 0.2, 10);
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
  EXPECT_FALSE(s.improved);
  EXPECT_NE(s.message.find("no improvement"), std::string::npos) << s.message;
  EXPECT_NE(s.cameras[0].note.find("sees none"), std::string::npos) << s.cameras[0].note;
}

TEST(Suggest, TargetOutsideEveryFrustumEndsCleanly) {
  std::string text = SceneText(1.0);
  // Move the region far behind every camera's working range.
  nlohmann::json j = nlohmann::json::parse(text);
  j["study"]["region"]["box"] = {{"min", {30, 30, 0}}, {"max", {31, 31, 1}}};
  Fixture f(j.dump());
  const SuggestOptions o = Options({0, 3}, 0.3, 10);
  const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
  CheckContract(f, o, s);
  EXPECT_FALSE(s.improved);
  EXPECT_EQ(s.before.coverage2, 0.0);
  EXPECT_EQ(s.before.min_resolution, 0.0);
  EXPECT_TRUE(std::isinf(s.before.sigma_p50));
  EXPECT_NE(s.message.find("no selected camera sees any target point"), std::string::npos)
      << s.message;
}

TEST(Suggest, MillimetreAndKilometreScenesBehaveAlike) {
  Fixture m(SceneText(1.0));
  const Suggestion sm = Suggest(m.scene, m.rig(), *m.caster, m.targets, Options({3}, 0.3, 30));
  ASSERT_TRUE(sm.improved);
  for (double scale : {1e-3, 1e3}) {
    Fixture f(SceneText(scale));
    const SuggestOptions o = Options({3}, 0.3 * scale, 30);
    const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
    CheckContract(f, o, s);
    ASSERT_TRUE(s.improved) << "scale " << scale << ": " << s.message;
    EXPECT_NEAR(s.before.objective, sm.before.objective, 0.02) << scale;
    EXPECT_GE(s.after.objective, sm.after.objective - 0.03) << scale;
    EXPECT_NEAR(s.cameras[0].move_m / scale, sm.cameras[0].move_m, 0.1) << scale;
  }
}

TEST(Suggest, SigmaAndResolutionObjectivesNeverWorsen) {
  Fixture f(SceneText(1.0));
  for (const char* name : {"sigma-mean", "sigma-p90", "resolution", "mix"}) {
    SuggestOptions o = Options({3}, 0.3, 30);
    o.objective = *ParseObjective(name);
    o.objective.k = 4;
    const Suggestion s = Suggest(f.scene, f.rig(), *f.caster, f.targets, o);
    CheckContract(f, o, s);
    EXPECT_TRUE(s.improved) << name << ": " << s.message;
  }
}

TEST(Suggest, BadSelectionAndLimitsAreInputErrors) {
  Fixture f(SceneText(1.0));
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, Options({}, 0.3, 10)), InputError);
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, Options({7}, 0.3, 10)), InputError);
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, Options({1, 1}, 0.3, 10)),
               InputError);
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, Options({1}, -0.1, 10)), InputError);
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, Options({1}, 0.1, 180)), InputError);
  SuggestOptions o = Options({3}, 0.3, 10);
  Aabb inside;
  inside.min = f.rig().cameras[3].center() - Vec3::Constant(0.1);
  inside.max = f.rig().cameras[3].center() + Vec3::Constant(0.1);
  o.keep_out = {inside};
  EXPECT_THROW(Suggest(f.scene, f.rig(), *f.caster, f.targets, o), InputError);
}

TEST(Suggest, BaselineRespectsLimitsAndBudget) {
  Fixture f(SceneText(1.0));
  const SuggestOptions o = Options({3}, 0.3, 30);
  const Suggestion b = BaselineSearch(f.scene, f.rig(), *f.caster, f.targets, o, 200, 5);
  CheckContract(f, o, b);
  EXPECT_LE(b.evaluations, 200);
  EXPECT_GE(b.evaluations, 199);
}

// ------------------------------------------------------------------------------------------------
// Accept cycle on files.

class SuggestAcceptTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("pandora_accept_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string Read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  static void Write(const fs::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
  }
  // Suggests for c2 and c4 on the scene file and writes the suggestion next to it.
  std::string MakeSuggestion(const fs::path& scene_path, Suggestion* out = nullptr) {
    const Scene scene = LoadScene(scene_path.string());
    const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
    const auto targets = SampleTargets(scene, 300, {}, false, 7);
    const SuggestOptions o = Options({1, 3}, 0.3, 30);
    const Suggestion s = Suggest(scene, scene.rigs[0], *caster, targets, o);
    EXPECT_TRUE(s.improved) << s.message;
    const fs::path p = dir_ / "suggestion.json";
    Write(p, SuggestionToJson(s, scene, scene.rigs[0], o));
    if (out) *out = s;
    return p.string();
  }
  fs::path dir_;
};

// A reloaded pose against the suggested one: centres within 1e-9 m, orientations within 1e-9 rad
// (accept writes 12 significant digits).
::testing::AssertionResult SamePose(const Eigen::Isometry3d& got, const Eigen::Isometry3d& want) {
  const double dc = (got.translation() - want.translation()).norm();
  const Eigen::Quaterniond q(Mat3(got.linear().transpose() * want.linear()));
  const double angle = 2 * std::atan2(q.vec().norm(), std::abs(q.w()));
  if (dc <= 1e-9 && angle <= 1e-9) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "centre off by " << dc << " m, orientation by " << angle << " rad";
}

std::vector<std::string> Keys(const nlohmann::ordered_json& cam) {
  std::vector<std::string> keys;
  for (auto it = cam.begin(); it != cam.end(); ++it) keys.push_back(it.key());
  return keys;
}

// Everything but the pose keys of the named cameras is JSON-equal.
void ExpectEqualButPoses(const std::string& a_text, const std::string& b_text,
                         const std::set<std::string>& ids) {
  nlohmann::ordered_json a = nlohmann::ordered_json::parse(a_text),
                         b = nlohmann::ordered_json::parse(b_text);
  for (auto* j : {&a, &b})
    for (auto& cam : (*j)["rigs"][0]["cameras"])
      if (ids.count(cam["id"].get<std::string>()))
        for (const char* k : {"position", "look_at", "up", "quaternion", "euler_deg"}) cam.erase(k);
  EXPECT_EQ(a, b);
}

TEST_F(SuggestAcceptTest, PartialAcceptWritesBackupAndOnlyThatPose) {
  const fs::path scene_path = dir_ / "scene.json";
  const std::string original = SceneText(1.0);
  Write(scene_path, original);
  Suggestion s;
  const std::string suggestion = MakeSuggestion(scene_path, &s);
  // Nothing changes until accept.
  EXPECT_EQ(Read(scene_path), original);

  AcceptOptions only_c4;
  only_c4.cameras = {"c4"};
  const AcceptResult r = AcceptSuggestion(suggestion, only_c4);
  EXPECT_EQ(r.accepted, std::vector<std::string>{"c4"});
  EXPECT_EQ(fs::path(r.backup_path), fs::path(scene_path.string() + ".bak"));
  EXPECT_EQ(Read(r.backup_path), original);
  const std::string updated = Read(scene_path);
  ExpectEqualButPoses(original, updated, {"c4"});
  // The camera keeps its look_at form, in the same place; `up` follows look_at when the suggestion
  // rolled the camera (then accept says so).
  const nlohmann::ordered_json cam =
      nlohmann::ordered_json::parse(updated)["rigs"][0]["cameras"][3];
  std::vector<std::string> keys = Keys(cam);
  const bool rolled = cam.contains("up");
  EXPECT_EQ(rolled, !r.notes.empty());
  if (rolled) keys.erase(std::find(keys.begin(), keys.end(), "up"));
  EXPECT_EQ(keys, (std::vector<std::string>{"id", "position", "look_at", "resolution", "hfov_deg",
                                            "range"}));

  const Scene after = LoadScene(scene_path.string());
  const Scene before = ParseScene(original, scene_path.string());
  EXPECT_TRUE(SamePose(after.rigs[0].cameras[3].world_from_camera, s.cameras[1].after));
  for (int c : {0, 1, 2})  // c2 was offered but not accepted
    EXPECT_TRUE(after.rigs[0].cameras[c].world_from_camera.matrix() ==
                before.rigs[0].cameras[c].world_from_camera.matrix());

  // The scene changed since: accepting the rest is refused, nothing written.
  AcceptOptions c2;
  c2.cameras = {"c2"};
  EXPECT_THROW(AcceptSuggestion(suggestion, c2), InputError);
  EXPECT_EQ(Read(scene_path), updated);
  EXPECT_FALSE(fs::exists(scene_path.string() + ".bak.1"));
  // With force it goes through, with a second backup.
  c2.force = true;
  const AcceptResult r2 = AcceptSuggestion(suggestion, c2);
  EXPECT_EQ(fs::path(r2.backup_path), fs::path(scene_path.string() + ".bak.1"));
  EXPECT_EQ(Read(r2.backup_path), updated);
  const Scene both = LoadScene(scene_path.string());
  EXPECT_TRUE(SamePose(both.rigs[0].cameras[1].world_from_camera, s.cameras[0].after));
  EXPECT_TRUE(SamePose(both.rigs[0].cameras[3].world_from_camera, s.cameras[1].after));
}

TEST_F(SuggestAcceptTest, ZoomWritesFocalLengthInPlaceOfTheFieldOfView) {
  const fs::path scene_path = dir_ / "scene.json";
  const std::string original = SceneText(1.0);
  Write(scene_path, original);
  const Scene scene = LoadScene(scene_path.string());
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const auto targets = SampleTargets(scene, 300, {}, false, 7);
  SuggestOptions o = Options({3}, 0.1, 5);
  o.limits[0].min_hfov_deg = 40;
  o.limits[0].max_hfov_deg = 80;
  const Suggestion s = Suggest(scene, scene.rigs[0], *caster, targets, o);
  ASSERT_TRUE(s.improved) << s.message;
  ASSERT_NE(s.cameras[0].focal_scale, 1.0);
  const fs::path p = dir_ / "suggestion.json";
  Write(p, SuggestionToJson(s, scene, scene.rigs[0], o));
  AcceptSuggestion(p.string(), {});
  const Scene after = LoadScene(scene_path.string());
  const Intrinsics& k0 = scene.rigs[0].cameras[3].model.intrinsics();
  const Intrinsics& k1 = after.rigs[0].cameras[3].model.intrinsics();
  EXPECT_NEAR(k1.fx, k0.fx * s.cameras[0].focal_scale, 1e-9 * k0.fx);
  EXPECT_NEAR(k1.fy, k0.fy * s.cameras[0].focal_scale, 1e-9 * k0.fy);
  EXPECT_EQ(k1.cx, k0.cx);
  EXPECT_TRUE(SamePose(after.rigs[0].cameras[3].world_from_camera, s.cameras[0].after));
  const nlohmann::ordered_json cam =
      nlohmann::ordered_json::parse(Read(scene_path))["rigs"][0]["cameras"][3];
  std::vector<std::string> keys = Keys(cam);
  if (cam.contains("up")) keys.erase(std::find(keys.begin(), keys.end(), "up"));
  EXPECT_EQ(keys, (std::vector<std::string>{"id", "position", "look_at", "resolution", "focal_px",
                                            "range"}));
}

TEST_F(SuggestAcceptTest, UnknownCameraAndNoImprovementAreRefused) {
  const fs::path scene_path = dir_ / "scene.json";
  Write(scene_path, SceneText(1.0));
  const std::string suggestion = MakeSuggestion(scene_path);
  AcceptOptions bad;
  bad.cameras = {"c3"};  // in the rig, but not in the suggestion
  EXPECT_THROW(AcceptSuggestion(suggestion, bad), InputError);
  EXPECT_FALSE(fs::exists(scene_path.string() + ".bak"));
  // A suggestion that found nothing cannot be accepted.
  nlohmann::json j = nlohmann::json::parse(Read(suggestion));
  j["improved"] = false;
  Write(suggestion, j.dump());
  EXPECT_THROW(AcceptSuggestion(suggestion, {}), InputError);
  EXPECT_EQ(Read(scene_path), SceneText(1.0));
}

// Library-level refusals and file handling: a suggestion made from perturbed poses (whatever its
// JSON layout), a read-only scene, and a scene reached through a symbolic link (the file it names
// is updated, the link stays a link, the permissions stay).
TEST_F(SuggestAcceptTest, PerturbedReadOnlyAndSymlinkedScenes) {
  const fs::path real = dir_ / "real_scene.json";
  const std::string original = SceneText(1.0);
  Write(real, original);
  const fs::path link = dir_ / "scene.json";
  fs::create_symlink(real.filename(), link);
  const std::string suggestion = MakeSuggestion(link);

  nlohmann::json j = nlohmann::json::parse(Read(suggestion));
  j["perturbed_for_benchmark"] = true;
  const fs::path perturbed = dir_ / "perturbed.json";
  Write(perturbed, j.dump());  // compact: no "key": value spacing to search for
  EXPECT_THROW(AcceptSuggestion(perturbed.string(), {}), InputError);

  fs::permissions(real, fs::perms::owner_read | fs::perms::group_read);
  EXPECT_THROW(AcceptSuggestion(suggestion, {}), InputError);
  EXPECT_EQ(Read(real), original);
  EXPECT_FALSE(fs::exists(dir_ / "real_scene.json.bak"));

  const fs::perms mode = fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read;
  fs::permissions(real, mode);
  const AcceptResult r = AcceptSuggestion(suggestion, {});
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_NE(Read(real), original);
  EXPECT_EQ(Read(r.backup_path), original);
  EXPECT_EQ(fs::path(r.backup_path).filename(), "real_scene.json.bak");
  EXPECT_EQ(fs::status(real).permissions() & fs::perms::all, mode);
}

TEST_F(SuggestAcceptTest, MillimetreFileGetsMillimetres) {
  // The same scene written in millimetres: accept writes the position in the file's unit.
  const fs::path scene_path = dir_ / "scene_mm.json";
  const std::string original = SceneText(1000.0, Vec3(2.0, 0.0, 0.5), "mm");
  Write(scene_path, original);
  Suggestion s;
  const std::string suggestion = MakeSuggestion(scene_path, &s);
  AcceptSuggestion(suggestion, {});
  const Scene after = LoadScene(scene_path.string());
  EXPECT_TRUE(SamePose(after.rigs[0].cameras[3].world_from_camera, s.cameras[1].after));
  const auto pos = nlohmann::json::parse(Read(scene_path))["rigs"][0]["cameras"][3]["position"];
  EXPECT_NEAR(pos[1].get<double>(), s.cameras[1].after.translation().y() * 1000.0, 1e-6);  // mm
}

// The three forms of a pose survive accept: look_at (with up), euler_deg and quaternion; with
// --snap-move 0.05 the positions in the file are multiples of 5 cm (in a centimetre file: of 5);
// the reloaded poses are the suggested ones (SamePose) and the look_at point keeps its distance.
TEST_F(SuggestAcceptTest, AcceptKeepsEachCamerasFormAndWritesSnappedNumbers) {
  for (const std::string units : {"m", "cm"}) {
    SCOPED_TRACE(units);
    const double s_unit = units == "m" ? 1.0 : 100.0;
    nlohmann::ordered_json j =
        nlohmann::ordered_json::parse(SceneText(s_unit, Vec3(2.0, 0.0, 0.5), units));
    auto& cams = j["rigs"][0]["cameras"];
    cams[3]["up"] = {0, 0, 1};
    // c2 as Euler angles (it looks at the region's centre from (0, 4, 2): yaw -90, pitch down).
    cams[1].erase("look_at");
    cams[1]["euler_deg"] = {{"yaw", -90}, {"pitch", -20}};
    cams[0].erase("look_at");  // c1 as a quaternion: looking along -x, tilted down 20 degrees
    const Mat3 R1 = RotationFromYawPitchRollDeg(Vec3(180, -20, 0));
    const Eigen::Quaterniond q1(R1);
    cams[0]["quaternion"] = {q1.w(), q1.x(), q1.y(), q1.z()};
    const fs::path scene_path = dir_ / ("forms_" + units + ".json");
    Write(scene_path, j.dump(2) + "\n");
    const double look_distance = (Vec3(2.0, 0.0, 0.5) - Vec3(0, -4, 2)).norm() * s_unit;

    const Scene scene = LoadScene(scene_path.string());
    const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
    const auto targets = SampleTargets(scene, 300, {}, false, 7);
    SuggestOptions o = Options({0, 1, 3}, 0.3, 20);
    o.snap_move = 0.05;
    o.snap_rotate_deg = 1.0;
    const Suggestion s = Suggest(scene, scene.rigs[0], *caster, targets, o);
    ASSERT_TRUE(s.improved) << s.message;
    const fs::path sp = dir_ / ("suggestion_" + units + ".json");
    Write(sp, SuggestionToJson(s, scene, scene.rigs[0], o));
    const AcceptResult r = AcceptSuggestion(sp.string(), {});

    const nlohmann::ordered_json out = nlohmann::ordered_json::parse(Read(scene_path));
    const auto& written = out["rigs"][0]["cameras"];
    const Scene after = LoadScene(scene_path.string());
    for (const CameraChange& ch : s.cameras) {
      SCOPED_TRACE(ch.id);
      const auto& cam = written[ch.index];
      if (!(ch.move_m > 0 || ch.rotate_deg > 0)) continue;  // left as written
      EXPECT_TRUE(SamePose(after.rigs[0].cameras[ch.index].world_from_camera, ch.after));
      for (int a = 0; a < 3; ++a) {  // k * 5 cm, written as such (5 cm = 5 in the cm file)
        const double v = cam["position"][a].get<double>();
        const double step = 0.05 * s_unit;
        EXPECT_EQ(v, std::strtod(Num(std::round(v / step) * step).c_str(), nullptr));
        EXPECT_LT(std::abs(v / step - std::round(v / step)), 1e-9) << v;
        std::ostringstream text;
        text << cam["position"][a];
        EXPECT_LE(text.str().size(), 8u) << text.str();  // e.g. -4.15 or 415, not -4.1499999999
      }
    }
    EXPECT_TRUE(written[0].contains("quaternion"));
    EXPECT_FALSE(written[0].contains("euler_deg") || written[0].contains("look_at"));
    EXPECT_TRUE(written[1].contains("euler_deg"));
    EXPECT_FALSE(written[1].contains("quaternion") || written[1].contains("look_at"));
    ASSERT_TRUE(written[3].contains("look_at"));
    EXPECT_FALSE(written[3].contains("quaternion"));
    const Vec3 p(written[3]["position"][0].get<double>(), written[3]["position"][1].get<double>(),
                 written[3]["position"][2].get<double>());
    const Vec3 t(written[3]["look_at"][0].get<double>(), written[3]["look_at"][1].get<double>(),
                 written[3]["look_at"][2].get<double>());
    EXPECT_NEAR((t - p).norm(), look_distance, 1e-9 * look_distance);
    // The roll change was snapped to whole degrees: either none (up kept as [0, 0, 1]) or a
    // multiple of 1 degree that accept reports and writes into up.
    ASSERT_TRUE(written[3].contains("up"));
    const bool kept = written[3]["up"] == nlohmann::ordered_json({0, 0, 1});
    bool noted = false;
    for (const std::string& n : r.notes) noted = noted || n.rfind("c4:", 0) == 0;
    EXPECT_EQ(kept, !noted);
  }
}

TEST(SuggestReplacePoses, LookAtKeepsUpOrSaysWhyNot) {
  const std::string text = nlohmann::ordered_json::parse(SceneText(1.0)).dump(2) + "\n";
  // c1 at (4, 0, 2) looking at (0, 0, 0.5): move it 10 cm and turn it to look at (0, 0.5, 0.5).
  const Vec3 p(4.1, 0.0, 2.0), target(0, 0.5, 0.5);
  const double distance = (Vec3(0, 0, 0.5) - Vec3(4, 0, 2)).norm();
  Eigen::Isometry3d pose = *LookAt(p, target, Vec3::UnitZ());
  std::vector<std::string> notes;
  std::string out = ReplacePoses(text, "x.json", "ring", {{"c1", pose, std::nullopt, 0}}, &notes);
  nlohmann::ordered_json cam = nlohmann::ordered_json::parse(out)["rigs"][0]["cameras"][0];
  EXPECT_EQ(Keys(cam), (std::vector<std::string>{"id", "position", "look_at", "resolution",
                                                 "hfov_deg", "range"}));
  EXPECT_TRUE(notes.empty());
  const Vec3 t(cam["look_at"][0].get<double>(), cam["look_at"][1].get<double>(),
               cam["look_at"][2].get<double>());
  EXPECT_NEAR((t - p).norm(), distance, 1e-9);  // the old look_at's distance, along the new axis
  EXPECT_NEAR((t - p).normalized().dot((target - p).normalized()), 1.0, 1e-15);
  EXPECT_TRUE(SamePose(ParseScene(out, "x.json").rigs[0].cameras[0].world_from_camera, pose));
  // Rolled 5 degrees about its optical axis: up cannot stay [0, 0, 1]; it becomes the camera's up.
  Eigen::Isometry3d rolled = pose;
  rolled.linear() =
      pose.linear() * Eigen::AngleAxisd(5 * kPi / 180, Vec3::UnitZ()).toRotationMatrix();
  out = ReplacePoses(text, "x.json", "ring", {{"c1", rolled, std::nullopt, 0}}, &notes);
  cam = nlohmann::ordered_json::parse(out)["rigs"][0]["cameras"][0];
  EXPECT_EQ(Keys(cam), (std::vector<std::string>{"id", "position", "look_at", "up", "resolution",
                                                 "hfov_deg", "range"}));
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("c1: the suggestion also turns the camera 5 deg about its optical axis"),
            std::string::npos)
      << notes[0];
  EXPECT_TRUE(SamePose(ParseScene(out, "x.json").rigs[0].cameras[0].world_from_camera, rolled));
}

TEST(SuggestReplacePoses, UntouchedTextIsByteIdentical) {
  // A file in nlohmann's own layout (any indentation) round-trips byte for byte when no pose
  // changes, and only the pose lines change when one does.
  for (int indent : {1, 2, 4}) {
    const std::string text = nlohmann::ordered_json::parse(SceneText(1.0)).dump(indent) + "\n";
    EXPECT_EQ(ReplacePoses(text, "x.json", "ring", {}), text) << indent;
  }
  const std::string text = nlohmann::ordered_json::parse(SceneText(1.0)).dump(2) + "\n";
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Vec3(1, 2, 3);
  const std::string out = ReplacePoses(text, "x.json", "ring", {{"c1", pose, std::nullopt}});
  ExpectEqualButPoses(text, out, {"c1"});
  EXPECT_THROW(ReplacePoses(text, "x.json", "nope", {{"c1", pose, std::nullopt}}), InputError);
  EXPECT_THROW(ReplacePoses(text, "x.json", "ring", {{"c9", pose, std::nullopt}}), InputError);
}

}  // namespace
}  // namespace pandora
