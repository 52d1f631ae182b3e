// Stability suite for triangulation uncertainty: every case against its closed form, or flagged not
// triangulable; never NaN. Steady state: closed form against doubling and long Riccati iteration.
#include "analysis/geometry/uncertainty.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <cmath>
#include <random>

#include "analysis/geometry/camera.h"
#include "analysis/util/units.h"
#include "tests/fixtures.h"

namespace pandora {
namespace {

Camera Pinhole(const Vec3& position, const Vec3& target, double f_px, int w = 2000, int h = 2000,
               const Vec3& up = Vec3(0, 0, 1)) {
  Camera c = testing::WithIntrinsics(
      testing::TestCamera("", position, target, 60, w, h, LensModel::kPinhole, up),
      [&](Intrinsics& k) { k.fx = k.fy = f_px; });
  return c;
}

// Information from the cameras that project X (all assumed to see it).
Information InformationAt(const std::vector<Camera>& cams, const Vec3& X, double sigma) {
  InformationBuilder b;
  for (const Camera& c : cams) {
    Mat23 J;
    EXPECT_TRUE(c.Project(X, &J).has_value());
    b.Add(J, sigma);
  }
  return b.Decompose();
}

void ExpectFinite(const StaticUncertainty& s) {
  EXPECT_TRUE(std::isfinite(s.sigma_max) && std::isfinite(s.sigma_mean) &&
              std::isfinite(s.condition));
  EXPECT_TRUE(s.covariance.allFinite());
}

// Rectified stereo: sigma_Z = Z^2 sqrt(2) sigma / (f B) exactly for a point on the midline.
TEST(StaticUncertainty, RectifiedStereoDepth) {
  const double f = 1200, B = 0.12, sigma = 0.5;
  for (double Z : {0.5, 2.0, 10.0, 50.0}) {
    std::vector<Camera> cams{Pinhole(Vec3(-B / 2, 0, 0), Vec3(-B / 2, Z, 0), f),
                             Pinhole(Vec3(B / 2, 0, 0), Vec3(B / 2, Z, 0), f)};
    const StaticUncertainty s = StaticFromInformation(InformationAt(cams, Vec3(0, Z, 0), sigma), 2);
    ASSERT_TRUE(s.triangulable);
    const double expected = Z * Z * std::sqrt(2.0) * sigma / (f * B);
    EXPECT_NEAR(std::sqrt(s.covariance(1, 1)), expected, 1e-9 * expected) << "Z " << Z;
    // Lateral: each camera constrains X with f/Z; two of them: sigma_X = Z sigma / (f sqrt(2)).
    EXPECT_NEAR(std::sqrt(s.covariance(0, 0)), Z * sigma / (f * std::sqrt(2.0)),
                1e-9 * Z * sigma / f);
    ExpectFinite(s);
  }
}

// Two cameras at distance D converging at angle theta: sigma_max = sigma D / (f sqrt(1 - cos
// theta)), cond(J) = 2 / (1 - cos theta) ~ 4 / theta^2.
TEST(StaticUncertainty, ConvergingCameras) {
  const double f = 1000, D = 3.0, sigma = 0.3;
  for (double deg : {90.0, 10.0, 1.0, 0.1}) {
    const double t = deg * kPi / 180.0;
    const Vec3 X(0.2, -0.1, 1.5);
    std::vector<Camera> cams{Pinhole(X + D * Vec3(std::sin(t / 2), -std::cos(t / 2), 0), X, f),
                             Pinhole(X + D * Vec3(-std::sin(t / 2), -std::cos(t / 2), 0), X, f)};
    const StaticUncertainty s = StaticFromInformation(InformationAt(cams, X, sigma), 2);
    ASSERT_TRUE(s.triangulable) << deg;
    const double one_minus_cos = 2 * std::pow(std::sin(t / 2), 2);
    const double expected = sigma * D / (f * std::sqrt(one_minus_cos));
    EXPECT_NEAR(s.sigma_max, expected, 1e-7 * expected) << deg << " deg";
    EXPECT_NEAR(s.condition, 2.0 / one_minus_cos, 1e-6 * 2.0 / one_minus_cos) << deg << " deg";
    ExpectFinite(s);
  }
}

TEST(StaticUncertainty, SingleCameraIsNotTriangulable) {
  std::vector<Camera> cams{Pinhole(Vec3(0, 0, 0), Vec3(0, 1, 0), 800)};
  const Information info = InformationAt(cams, Vec3(0.1, 2, 0.05), 0.5);
  EXPECT_FALSE(info.observable);  // rank 2: nothing along the ray
  const StaticUncertainty s = StaticFromInformation(info, 1);
  EXPECT_FALSE(s.triangulable);
  EXPECT_EQ(s.sigma_max, 0.0);  // not NaN, not a pseudo-inverse value
  ExpectFinite(s);
}

TEST(StaticUncertainty, CamerasOneNanometreApartAreFlagged) {
  const Vec3 X(0, 2, 0);
  std::vector<Camera> cams{Pinhole(Vec3(0, 0, 0), X, 800), Pinhole(Vec3(1e-9, 0, 0), X, 800)};
  const Information info = InformationAt(cams, X, 0.5);
  EXPECT_FALSE(info.observable);
  const StaticUncertainty s = StaticFromInformation(info, 2);
  EXPECT_FALSE(s.triangulable);
  ExpectFinite(s);
}

// Scale: the same rig scaled by k gives sigma scaled by k, from 1 mm to 10 km.
TEST(StaticUncertainty, ScaleInvariance) {
  const double f = 1000, sigma = 0.5;
  for (double k : {1e-3, 1.0, 1e4}) {
    const Vec3 X = k * Vec3(0.1, 1.0, 0.05);
    std::vector<Camera> cams{Pinhole(k * Vec3(-0.5, 0, 0), X, f),
                             Pinhole(k * Vec3(0.5, 0, 0), X, f),
                             Pinhole(k * Vec3(0, 0, 0.6), X, f)};
    const StaticUncertainty s = StaticFromInformation(InformationAt(cams, X, sigma), 3);
    ASSERT_TRUE(s.triangulable);
    std::vector<Camera> unit{Pinhole(Vec3(-0.5, 0, 0), X / k, f),
                             Pinhole(Vec3(0.5, 0, 0), X / k, f),
                             Pinhole(Vec3(0, 0, 0.6), X / k, f)};
    const StaticUncertainty u = StaticFromInformation(InformationAt(unit, X / k, sigma), 3);
    EXPECT_NEAR(s.sigma_max, k * u.sigma_max, 1e-9 * k * u.sigma_max) << k;
    EXPECT_NEAR(s.condition, u.condition, 1e-7 * u.condition) << k;
  }
  // A point 1 mm and one 10 km in front of a 10 cm stereo pair: sigma_Z by the stereo formula.
  for (double Z : {1e-3, 1e4}) {
    const double B = 0.1;
    std::vector<Camera> cams{Pinhole(Vec3(-B / 2, 0, 0), Vec3(-B / 2, Z, 0), f),
                             Pinhole(Vec3(B / 2, 0, 0), Vec3(B / 2, Z, 0), f)};
    const Vec3 X(0, Z, 0);
    if (Z < B) {
      // 1 mm away the point is 50 mm off each optical axis at 1 mm depth: outside any sane FOV,
      // but the maths still holds: compare with the exact inverse of J built by hand.
      cams = {Pinhole(Vec3(-B / 2, 0, 0), X, f), Pinhole(Vec3(B / 2, 0, 0), X, f)};
    }
    const StaticUncertainty s = StaticFromInformation(InformationAt(cams, X, sigma), 2);
    ASSERT_TRUE(s.triangulable) << Z;
    ExpectFinite(s);
    if (Z > B) {
      const double expected = Z * Z * std::sqrt(2.0) * sigma / (f * B);
      EXPECT_NEAR(std::sqrt(s.covariance(1, 1)), expected, 1e-8 * expected);
    } else {
      // Converging at 2 atan(0.05 / 0.001): the closed form of the converging test.
      const double d = std::hypot(B / 2, Z), t = 2 * std::atan2(B / 2, Z);
      const double expected = sigma * d / (f * std::sqrt(2 * std::pow(std::sin(t / 2), 2)));
      const double lateral = sigma * d / (f * std::sqrt(1 + std::cos(t)));
      EXPECT_NEAR(s.sigma_max, std::max(expected, lateral), 1e-9 * std::max(expected, lateral));
    }
  }
}

// Extreme lenses: the covariance is the exact inverse of the information the camera model's
// Jacobians give (checked by J Cov = I), finite, or the point is flagged.
TEST(StaticUncertainty, ExtremeLenses) {
  auto lens = [](LensModel model, double hfov_deg, double k1, double k2) {
    Intrinsics k;
    k.width = 1000;
    k.height = 1000;
    k.model = model;
    k.fx = k.fy = FocalFromHfov(hfov_deg * kPi / 180, k.width, model);
    k.cx = k.cy = 499.5;
    k.k1 = k1;
    k.k2 = k2;
    return CameraModel(k);
  };
  struct Case {
    const char* name;
    CameraModel model;
    double off_axis_deg;  // where the point sits in each camera
  };
  const double rmax_k1 = std::sqrt(-1.0 / (3 * -0.3));  // domain edge for k1 = -0.3 alone
  const std::vector<Case> cases{
      {"pinhole 170 deg near edge", lens(LensModel::kPinhole, 170, 0, 0), 84.0},
      {"fisheye 190 deg at 94 deg", lens(LensModel::kFisheye, 190, 0, 0), 94.0},
      {"brown-conrady at 0.999 of its domain", lens(LensModel::kBrownConrady, 120, -0.3, 0),
       std::atan(0.999 * rmax_k1) * 180 / kPi},
  };
  for (const Case& c : cases) {
    // Two cameras 1 m from X, 60 degrees apart, each rotated so X appears off_axis_deg off-axis.
    const Vec3 X(0, 0, 0);
    InformationBuilder b;
    for (double side : {-1.0, 1.0}) {
      const double a = side * 30 * kPi / 180;
      const Vec3 C = Vec3(std::sin(a), -std::cos(a), 0);
      // Aim the optical axis off_axis_deg away from X, rotating about the vertical.
      const double off = c.off_axis_deg * kPi / 180;
      const Vec3 to_x = (X - C).normalized();
      const Vec3 axis = Eigen::AngleAxisd(off, Vec3::UnitZ()) * to_x;
      Camera cam;
      cam.model = c.model;
      cam.world_from_camera = LookAt(C, C + axis, Vec3(0, 0, 1)).value();
      Mat23 J;
      const auto px = cam.Project(X, &J);
      ASSERT_TRUE(px.has_value()) << c.name;
      ASSERT_TRUE(J.allFinite()) << c.name;
      b.Add(J, 0.5);
    }
    const Information info = b.Decompose();
    const StaticUncertainty s = StaticFromInformation(info, 2);
    ExpectFinite(s);
    if (s.triangulable) {
      const Mat3 should_be_identity = info.J * s.covariance;
      EXPECT_LT((should_be_identity - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-6 * s.condition)
          << c.name;
    }
    std::printf("%-40s triangulable %d sigma_max %.4g m cond %.3g\n", c.name, s.triangulable,
                s.sigma_max, s.condition);
  }
}

TEST(DecomposeInformation, EigenvaluesOnlyMatchIterativeSolverFromEasyToStiff) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n;
  for (double cond : {1.0, 3.0, 1e2, 1e4, 1e6, 1e7, 1e9, 1e13}) {
    for (int trial = 0; trial < 50; ++trial) {
      Mat3 A;
      for (int i = 0; i < 9; ++i) A.data()[i] = n(rng);
      const Mat3 Q = Eigen::HouseholderQR<Mat3>(A).householderQ();
      const Vec3 lambda(1.0 / cond, 0.3 + 0.7 * std::abs(n(rng)) / 3, 1.0);
      const Mat3 J = 1e5 * (Q * lambda.asDiagonal() * Q.transpose());
      const Vec3 fast = DecomposeInformation(J, /*eigenvectors=*/false).eigenvalues;
      const Vec3 reference =
          Eigen::SelfAdjointEigenSolver<Mat3>(J, Eigen::EigenvaluesOnly).eigenvalues();
      // Absolute accuracy relative to the largest eigenvalue, as any symmetric solver; at an exact
      // double root (cond = 1 here: two eigenvalues equal) the closed form is good to about
      // sqrt(eps), still far below the float the fields are stored in.
      const double tol = (cond == 1.0 ? 1e-8 : 1e-13) * reference[2];
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(fast[k], reference[k], tol) << "cond " << cond << " k " << k;
    }
  }
}

// The batched Jacobi eigenvalues against a long-double reference (QL iteration, 64-bit mantissa) on
// random spectra from equal eigenvalues to condition 1e13, scaled from 1e-6 to 1e18, plus exact
// cases: diagonal, zero, rank one.
TEST(SymmetricEigenvalues3, MatchLongDoubleReferenceAtEveryConditioning) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n;
  std::vector<Mat3> cases;
  for (double scale : {1e-6, 1.0, 1e5, 1e18})
    for (double cond : {1.0, 3.0, 1e2, 1e4, 1e6, 1e7, 1e9, 1e13})
      for (int trial = 0; trial < 20; ++trial) {
        Mat3 A;
        for (int i = 0; i < 9; ++i) A.data()[i] = n(rng);
        const Mat3 Q = Eigen::HouseholderQR<Mat3>(A).householderQ();
        // Trials alternate a double root at the top, at the bottom, and a spread spectrum.
        const double mid = trial % 3 == 0   ? 1.0
                           : trial % 3 == 1 ? 1.0 / cond
                                            : 0.3 + 0.2 * n(rng) / 3;
        const Vec3 lambda(1.0 / cond, mid, 1.0);
        const Mat3 J = scale * (Q * lambda.asDiagonal() * Q.transpose());
        cases.push_back(0.5 * (J + J.transpose()));
      }
  cases.push_back(Vec3(3.0, 1e-9, 2.0).asDiagonal());
  cases.push_back(Mat3::Zero());
  const Vec3 a(1.0, -2.0, 0.5);
  cases.push_back(a * a.transpose());
  const std::size_t count = cases.size();
  std::vector<double> in[6], out[3];
  for (auto& v : in) v.resize(count);
  for (auto& v : out) v.resize(count);
  const int index[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
  for (std::size_t i = 0; i < count; ++i)
    for (int k = 0; k < 6; ++k) in[k][i] = cases[i](index[k][0], index[k][1]);
  const double* upper[6];
  for (int k = 0; k < 6; ++k) upper[k] = in[k].data();
  double* values[3] = {out[0].data(), out[1].data(), out[2].data()};
  std::vector<unsigned char> converged(count, 7);
  SymmetricEigenvalues3(upper, values, converged.data(), count);
  for (std::size_t i = 0; i < count; ++i) {
    const Eigen::Matrix<long double, 3, 3> J = cases[i].cast<long double>();
    const auto reference =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix<long double, 3, 3>>(J, Eigen::EigenvaluesOnly)
            .eigenvalues();
    const double largest = static_cast<double>(reference[2]);
    EXPECT_EQ(converged[i], 1) << "case " << i;
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(out[k][i], static_cast<double>(reference[k]), 2e-15 * largest + 1e-300)
          << "case " << i << " k " << k;
  }
  // Exact cases: the diagonal comes back sorted (to the ulps of scaling by 1/3 and back), zero
  // stays zero, rank one is (0, 0, |a|^2).
  const std::size_t d = count - 3;
  EXPECT_DOUBLE_EQ(out[0][d], 1e-9);
  EXPECT_DOUBLE_EQ(out[1][d], 2.0);
  EXPECT_DOUBLE_EQ(out[2][d], 3.0);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(out[k][d + 1], 0.0);
  EXPECT_NEAR(out[2][d + 2], a.squaredNorm(), 1e-15 * a.squaredNorm());
  EXPECT_NEAR(out[0][d + 2], 0.0, 1e-15 * a.squaredNorm());
}

TEST(MaxTriangulationAngle, IsAccurateAtTinyAndLargeAngles) {
  for (double t : {1e-9, 1e-3, 0.5, 3.0, kPi - 1e-9}) {
    std::vector<Vec3> d{Vec3(1, 0, 0), Vec3(std::cos(t), std::sin(t), 0),
                        Vec3(1, 1e-12, 0).normalized()};
    EXPECT_NEAR(MaxTriangulationAngle(d), t, 1e-15 + 1e-12 * t);
  }
  EXPECT_EQ(MaxTriangulationAngle({Vec3(1, 0, 0)}), 0.0);
}

// ---- Steady state -------------------------------------------------------------------------------

Eigen::Matrix2d ScalarViaDoubling(double q, double T, double r, bool prior) {
  Eigen::MatrixXd F(2, 2), G(2, 2), Q(2, 2);
  F << 1, T, 0, 1;
  G << 1 / r, 0, 0, 0;
  Q << T * T * T / 3, T * T / 2, T * T / 2, T;
  Q *= q;
  const auto M = SolveDareDoubling(F, G, Q);
  EXPECT_TRUE(M.has_value());
  if (!M) return Eigen::Matrix2d::Constant(NAN);
  return prior ? Eigen::Matrix2d(*M) : Eigen::Matrix2d(PosteriorFromPrior(*M, G));
}

TEST(SteadyState, ClosedFormMatchesDoublingAndRiccati) {
  const double r = 1e-6;  // (1 mm)^2 per frame
  for (double q : {1e-12, 1e-6, 1.0, 1e8}) {
    for (double rate : {1.0, 60.0, 1e6}) {
      const double T = 1 / rate;
      for (bool prior : {false, true}) {
        const Eigen::Matrix2d closed = ScalarSteadyState(q, T, r, prior);
        ASSERT_TRUE(closed.allFinite());
        EXPECT_EQ(SteadyPositionVariance(q, T, r, prior), closed(0, 0));
        const Eigen::Matrix2d doubling = ScalarViaDoubling(q, T, r, prior);
        // The reference's posterior is (I + M G)^-1 M, which loses about cond(I + M G) * eps
        // relative accuracy when stiff (the closed form does not); the prior is exact to 1e-9.
        const double cond = 1 + ScalarSteadyState(q, T, r, true)(0, 0) / r;
        const double tol = prior ? 1e-9 : 1e-9 + 4e-16 * cond;
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j)
            EXPECT_NEAR(closed(i, j), doubling(i, j), tol * std::abs(closed(i, j)) + 1e-300)
                << "q " << q << " rate " << rate << " prior " << prior << " (" << i << j << ")";
        // Positive definite (q > 0): a valid covariance.
        EXPECT_GT(closed(0, 0), 0);
        EXPECT_GT(closed.determinant(), 0) << q << " " << rate;
      }
    }
  }
  // Where plain iteration converges (not stiff), it agrees too.
  for (double q : {1e-3, 1.0, 100.0}) {
    const double T = 1 / 60.0;
    Eigen::MatrixXd F(2, 2), G(2, 2), Q(2, 2);
    F << 1, T, 0, 1;
    G << 1 / r, 0, 0, 0;
    Q << T * T * T / 3, T * T / 2, T * T / 2, T;
    Q *= q;
    bool converged = false;
    int iterations = 0;
    const Eigen::MatrixXd M = SolveDareIteration(F, G, Q, 1e-15, 1000000, &converged, &iterations);
    ASSERT_TRUE(converged) << q;
    const Eigen::Matrix2d closed = ScalarSteadyState(q, T, r, true);
    EXPECT_NEAR(M(0, 0), closed(0, 0), 1e-9 * closed(0, 0)) << q << " after " << iterations;
  }
}

TEST(SteadyState, LimitsAreExact) {
  const double r = 4e-6, T = 0.01;
  // No process noise: the filter converges to certainty.
  const Eigen::Matrix2d zero = ScalarSteadyState(0.0, T, r);
  EXPECT_EQ(zero(0, 0), 0.0);
  EXPECT_EQ(zero(1, 1), 0.0);
  // Huge process noise: the filter trusts each frame alone, the posterior tends to r.
  const Eigen::Matrix2d wild = ScalarSteadyState(1e30, T, r);
  EXPECT_NEAR(wild(0, 0), r, 1e-6 * r);
  // Tiny q: variance ~ (q r^3 T^-1)^(1/4) * sqrt(2) * ... just monotone and finite, no NaN.
  double previous = 0;
  for (double q : {1e-30, 1e-20, 1e-12, 1e-6, 1.0, 1e8, 1e20}) {
    const Eigen::Matrix2d P = ScalarSteadyState(q, T, r);
    ASSERT_TRUE(P.allFinite()) << q;
    EXPECT_GT(P(0, 0), previous) << q;
    EXPECT_LE(P(0, 0), r) << q;  // never worse than one frame alone
    previous = P(0, 0);
  }
  // No measurement: no steady state.
  EXPECT_FALSE(ScalarSteadyState(1.0, T, std::numeric_limits<double>::infinity()).allFinite());
}

// The decoupled 3D solution equals the full 6x6 doubling solution.
TEST(SteadyState, DecoupledMatchesFull6x6) {
  const double f = 1000, sigma = 0.5;
  const Vec3 X(0.1, 2.0, 0.3);
  std::vector<Camera> cams{Pinhole(Vec3(-1, 0, 0.5), X, f), Pinhole(Vec3(1, 0, 1.5), X, f),
                           Pinhole(Vec3(0.2, 0.3, 2.5), X, f)};
  const Information info = InformationAt(cams, X, sigma);
  for (const MotionModel motion :
       {MotionModel{1e-4, 30}, MotionModel{1.0, 120}, MotionModel{1e6, 1e6}}) {
    for (bool prior : {false, true}) {
      const SteadyUncertainty s = SteadyFromInformation(info, 3, motion, prior);
      ASSERT_TRUE(s.converged);
      const ConstantVelocity6 m = MakeConstantVelocity6(info.J, motion);
      const auto M = SolveDareDoubling(m.F, m.G, m.Q);
      ASSERT_TRUE(M.has_value());
      const Eigen::MatrixXd full = prior ? *M : PosteriorFromPrior(*M, m.G);
      const Mat3 position = full.block<3, 3>(0, 0);
      EXPECT_LT((position - s.covariance).cwiseAbs().maxCoeff(), 1e-8 * s.covariance.norm())
          << motion.q << " " << motion.rate_hz << " prior " << prior;
    }
  }
}

}  // namespace
}  // namespace pandora
