// The accuracy studies (app/session/accuracy.h) on small synthetic scenes: options that name their
// field, the power-law fit against an exact power law, sample points and the prediction against the
// closed form of a ring of cameras, the voxel study's sizes, counts and notes, a small Monte Carlo
// run, and the steady-state study's rows.
#include "app/session/accuracy.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "analysis/geometry/uncertainty_reference.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/error.h"
#include "tests/expect_input_error.h"
#include "tests/fixtures.h"
#include "volume/fields.h"
#include "volume/summary.h"

namespace pandora {
namespace {

using testing::ErrorOf;

// A 4 x 4 x 2.5 m room, a 1 m region at 0.1 m voxels, four cameras 1.8 m out and 1.2 m above the
// region's centre (0, 0, 0.5).
Scene RingRoom() {
  Scene scene = testing::BoxRoom(Vec3(4, 4, 2.5), 0.1);
  scene.rigs.push_back(testing::RingRig(4, 1.8, 1.2, Vec3(0, 0, 0.5), 70));
  return scene;
}

TEST(AccuracyOptions, DefaultsQuickAndErrors) {
  AccuracyOptions().Check();
  const AccuracyOptions quick = AccuracyOptions::Quick();
  quick.Check();
  EXPECT_EQ(quick.voxel_factors, (std::vector<double>{4, 2, 1, 0.5}));
  EXPECT_EQ(quick.trials, (std::vector<int>{100, 300, 1000, 3000}));
  EXPECT_EQ(quick.sample_points, 3);
  auto field_of = [](AccuracyOptions o) {
    const InputError e = ErrorOf([&] { o.Check(); });
    EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos) << e.what();
    return e.file();
  };
  AccuracyOptions o;
  o.voxel_factors = {2, 0};
  EXPECT_EQ(field_of(o), "voxel_factors");
  o = {};
  o.trials = {100, 1};
  EXPECT_EQ(field_of(o), "trials");
  o = {};
  o.sample_points = 0;
  EXPECT_EQ(field_of(o), "sample_points");
  o = {};
  o.min_timing_seconds = 0;
  EXPECT_EQ(field_of(o), "min_timing_seconds");
  o = {};
  o.run_on_iterations = 0;
  EXPECT_EQ(field_of(o), "run_on_iterations");
}

TEST(PowerLawCrossing, ExactPowerLaw) {
  // y = 2 x^-1/2: y = 0.01 at x = (2 / 0.01)^2 = 40000.
  const std::vector<double> x{1, 4, 16, 64};
  std::vector<double> y;
  for (double v : x) y.push_back(2 / std::sqrt(v));
  EXPECT_NEAR(PowerLawCrossing(x, y, 0.01), 40000, 1e-6);
  // Points that cannot be on log axes are left out.
  EXPECT_NEAR(PowerLawCrossing({1, 0, 4, 16}, {2, 5, 1, 0.5}, 0.01), 40000, 1e-6);
  EXPECT_TRUE(std::isnan(PowerLawCrossing({1, 4}, {1, 2}, 0.01)));  // error grows with time
  EXPECT_TRUE(std::isnan(PowerLawCrossing({1}, {1}, 0.01)));        // one point
  EXPECT_TRUE(std::isnan(PowerLawCrossing({3, 3}, {1, 2}, 0.01)));  // no spread in time
}

TEST(SamplePoints, CellCentresSeenByTwoCamerasSpreadEvenly) {
  const Scene scene = RingRoom();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  // Every cell centre of the 1 m box is seen by all four cameras: 27 points; two picked: the first
  // and the last cell.
  const std::vector<SamplePoint> all = SamplePoints(scene, scene.rigs[0], *caster, 100);
  ASSERT_EQ(all.size(), 27u);
  for (const SamplePoint& p : all) EXPECT_EQ(p.cameras.size(), 4u);
  const std::vector<SamplePoint> two = SamplePoints(scene, scene.rigs[0], *caster, 2);
  ASSERT_EQ(two.size(), 2u);
  EXPECT_TRUE(two[0].X.isApprox(Vec3(-1.0 / 3, -1.0 / 3, 1.0 / 6)));
  EXPECT_TRUE(two[1].X.isApprox(Vec3(1.0 / 3, 1.0 / 3, 5.0 / 6)));
}

TEST(PredictUncertainty, RingOfCamerasClosedForm) {
  // N pinholes on a ring of radius R, h above X, looking at X: each adds (f / (d sigma))^2 (I - z
  // z^T) with z its axis, d = sqrt(R^2 + h^2); summed, J = k N diag(1 - c^2 / 2, 1 - c^2 / 2, c^2)
  // with c = R / d and k = (f / (d sigma))^2.
  const int N = 6;
  const double R = 1.8, h = 1.2, sigma = 0.5;
  const Vec3 X(0.3, -0.2, 0.5);
  SamplePoint p;
  p.X = X;
  p.cameras = testing::RingRig(N, R, h, X, 70).cameras;
  Information info;
  const StaticUncertainty u = PredictUncertainty(p, sigma, &info);
  const double f = p.cameras[0].model.intrinsics().fx, d = std::hypot(R, h), c2 = R * R / (d * d);
  const double k = std::pow(f / (d * sigma), 2);
  const Vec3 diagonal = k * N * Vec3(1 - c2 / 2, 1 - c2 / 2, c2);
  EXPECT_TRUE(info.J.isApprox(Mat3(diagonal.asDiagonal()), 1e-12)) << info.J;
  ASSERT_TRUE(u.triangulable);
  EXPECT_NEAR(u.sigma_max, 1 / std::sqrt(diagonal.minCoeff()), 1e-12 * u.sigma_max);
}

// Coarse-to-fine: the rows, counts and invariants (the exactness of the refined voxels themselves
// is FieldEvaluator.VoxelFilterEvaluatesExactlyTheKeptVoxels). A finer study voxel (5 cm, 20^3)
// gives the coarse passes cells of 10 and 20 cm.
TEST(RefineStudy, RowsCountsAndInvariants) {
  Scene scene = RingRoom();
  scene.study.voxel_size = 0.05;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const RefineStudy study = RunRefineStudy(scene, scene.rigs[0], *caster);
  EXPECT_EQ(study.reference_voxels, 8000);  // 20^3
  EXPECT_GT(study.reference_triangulable, 0);
  EXPECT_GT(study.reference_seconds, 0);
  ASSERT_EQ(study.rows.size(), 4u);
  const int factors[4] = {2, 2, 4, 4};
  const double tolerances[4] = {0.02, 0.1, 0.02, 0.1};
  for (int r = 0; r < 4; ++r) {
    const RefineRow& row = study.rows[r];
    EXPECT_EQ(row.factor, factors[r]);
    EXPECT_EQ(row.tolerance, tolerances[r]);
    EXPECT_GT(row.refined_voxels, 0);  // at least the region's edge
    EXPECT_LE(row.refined_voxels, study.reference_voxels);
    EXPECT_LE(row.class_wrong_pct, row.coverage_wrong_pct);
    EXPECT_LE(row.sigma_p50_pct, row.sigma_p99_pct);
    EXPECT_LE(row.sigma_p99_pct, row.sigma_max_pct);
    if (row.refined_voxels == study.reference_voxels) {  // everything exact
      EXPECT_EQ(row.coverage_wrong_pct, 0);
      EXPECT_EQ(row.sigma_max_pct, 0);
      EXPECT_EQ(row.triangulable_mismatch, 0);
    }
  }
  // A larger tolerance refines no more cells.
  EXPECT_LE(study.rows[1].refined_voxels, study.rows[0].refined_voxels);
  EXPECT_LE(study.rows[3].refined_voxels, study.rows[2].refined_voxels);
  EXPECT_EQ(scene.study.voxel_size, 0.05);  // the caller's scene is left alone
}

TEST(VoxelStudy, SizesCountsAndTheReference) {
  Scene scene = RingRoom();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  AccuracyOptions options = AccuracyOptions::Quick();
  options.voxel_factors = {2, 1};
  const VoxelStudy study = RunVoxelStudy(scene, scene.rigs[0], *caster, options);
  ASSERT_EQ(study.rows.size(), 2u);
  EXPECT_FALSE(study.steady);
  EXPECT_TRUE(study.notes.empty());
  EXPECT_DOUBLE_EQ(study.rows[0].voxel_size, 0.2);
  EXPECT_EQ(study.rows[0].region_voxels, 125);   // 5^3 (closed form)
  EXPECT_EQ(study.rows[1].region_voxels, 1000);  // 10^3
  EXPECT_EQ(scene.study.voxel_size, 0.1);        // the caller's scene is left alone
  // The reference row equals an evaluation of its own.
  FieldOptions field_options;
  field_options.fields = {"coverage", "sigma_max", "sigma_mean"};
  const Fields fields = EvaluateFields(scene, scene.rigs[0], *caster, field_options);
  const Summary s = Summarize(scene, scene.rigs[0], fields, field_options.fields, 1);
  const VoxelRow& ref = study.rows[1];
  EXPECT_EQ(ref.ge[0], s.coverage.ge1);
  EXPECT_EQ(ref.ge[1], s.coverage.ge2);
  EXPECT_EQ(ref.ge[2], s.coverage.ge3);
  EXPECT_EQ(ref.p50, *s.uncertainty->sigma_max_mm.p50);
  EXPECT_EQ(ref.p90, *s.uncertainty->sigma_max_mm.p90);
  EXPECT_EQ(ref.triangulable_voxels, s.uncertainty->triangulable_voxels);
  EXPECT_TRUE(std::isnan(ref.steady_p50));
  for (const VoxelRow& r : study.rows) {
    EXPECT_GE(r.repeats, 1);
    EXPECT_GT(r.seconds, 0);
  }

  // With a motion model: the steady-state columns.
  scene.study.motion = MotionModel{1.0, 60.0};
  options.voxel_factors = {2};
  const VoxelStudy steady = RunVoxelStudy(scene, scene.rigs[0], *caster, options);
  ASSERT_EQ(steady.rows.size(), 1u);
  EXPECT_TRUE(steady.steady);
  EXPECT_LT(steady.rows[0].steady_p50, steady.rows[0].p50);

  // Over the memory budget: no row, a note.
  Scene tight = RingRoom();
  tight.study.memory_budget_bytes = 1000;
  const VoxelStudy none = RunVoxelStudy(tight, tight.rigs[0], *caster, options);
  EXPECT_TRUE(none.rows.empty());
  ASSERT_EQ(none.notes.size(), 1u);
  EXPECT_NE(none.notes[0].find("voxel 200 mm skipped: needs about"), std::string::npos)
      << none.notes[0];

  // Over the time limit: the finer size is skipped with a note.
  options.voxel_factors = {2, 1};
  options.max_reference_seconds = 1e-12;
  const VoxelStudy quick = RunVoxelStudy(RingRoom(), scene.rigs[0], *caster, options);
  EXPECT_EQ(quick.rows.size(), 1u);
  ASSERT_EQ(quick.notes.size(), 1u);
  EXPECT_NE(quick.notes[0].find("voxel 100 mm skipped: predicted"), std::string::npos)
      << quick.notes[0];
}

TEST(MonteCarloStudy, SmallRun) {
  const Scene scene = RingRoom();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  AccuracyOptions options;
  options.sample_points = 2;
  options.trials = {30, 120};
  options.min_timing_seconds = 1e-3;
  const MonteCarloStudy mc = RunMonteCarloStudy(scene, scene.rigs[0], *caster, options);
  ASSERT_EQ(mc.points.size(), 2u);
  EXPECT_EQ(mc.sigma_px, scene.study.pixel_sigma);
  for (const SamplePoint& p : mc.points)
    EXPECT_DOUBLE_EQ(p.sigma_max, PredictUncertainty(p, mc.sigma_px).sigma_max);
  ASSERT_EQ(mc.rows.size(), 2u);
  for (const MonteCarloRow& r : mc.rows) {
    EXPECT_EQ(r.points, 2);
    EXPECT_EQ(r.failures, 0);
    EXPECT_GT(r.seconds_per_point, 0);
    EXPECT_LT(r.rel_mean, 0.5);  // about 1 / sqrt(pi N): 10% at N = 30
    EXPECT_LE(r.rel_mean, r.rel_max);
  }
  EXPECT_GT(mc.prediction_seconds, 0);
  EXPECT_LT(mc.prediction_seconds, 1e-3);
}

// The gate on a narrow-baseline rig (three cameras 0.4 m apart, 1.8 m from the region: the
// covariance is long along the depth, so its major axis is resolvable): every sampled voxel is a
// region voxel centre that >= 2 cameras see, the sample covariance of 2,000 triangulations matches
// J^-1 axis by axis, and a second run gives the same numbers bit for bit. At 40x the pixel noise
// the estimator's nonlinearity shows: the errors along the depth (major) axis skew (1/Z is what
// the pixels measure), which the gate reports as where the first-order prediction stops holding.
TEST(GateStudy, NarrowBaselineMatchesThePredictionAxisByAxis) {
  Scene scene = testing::BoxRoom(Vec3(4, 4, 2.5), 0.1);
  Rig rig;
  rig.name = "wall";
  for (int i = 0; i < 3; ++i)
    rig.cameras.push_back(testing::TestCamera("c" + std::to_string(i),
                                              Vec3(-1.8, 0.4 * (i - 1), 1.2), Vec3(0, 0, 0.5)));
  scene.rigs = {rig};
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  AccuracyOptions options = AccuracyOptions::Quick();
  const GateStudy gate = RunGateStudy(scene, rig, *caster, options);
  ASSERT_EQ(gate.voxels.size(), 12u);
  EXPECT_EQ(gate.trials, 2000);
  const VisibilityTester tester(rig.cameras, *caster, scene.Bounds().diagonal());
  const Aabb& box = scene.study.region.box;
  int resolvable_major = 0;
  std::vector<double> skews;
  for (const GateVoxel& v : gate.voxels) {
    int seen = 0;
    for (int c = 0; c < 3; ++c) seen += tester.Test(c, v.X) == ViewResult::kSeen ? 1 : 0;
    EXPECT_EQ(seen, v.cameras);
    EXPECT_GE(v.cameras, 2);
    for (int a = 0; a < 3; ++a) {  // on the voxel lattice of the region
      const double index = (v.X[a] - box.min[a]) / scene.study.voxel_size - 0.5;
      EXPECT_NEAR(index, std::round(index), 1e-9);
      EXPECT_NEAR(v.Ratio(a), 1.0, kGateEigenTolerance[a]) << a;
      if (std::isfinite(v.axis_deg[a])) {
        EXPECT_LE(v.axis_deg[a], kGateAngleDeg);
      }
    }
    resolvable_major += std::isfinite(v.axis_deg[0]) ? 1 : 0;
    EXPECT_GT(v.predicted[0], 10 * v.predicted[1]);  // depth: long
    EXPECT_GE(v.predicted[1], v.predicted[2]);
    EXPECT_EQ(v.failures, 0);
    EXPECT_TRUE(v.pass);
    skews.push_back(std::abs(v.skew_major));
  }
  EXPECT_EQ(resolvable_major, 12);
  EXPECT_DOUBLE_EQ(gate.PassShare(), 1.0);
  std::sort(skews.begin(), skews.end());
  const double quiet_skew = skews[6];
  // Gaussian errors: the skew of 2,000 samples has a standard error of sqrt(6 / 2000) = 0.055.
  EXPECT_LT(quiet_skew, 0.2);

  const GateStudy again = RunGateStudy(scene, rig, *caster, options);
  for (std::size_t i = 0; i < gate.voxels.size(); ++i)
    for (int a = 0; a < 3; ++a)
      EXPECT_EQ(again.voxels[i].empirical[a], gate.voxels[i].empirical[a]);

  scene.study.pixel_sigma = 20;
  const GateStudy noisy = RunGateStudy(scene, rig, *caster, options);
  skews.clear();
  for (const GateVoxel& v : noisy.voxels) skews.push_back(std::abs(v.skew_major));
  std::sort(skews.begin(), skews.end());
  EXPECT_GT(skews[6], 0.3) << "median |skew| " << skews[6] << " vs " << quiet_skew;
  EXPECT_LT(noisy.PassShare(), 1.0);
}

TEST(SteadyStudy, RowsAgainstTheLongDoubleReference) {
  const Scene scene = RingRoom();  // no motion model: the "nominal" case
  AccuracyOptions options;
  options.min_timing_seconds = 1e-4;
  options.run_on_iterations = 2000;
  const SteadyStudy st = RunSteadyStudy(scene, MonteCarloStudy(), options);
  EXPECT_EQ(st.J, 1e6 * Mat3::Identity());  // no sample point: isotropic, sigma 1 mm
  EXPECT_NE(st.J_source.find("no triangulable sample point"), std::string::npos);
  ASSERT_EQ(st.cases.size(), 3u);
  EXPECT_EQ(st.cases[0].name, "nominal");
  ASSERT_EQ(st.rows.size(), 24u);  // 8 solvers x 3 cases
  for (const SteadyRow& r : st.rows) {
    EXPECT_GT(r.seconds, 0) << r.method;
    // Isotropic J: every axis has r = 1e-6 m^2.
    const double T = 1 / r.motion.rate_hz;
    EXPECT_DOUBLE_EQ(r.lambda_min, r.lambda_max);
    EXPECT_NEAR(r.lambda_min, std::sqrt(r.motion.q * T * T * T / 1e-6), 1e-9 * r.lambda_min);
    if (r.method == "closed form (ScalarSteadyState x 3)") {
      EXPECT_LT(r.error, 1e-15) << r.case_name;
      EXPECT_EQ(r.iterations, 0);
    }
    if (r.method == "doubling 2x2 in long double (reference check)") {
      EXPECT_LT(r.error, 5e-17) << r.case_name;
      int n = 0;
      SteadyPositionVarianceDoublingLong(r.motion.q, T, 1e-6L, &n);
      EXPECT_EQ(r.iterations, n);
    }
    if (r.run_on) {
      EXPECT_LE(r.iterations, 2000);  // stops early only at an exact fixed point
    }
    if (r.method == "doubling 6x6 (tol 1e-15)") {
      EXPECT_TRUE(r.converged);
      EXPECT_LT(r.error, 1e-12) << r.case_name;
    }
  }
  // Plain iteration at 1e-4 is far off at 1 MHz (slow convergence), doubling is not.
  double loose = 0;
  for (const SteadyRow& r : st.rows)
    if (r.case_name == "1 MHz" && r.method == "iteration 6x6 (tol 1e-04)") loose = r.error;
  EXPECT_GT(loose, 1e-3);
}

}  // namespace
}  // namespace pandora
