// Ceres triangulation and the Monte Carlo check of the predicted covariance (issue 3, point 5):
// noise-free pixels triangulate back exactly; at trauma-room sample points 10^4 noisy trials agree
// with J^-1 within 5%; the Monte Carlo error shrinks like 1/sqrt(trials).
#include "analysis/geometry/triangulation.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "tests/fixtures.h"

namespace pandora {
namespace {

// A 1280 x 960 camera (tests/fixtures.h) with Z up, an off-centre principal point and the lens
// model's coefficients (Brown-Conrady k1 k2 p1 p2 k3, fisheye k1..k4).
Camera MakeCamera(const std::string& id, const Vec3& position, const Vec3& target, LensModel model,
                  double hfov_deg, const std::array<double, 5>& coefficients = {}) {
  return testing::WithIntrinsics(
      testing::TestCamera(id, position, target, hfov_deg, 1280, 960, model, Vec3(0, 0, 1)),
      [&](Intrinsics& k) {
        k.cx += 7.3;  // off-centre principal point
        k.cy -= 4.1;
        if (model == LensModel::kBrownConrady) {
          k.k1 = coefficients[0];
          k.k2 = coefficients[1];
          k.p1 = coefficients[2];
          k.p2 = coefficients[3];
          k.k3 = coefficients[4];
        } else if (model == LensModel::kFisheye) {
          k.k1 = coefficients[0];
          k.k2 = coefficients[1];
          k.k3 = coefficients[2];
          k.k4 = coefficients[3];
        }
      });
}

// Three rigs around a point near (0.3, -0.2, 1.1): pinhole, strongly distorted Brown-Conrady (all
// five coefficients), fisheye.
std::vector<std::vector<Camera>> SyntheticRigs(const Vec3& target) {
  const std::array<double, 5> bc{-0.28, 0.09, 0.0012, -0.0008, -0.012};
  const std::array<double, 5> fe{0.05, -0.01, 0.003, -0.0005, 0};
  return {
      {MakeCamera("p0", Vec3(2.0, 0.5, 2.2), target, LensModel::kPinhole, 50),
       MakeCamera("p1", Vec3(-1.5, 1.0, 1.8), target, LensModel::kPinhole, 60)},
      {MakeCamera("b0", Vec3(2.0, -1.5, 2.4), target, LensModel::kBrownConrady, 70, bc),
       MakeCamera("b1", Vec3(-1.8, -1.2, 2.0), target, LensModel::kBrownConrady, 80, bc),
       MakeCamera("b2", Vec3(0.2, 2.5, 0.6), target, LensModel::kBrownConrady, 65, bc),
       MakeCamera("b3", Vec3(0.5, 0.3, 3.2), target + Vec3(0.4, 0.2, 0), LensModel::kBrownConrady,
                  75, bc)},
      {MakeCamera("f0", Vec3(1.2, 1.2, 2.6), target + Vec3(0.3, 0, 0), LensModel::kFisheye, 180,
                  fe),
       MakeCamera("f1", Vec3(-1.0, -1.4, 2.6), target, LensModel::kFisheye, 150, fe),
       MakeCamera("f2", Vec3(-1.6, 1.0, 0.4), target, LensModel::kFisheye, 190, fe)},
  };
}

std::vector<Vec2> TruePixels(const std::vector<Camera>& cams, const Vec3& X) {
  std::vector<Vec2> pixels;
  for (const Camera& c : cams) {
    const std::optional<Vec2> p = c.Project(X);
    EXPECT_TRUE(p.has_value()) << c.id;
    pixels.push_back(p.value_or(Vec2::Zero()));
  }
  return pixels;
}

TEST(TriangulatePoint, NoiseFreePixelsGiveBackThePoint) {
  const Vec3 target(0.3, -0.2, 1.1);
  int rig_index = 0;
  double worst = 0;
  for (const std::vector<Camera>& cams : SyntheticRigs(target)) {
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(0.2, -0.15, 0.1), Vec3(-0.25, 0.1, -0.2)}) {
      const Vec3 X = target + offset;
      const std::vector<Vec2> pixels = TruePixels(cams, X);
      const std::vector<double> sigmas(cams.size(), 0.5);
      for (const Vec3& start_offset : {Vec3(0.05, 0.03, -0.04), Vec3(-0.1, 0.08, 0.06)}) {
        const std::optional<Vec3> estimate =
            TriangulatePoint(cams, pixels, sigmas, X + start_offset);
        ASSERT_TRUE(estimate.has_value()) << "rig " << rig_index;
        worst = std::max(worst, (*estimate - X).norm() / X.norm());
        EXPECT_LE((*estimate - X).norm(), 1e-9 * X.norm())
            << "rig " << rig_index << " X " << X.transpose() << " error " << (*estimate - X).norm();
      }
    }
    ++rig_index;
  }
  std::printf("noise-free triangulation, worst relative error %.2e\n", worst);
}

TEST(TriangulatePoint, TraumaRoomRigsNoiseFree) {
  LoadOptions cameras_only;
  cameras_only.load_meshes = false;
  const Scene scene = LoadScene("examples/trauma_room/scene.json", cameras_only);
  const Vec3 X = scene.study.region.box.center();
  for (const char* name : {"grid4x2", "octagon"}) {
    const Rig& rig = scene.FindRig(name);
    const std::vector<Vec2> pixels = TruePixels(rig.cameras, X);
    const std::optional<Vec3> estimate = TriangulatePoint(
        rig.cameras, pixels, std::vector<double>(rig.cameras.size(), 0.5), X + Vec3(0.03, 0, 0.02));
    ASSERT_TRUE(estimate.has_value()) << name;
    EXPECT_LE((*estimate - X).norm(), 1e-9 * X.norm()) << name;
  }
}

TEST(TriangulatePoint, ExpectedFailuresAreValues) {
  const Vec3 target(0.3, -0.2, 1.1);
  const std::vector<Camera> cams = SyntheticRigs(target)[0];
  const std::vector<Vec2> pixels = TruePixels(cams, target);
  const std::vector<double> sigmas(2, 1.0);
  // One camera cannot triangulate.
  EXPECT_FALSE(TriangulatePoint({cams[0]}, {pixels[0]}, {1.0}, target).has_value());
  // A start behind a camera does not project.
  const Vec3 behind = cams[0].center() + (cams[0].center() - target);
  EXPECT_FALSE(TriangulatePoint(cams, pixels, sigmas, behind).has_value());
  // Bad arguments throw.
  EXPECT_THROW(TriangulatePoint(cams, {pixels[0]}, sigmas, target), std::invalid_argument);
  EXPECT_THROW(TriangulatePoint(cams, pixels, {1.0, 0.0}, target), std::invalid_argument);
  EXPECT_THROW(MonteCarloCovariance({cams[0]}, target, 0.5, 100, 1), std::invalid_argument);
  EXPECT_THROW(MonteCarloCovariance(cams, target, 0.5, 1, 1), std::invalid_argument);
}

TEST(MonteCarlo, IndependentOfThreadCount) {
  const Vec3 target(0.3, -0.2, 1.1);
  const std::vector<Camera> cams = SyntheticRigs(target)[1];
  const MonteCarloResult many = MonteCarloCovariance(cams, target, 0.5, 500, 42);
  MonteCarloResult one;
  tbb::task_arena arena(1);
  arena.execute([&] { one = MonteCarloCovariance(cams, target, 0.5, 500, 42); });
  EXPECT_EQ(many.empirical_covariance, one.empirical_covariance);
  EXPECT_EQ(many.failures, one.failures);
  // A different seed gives different noise.
  const MonteCarloResult other = MonteCarloCovariance(cams, target, 0.5, 500, 43);
  EXPECT_NE(other.empirical_covariance, many.empirical_covariance);
}

// Deterministic sample points of the study region: the centres of its 3 x 3 x 3 lattice cells, kept
// when at least two cameras see them (Embree visibility over the whole scene; the region holds the
// patient's neck, so many are inside it or hidden), then `wanted` of them spread evenly over that
// list.
struct SamplePoint {
  Vec3 X;
  std::vector<Camera> cameras;
};

std::vector<SamplePoint> SamplePoints(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                      std::size_t wanted) {
  const VisibilityTester tester(rig.cameras, caster, scene.Bounds().diagonal());
  const Aabb& box = scene.study.region.box;
  std::vector<SamplePoint> seen;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        const Vec3 X =
            box.min + Vec3((i + 0.5) / 3, (j + 0.5) / 3, (k + 0.5) / 3).cwiseProduct(box.size());
        SamplePoint p{X, {}};
        for (int c = 0; c < static_cast<int>(rig.cameras.size()); ++c)
          if (tester.Test(c, X) == ViewResult::kSeen) p.cameras.push_back(rig.cameras[c]);
        if (p.cameras.size() >= 2) seen.push_back(std::move(p));
      }
    }
  }
  if (seen.size() <= wanted) return seen;
  std::vector<SamplePoint> points;
  for (std::size_t q = 0; q < wanted; ++q)
    points.push_back(seen[q * (seen.size() - 1) / (wanted - 1)]);
  return points;
}

TEST(MonteCarlo, AgreesWithPredictionAtTraumaRoomPoints) {
  const Scene scene = LoadScene("examples/trauma_room/scene.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const double sigma = scene.study.pixel_sigma;
  const int trials = 10000;
  std::printf("Monte Carlo (%d trials, sigma %.2f px) against J^-1, trauma room:\n", trials, sigma);
  std::printf("%-8s %-24s %4s %12s %12s %8s %8s %10s %6s %7s\n", "rig", "X (m)", "cams",
              "sigma_max_p", "sigma_max_e", "rel_err", "frob_err", "|bias|", "fail", "sec");
  uint64_t seed = 1;
  for (const char* name : {"grid4x2", "octagon"}) {
    const std::vector<SamplePoint> points = SamplePoints(scene, scene.FindRig(name), *caster, 5);
    ASSERT_EQ(points.size(), 5u) << name << ": too few sample points seen by two cameras";
    for (const SamplePoint& p : points) {
      const MonteCarloResult r = MonteCarloCovariance(p.cameras, p.X, sigma, trials, seed++);
      std::printf(
          "%-8s (%6.3f, %6.3f, %6.3f) %4zu %9.4f mm %9.4f mm %7.2f%% %7.2f%% %7.4f mm %6d %7.3f\n",
          name, p.X.x(), p.X.y(), p.X.z(), p.cameras.size(), 1e3 * r.sigma_max_predicted,
          1e3 * r.sigma_max_empirical, 100 * r.relative_error, 100 * r.frobenius_relative_error,
          1e3 * r.mean_minus_true.norm(), r.failures, r.seconds);
      EXPECT_EQ(r.failures, 0) << name;
      EXPECT_LT(r.relative_error, 0.05) << name << " X " << p.X.transpose();
      EXPECT_LT(r.frobenius_relative_error, 0.05) << name << " X " << p.X.transpose();
      // The bias of the nonlinear estimator is far below its spread at pixel-level noise.
      EXPECT_LT(r.mean_minus_true.norm(), 0.1 * r.sigma_max_predicted) << name;
    }
  }
}

TEST(MonteCarlo, ErrorShrinksLikeOneOverSqrtTrials) {
  // Two pinhole cameras and one distorted camera about 2 m from the point, 0.5 px noise: the
  // nonlinearity bias (~ sigma_max / distance ~ 1e-3 relative) is far below the statistical error
  // even at the largest N.
  const Vec3 X(0.3, -0.2, 1.1);
  const std::vector<std::vector<Camera>> rigs = SyntheticRigs(X);
  const std::vector<Camera> cams{rigs[0][0], rigs[0][1], rigs[1][2]};
  const std::vector<int> Ns{100, 400, 1600, 6400};
  const int seeds = 8;
  std::vector<double> log_n, log_err;
  std::printf("Monte Carlo error against trials (mean over %d seeds, Frobenius relative):\n",
              seeds);
  std::printf("%6s %10s %10s %14s\n", "N", "frob_err", "sigma_err", "err*sqrt(N)");
  for (int N : Ns) {
    double frob = 0, rel = 0;
    for (int s = 0; s < seeds; ++s) {
      const MonteCarloResult r = MonteCarloCovariance(cams, X, 0.5, N, 1000003ULL * N + s);
      EXPECT_EQ(r.failures, 0);
      frob += r.frobenius_relative_error / seeds;
      rel += r.relative_error / seeds;
    }
    std::printf("%6d %9.3f%% %9.3f%% %14.3f\n", N, 100 * frob, 100 * rel, frob * std::sqrt(N));
    log_n.push_back(std::log(N));
    log_err.push_back(std::log(frob));
  }
  // Least-squares slope of log(error) against log(N).
  const double n = static_cast<double>(log_n.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < log_n.size(); ++i) {
    mx += log_n[i] / n;
    my += log_err[i] / n;
  }
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < log_n.size(); ++i) {
    sxy += (log_n[i] - mx) * (log_err[i] - my);
    sxx += (log_n[i] - mx) * (log_n[i] - mx);
  }
  const double slope = sxy / sxx;
  std::printf("fitted log-log slope %.3f (expected -0.5)\n", slope);
  EXPECT_GE(slope, -0.7);
  EXPECT_LE(slope, -0.3);
}

}  // namespace
}  // namespace pandora
