#include "analysis/geometry/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "analysis/util/units.h"

namespace pandora {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Cameras used throughout.

// 1920x1080 barrel lens, principal point slightly off-centre.
Intrinsics BarrelIntrinsics() {
  Intrinsics k;
  k.width = 1920;
  k.height = 1080;
  k.fx = 1400;
  k.fy = 1402;
  k.cx = 959.5 + 3.2;
  k.cy = 539.5 - 2.1;
  k.model = LensModel::kBrownConrady;
  k.k1 = -0.28;
  k.k2 = 0.07;
  k.p1 = 1e-4;
  k.p2 = -2e-4;
  k.k3 = 0;
  return k;
}

// Mild pincushion.
Intrinsics PincushionIntrinsics() {
  Intrinsics k = BarrelIntrinsics();
  k.k1 = 0.05;
  k.k2 = 0;
  k.p1 = -3e-4;
  k.p2 = 1e-4;
  return k;
}

// 190 degree fisheye with coefficients typical of an OpenCV calibration.
Intrinsics FisheyeIntrinsics() {
  Intrinsics k;
  k.width = 1920;
  k.height = 1080;
  k.model = LensModel::kFisheye;
  k.fx = FocalFromHfov(Rad(190), k.width, LensModel::kFisheye);
  k.fy = k.fx * 1.001;
  k.cx = 959.5 - 4.0;
  k.cy = 539.5 + 1.5;
  k.k1 = 0.05;
  k.k2 = -0.01;
  k.k3 = 0.002;
  k.k4 = -0.0003;
  return k;
}

Intrinsics PinholeIntrinsics(double hfov_deg, int width, int height) {
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.model = LensModel::kPinhole;
  k.fx = k.fy = FocalFromHfov(Rad(hfov_deg), width, LensModel::kPinhole);
  k.cx = 0.5 * (width - 1);
  k.cy = 0.5 * (height - 1);
  return k;
}

// ---------------------------------------------------------------------------------------------
// Helpers.

// Central finite-difference Jacobian of `f` at `p` with step `h`; false if any evaluation fails.
bool NumericJacobian(const std::function<std::optional<Vec2>(const Vec3&)>& f, const Vec3& p,
                     double h, Mat23* jacobian) {
  for (int i = 0; i < 3; ++i) {
    Vec3 plus = p, minus = p;
    plus(i) += h;
    minus(i) -= h;
    const std::optional<Vec2> fp = f(plus), fm = f(minus);
    if (!fp || !fm) return false;
    jacobian->col(i) = (*fp - *fm) / (2 * h);
  }
  return true;
}

// Largest entry difference relative to the largest entry of `reference`.
double RelativeError(const Mat23& value, const Mat23& reference) {
  return (value - reference).cwiseAbs().maxCoeff() / reference.cwiseAbs().maxCoeff();
}

// Checks the analytic Jacobian of `model` at `p` against finite differences.
void ExpectJacobianMatches(const CameraModel& model, const Vec3& p, double tolerance = 1e-6) {
  Mat23 analytic;
  ASSERT_TRUE(model.Project(p, &analytic)) << p.transpose();
  Mat23 numeric;
  ASSERT_TRUE(NumericJacobian([&](const Vec3& q) { return model.Project(q); }, p, 1e-5 * p.norm(),
                              &numeric))
      << p.transpose();
  EXPECT_LT(RelativeError(analytic, numeric), tolerance) << "at " << p.transpose() << "\nanalytic\n"
                                                         << analytic << "\nnumeric\n"
                                                         << numeric;
}

// Angle between two directions, accurate for tiny angles.
double AngleBetween(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Random pixel in the image rectangle [-0.5, w-0.5] x [-0.5, h-0.5].
Vec2 RandomPixel(const CameraModel& model, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-0.5, model.width() - 0.5);
  std::uniform_real_distribution<double> v(-0.5, model.height() - 0.5);
  return Vec2(u(rng), v(rng));
}

// Unproject then Project at `count` random pixels; returns the largest pixel error and counts the
// pixels that did not unproject.
double MaxPixelRoundTripError(const CameraModel& model, int count, int* failures) {
  std::mt19937 rng(12345);
  double max_error = 0;
  *failures = 0;
  for (int i = 0; i < count; ++i) {
    const Vec2 pixel = RandomPixel(model, rng);
    const std::optional<Vec3> ray = model.Unproject(pixel);
    if (!ray) {
      ++*failures;
      continue;
    }
    EXPECT_NEAR(ray->norm(), 1.0, 1e-15);
    const std::optional<Vec2> back = model.Project(*ray * 3.7);
    if (!back) {
      ++*failures;
      continue;
    }
    max_error = std::max(max_error, (*back - pixel).norm());
  }
  return max_error;
}

// Project then Unproject at `count` random points whose direction is within `max_angle` of the
// axis (distance 0.1 to 100 m); returns the largest angle between the point and the ray.
double MaxRayRoundTripError(const CameraModel& model, double max_angle, int count, int* failures) {
  std::mt19937 rng(777);
  std::uniform_real_distribution<double> unit(0, 1);
  double max_error = 0;
  *failures = 0;
  for (int i = 0; i < count; ++i) {
    const double theta = max_angle * std::sqrt(unit(rng));
    const double phi = 2 * kPi * unit(rng);
    const double depth = 0.1 * std::pow(1000.0, unit(rng));
    const Vec3 dir(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                   std::cos(theta));
    const std::optional<Vec2> pixel = model.Project(depth * dir);
    const std::optional<Vec3> ray = pixel ? model.Unproject(*pixel) : std::nullopt;
    if (!ray) {
      ++*failures;
      continue;
    }
    max_error = std::max(max_error, AngleBetween(*ray, dir));
  }
  return max_error;
}

// The smallest s > 0 where `slope(s)` <= 0 on a dense grid over (0, s_max], by brute force.
double BruteForceFirstNonPositive(const std::function<double(double)>& slope, double s_max,
                                  int steps) {
  for (int i = 1; i <= steps; ++i) {
    const double s = s_max * i / steps;
    if (slope(s) <= 0) return s;
  }
  return kInf;
}

// ---------------------------------------------------------------------------------------------
// Names and focal conversions.

TEST(LensModelNameTest, Names) {
  EXPECT_STREQ(LensModelName(LensModel::kPinhole), "pinhole");
  EXPECT_STREQ(LensModelName(LensModel::kBrownConrady), "brown_conrady");
  EXPECT_STREQ(LensModelName(LensModel::kFisheye), "fisheye");
}

TEST(FocalTest, EighteenMillimetreLensOnApsC) {
  const double fx = FocalFromLens(18.0, 18.43, 1920);
  EXPECT_DOUBLE_EQ(fx, 18.0 * 1920 / 18.43);
  const double hfov = HfovFromFocal(fx, 1920, LensModel::kPinhole);
  EXPECT_NEAR(hfov * 180 / kPi, 54.22, 0.01);
  EXPECT_NEAR(hfov, 2 * std::atan(18.43 / 2 / 18.0), 1e-14);
  // Brown-Conrady uses the pinhole relation.
  EXPECT_DOUBLE_EQ(HfovFromFocal(fx, 1920, LensModel::kBrownConrady), hfov);
}

TEST(FocalTest, ClosedForms) {
  // 90 degrees across 1000 px: tan(45) = 1.
  EXPECT_NEAR(FocalFromHfov(Rad(90), 1000, LensModel::kPinhole), 500.0, 1e-12);
  EXPECT_NEAR(FocalFromHfov(Rad(90), 1000, LensModel::kBrownConrady), 500.0, 1e-12);
  // Equidistant fisheye: 180 degrees across 1000 px is 500 px per pi/2.
  EXPECT_NEAR(FocalFromHfov(Rad(180), 1000, LensModel::kFisheye), 1000.0 / kPi, 1e-12);
  EXPECT_NEAR(HfovFromFocal(1000.0 / kPi, 1000, LensModel::kFisheye), kPi, 1e-15);
  EXPECT_NEAR(HfovFromFocal(500, 1000, LensModel::kPinhole), kPi / 2, 1e-15);
}

TEST(FocalTest, RoundTrips) {
  for (double deg = 1; deg < 180; deg += 0.5) {
    for (LensModel model : {LensModel::kPinhole, LensModel::kBrownConrady}) {
      const double fx = FocalFromHfov(Rad(deg), 1920, model);
      EXPECT_NEAR(HfovFromFocal(fx, 1920, model), Rad(deg), 1e-13) << deg;
    }
  }
  for (double deg = 1; deg < 360; deg += 0.5) {
    const double fx = FocalFromHfov(Rad(deg), 1920, LensModel::kFisheye);
    EXPECT_NEAR(HfovFromFocal(fx, 1920, LensModel::kFisheye), Rad(deg), 1e-13) << deg;
  }
}

// ---------------------------------------------------------------------------------------------
// Pinhole.

TEST(PinholeTest, ProjectClosedForm) {
  Intrinsics k;
  k.width = 1280;
  k.height = 720;
  k.fx = 1000;
  k.fy = 1100;
  k.cx = 640;
  k.cy = 360;
  const CameraModel model(k);
  EXPECT_EQ(model.max_radius(), kInf);
  Mat23 jacobian;
  const std::optional<Vec2> pixel = model.Project(Vec3(0.3, -0.2, 2), &jacobian);
  ASSERT_TRUE(pixel);
  EXPECT_NEAR(pixel->x(), 640 + 1000 * 0.15, 1e-12);
  EXPECT_NEAR(pixel->y(), 360 - 1100 * 0.1, 1e-12);
  Mat23 expected;
  expected << 500, 0, -75,  //
      0, 550, 55;
  EXPECT_LT((jacobian - expected).cwiseAbs().maxCoeff(), 1e-12) << jacobian;

  const std::optional<Vec3> ray = model.Unproject(Vec2(790, 250));
  ASSERT_TRUE(ray);
  EXPECT_LT((*ray - Vec3(0.15, -0.1, 1).normalized()).norm(), 1e-15);

  EXPECT_FALSE(model.Project(Vec3(0, 0, -1)));
  EXPECT_FALSE(model.Project(Vec3(1, 0, 0)));
  EXPECT_FALSE(model.Project(Vec3(0, 0, 0)));
  EXPECT_FALSE(model.Project(Vec3(0, std::nan(""), 1)));
}

TEST(PinholeTest, RoundTripsAndJacobian) {
  const CameraModel model(PinholeIntrinsics(70, 1280, 800));
  int failures = 0;
  EXPECT_LT(MaxPixelRoundTripError(model, 2000, &failures), 1e-9);
  EXPECT_EQ(failures, 0);
  EXPECT_LT(MaxRayRoundTripError(model, Rad(60), 2000, &failures), 1e-14);
  EXPECT_EQ(failures, 0);
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) {
    const Vec3 p = *model.Unproject(RandomPixel(model, rng)) * (0.5 + i);
    ExpectJacobianMatches(model, p);
  }
}

TEST(PinholeTest, WideAngleEdge) {
  // 170 degrees across the width: the left and right image edges are at 85 degrees.
  const CameraModel model(PinholeIntrinsics(170, 1920, 1080));
  for (const Vec2& pixel : {Vec2(-0.5, 539.5), Vec2(1919.5, 539.5)}) {
    const std::optional<Vec3> ray = model.Unproject(pixel);
    ASSERT_TRUE(ray);
    EXPECT_NEAR(std::atan2(ray->head<2>().norm(), ray->z()), Rad(85), 1e-13);
    EXPECT_NEAR(ray->y(), 0, 1e-15);
    const std::optional<Vec2> back = model.Project(*ray * 10);
    ASSERT_TRUE(back);
    EXPECT_LT((*back - pixel).norm(), 1e-9);
  }
}

// ---------------------------------------------------------------------------------------------
// Brown-Conrady.

TEST(BrownConradyTest, ProjectHandComputed) {
  Intrinsics k;
  k.width = 1000;
  k.height = 800;
  k.fx = k.fy = 1000;
  k.cx = 500;
  k.cy = 400;
  k.model = LensModel::kBrownConrady;
  k.k1 = 0.1;
  k.k2 = 0.01;
  k.p1 = 0.001;
  k.p2 = 0.002;
  k.k3 = 0.001;
  const CameraModel model(k);
  // x = 0.5, y = 0.25, s = 0.3125, radial = 1.032257080078125,
  // x_d = 0.5 radial + 2 p1 x y + p2 (s + 2 x^2) = 0.5161285400390625 + 0.00025 + 0.001625,
  // y_d = 0.25 radial + p1 (s + 2 y^2) + 2 p2 x y = 0.25806427001953125 + 0.0004375 + 0.0005.
  const std::optional<Vec2> pixel = model.Project(Vec3(1.0, 0.5, 2.0));
  ASSERT_TRUE(pixel);
  EXPECT_NEAR(pixel->x(), 500 + 1000 * 0.5180035400390625, 1e-10);
  EXPECT_NEAR(pixel->y(), 400 + 1000 * 0.25900177001953125, 1e-10);
  // The principal ray maps to the principal point.
  const std::optional<Vec2> centre = model.Project(Vec3(0, 0, 4));
  ASSERT_TRUE(centre);
  EXPECT_NEAR((*centre - Vec2(500, 400)).norm(), 0, 1e-12);
  EXPECT_FALSE(model.Project(Vec3(0.1, 0.1, -1)));
  EXPECT_FALSE(model.Project(Vec3(0.1, 0.1, 0)));
}

TEST(BrownConradyTest, RoundTripsBarrel) {
  const CameraModel model(BarrelIntrinsics());
  EXPECT_EQ(model.max_radius(), kInf);  // 1 - 0.84 s + 0.35 s^2 has no real root.
  int failures = 0;
  const double pixel_error = MaxPixelRoundTripError(model, 5000, &failures);
  EXPECT_LT(pixel_error, 1e-9);
  EXPECT_EQ(failures, 0);
  const double ray_error = MaxRayRoundTripError(model, model.max_field_angle(), 5000, &failures);
  EXPECT_LT(ray_error, 1e-12);
  EXPECT_EQ(failures, 0);
}

TEST(BrownConradyTest, RoundTripsPincushion) {
  const CameraModel model(PincushionIntrinsics());
  EXPECT_EQ(model.max_radius(), kInf);
  int failures = 0;
  EXPECT_LT(MaxPixelRoundTripError(model, 5000, &failures), 1e-9);
  EXPECT_EQ(failures, 0);
  EXPECT_LT(MaxRayRoundTripError(model, model.max_field_angle(), 5000, &failures), 1e-12);
  EXPECT_EQ(failures, 0);
}

TEST(BrownConradyTest, JacobianMatchesFiniteDifferences) {
  for (const Intrinsics& k : {BarrelIntrinsics(), PincushionIntrinsics()}) {
    const CameraModel model(k);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> depth(0.2, 50);
    for (int i = 0; i < 500; ++i) {
      const std::optional<Vec3> ray = model.Unproject(RandomPixel(model, rng));
      ASSERT_TRUE(ray);
      ExpectJacobianMatches(model, *ray * depth(rng));
    }
    ExpectJacobianMatches(model, Vec3(0, 0, 2));
    ExpectJacobianMatches(model, Vec3(1e-9, -2e-9, 2));
  }
}

TEST(BrownConradyTest, DomainClosedForms) {
  auto max_radius = [](double k1, double k2, double k3) {
    Intrinsics k = BarrelIntrinsics();
    k.k1 = k1;
    k.k2 = k2;
    k.k3 = k3;
    return CameraModel(k).max_radius();
  };
  // k1 < 0 alone: 1 + 3 k1 s = 0.
  for (double k1 : {-0.01, -0.2, -0.28, -1.0, -5.0}) {
    EXPECT_NEAR(max_radius(k1, 0, 0), std::sqrt(-1 / (3 * k1)), 1e-15 * std::sqrt(-1 / k1));
  }
  // 1 + 0.3 s - 1.5 s^2 = 0.
  EXPECT_NEAR(max_radius(0.1, -0.3, 0), std::sqrt((0.3 + std::sqrt(0.09 + 6)) / 3), 1e-14);
  // k3 alone: 1 - 0.7 s^3 = 0.
  EXPECT_NEAR(max_radius(0, 0, -0.1), std::sqrt(std::cbrt(1 / 0.7)), 1e-14);
  // -(s - 1)(s - 2)(s - 3) / 6 = 1 - 11/6 s + s^2 - s^3 / 6: the first of three roots.
  EXPECT_NEAR(max_radius(-11.0 / 18, 1.0 / 5, -1.0 / 42), 1.0, 1e-13);
  // 1 - s + 0.3 s^2 dips to 1/6 at s = 5/3 but never reaches zero.
  EXPECT_EQ(max_radius(-1.0 / 3, 0.06, 0), kInf);
  // Same dip, then a negative cubic term turns it down far out: compare with a brute-force scan.
  const double far = max_radius(-1.0 / 3, 0.06, -1e-4);
  const double far_s = BruteForceFirstNonPositive(
      [](double s) { return 1 - s + 0.3 * s * s - 7e-4 * s * s * s; }, 1000, 10000000);
  EXPECT_NEAR(far * far, far_s, 2e-4);
  EXPECT_EQ(max_radius(0, 0, 0), kInf);
  EXPECT_EQ(max_radius(0.1, 0.02, 0.001), kInf);
}

TEST(BrownConradyTest, DomainMatchesBruteForceForRandomCoefficients) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coefficient(-1, 1);
  int finite = 0;
  for (int i = 0; i < 300; ++i) {
    Intrinsics k = BarrelIntrinsics();
    k.k1 = coefficient(rng);
    k.k2 = coefficient(rng);
    k.k3 = 0.5 * coefficient(rng);
    const double r = CameraModel(k).max_radius();
    auto slope = [&](double s) {
      return 1 + 3 * k.k1 * s + 5 * k.k2 * s * s + 7 * k.k3 * s * s * s;
    };
    const double brute = BruteForceFirstNonPositive(slope, 100, 1000000);
    if (std::isinf(brute)) {
      // Beyond the scan, compare with the sign at infinity.
      EXPECT_TRUE(std::isinf(r) || r * r > 100) << k.k1 << " " << k.k2 << " " << k.k3;
    } else {
      ++finite;
      EXPECT_NEAR(r * r, brute, 2e-4) << k.k1 << " " << k.k2 << " " << k.k3;
      const double s = r * r;
      const double scale =
          1 + std::abs(3 * k.k1 * s) + std::abs(5 * k.k2 * s * s) + std::abs(7 * k.k3 * s * s * s);
      EXPECT_NEAR(slope(s), 0, 1e-13 * scale);
    }
  }
  EXPECT_GT(finite, 100);
}

TEST(BrownConradyTest, DomainEdge) {
  Intrinsics k;
  k.width = 2000;
  k.height = 2000;
  k.fx = k.fy = 1000;
  k.cx = k.cy = 999.5;
  k.model = LensModel::kBrownConrady;
  k.k1 = -0.2;
  const CameraModel model(k);
  const double r_max = std::sqrt(1 / 0.6);
  ASSERT_NEAR(model.max_radius(), r_max, 1e-15);
  for (double phi : {0.0, 0.7, 2.0, 4.0}) {
    const Vec3 dir(std::cos(phi), std::sin(phi), 0);
    EXPECT_TRUE(model.Project(Vec3(0, 0, 1) + r_max * (1 - 1e-9) * dir)) << phi;
    EXPECT_FALSE(model.Project(Vec3(0, 0, 1) + r_max * (1 + 1e-9) * dir)) << phi;
    EXPECT_FALSE(model.Project(Vec3(0, 0, 1) + 3 * r_max * dir)) << phi;
  }
  // The image of the domain edge is the circle r_d = r_max (1 + k1 r_max^2) = 2/3 r_max.
  const double rd_max = 2.0 / 3.0 * r_max;
  const Vec2 centre(k.cx, k.cy);
  const Vec2 inside = centre + 1000 * rd_max * (1 - 1e-6) * Vec2(0.6, 0.8);
  const std::optional<Vec3> ray = model.Unproject(inside);
  ASSERT_TRUE(ray);
  EXPECT_LT(ray->head<2>().norm() / ray->z(), r_max);
  const std::optional<Vec2> back = model.Project(*ray);
  ASSERT_TRUE(back);
  EXPECT_LT((*back - inside).norm(), 1e-6);
  EXPECT_FALSE(model.Unproject(centre + 1000 * rd_max * (1 + 1e-9) * Vec2(0.6, 0.8)));
  // The image corners lie beyond the edge: the field angle is bounded by the domain.
  EXPECT_FALSE(model.Unproject(Vec2(-0.5, -0.5)));
  EXPECT_GE(model.max_field_angle(), std::atan(r_max));
  EXPECT_NEAR(model.max_field_angle(), std::atan(r_max), 1e-5);
  EXPECT_LE(model.normalized_bounds()(0), -r_max);
  EXPECT_GE(model.normalized_bounds()(1), r_max);
}

TEST(BrownConradyTest, TangentialDeterminant) {
  // With p1 only, on x = 0: det = (1 + 2 p1 y)(1 + 6 p1 y), zero at y = -1 / (6 p1).
  Intrinsics k;
  k.width = 1000;
  k.height = 1000;
  k.fx = k.fy = 500;
  k.cx = k.cy = 499.5;
  k.model = LensModel::kBrownConrady;
  k.p1 = 0.1;
  const CameraModel model(k);
  EXPECT_EQ(model.max_radius(), kInf);
  const std::optional<Vec2> pixel = model.Project(Vec3(0, -1, 1));
  ASSERT_TRUE(pixel);
  // y_d = y + p1 (s + 2 y^2) = -1 + 0.3.
  EXPECT_NEAR(pixel->x(), 499.5, 1e-12);
  EXPECT_NEAR(pixel->y(), 499.5 + 500 * -0.7, 1e-12);
  EXPECT_TRUE(model.Project(Vec3(0, -1.66, 1)));
  EXPECT_FALSE(model.Project(Vec3(0, -1.67, 1)));
  EXPECT_FALSE(model.Project(Vec3(0, -3, 1)));
  // Unproject inverts it and rejects nothing inside the domain.
  const std::optional<Vec3> ray = model.Unproject(*pixel);
  ASSERT_TRUE(ray);
  EXPECT_LT(AngleBetween(*ray, Vec3(0, -1, 1)), 1e-13);
}

// ---------------------------------------------------------------------------------------------
// Fisheye.

TEST(FisheyeTest, ProjectClosedForm) {
  Intrinsics k;
  k.width = 1000;
  k.height = 1000;
  k.fx = 500;
  k.fy = 510;
  k.cx = 499.5;
  k.cy = 489.5;
  k.model = LensModel::kFisheye;
  const double theta = Rad(60), phi = Rad(30);
  const Vec3 p =
      2.5 * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
  {
    const CameraModel model(k);
    EXPECT_DOUBLE_EQ(model.max_radius(), kPi);
    const std::optional<Vec2> pixel = model.Project(p);
    ASSERT_TRUE(pixel);
    EXPECT_NEAR(pixel->x(), 499.5 + 500 * theta * std::cos(phi), 1e-10);
    EXPECT_NEAR(pixel->y(), 489.5 + 510 * theta * std::sin(phi), 1e-10);
    // Behind the camera plane: theta = 120 degrees.
    const std::optional<Vec2> behind =
        model.Project(Vec3(std::sin(Rad(120)), 0, std::cos(Rad(120))));
    ASSERT_TRUE(behind);
    EXPECT_NEAR(behind->x(), 499.5 + 500 * Rad(120), 1e-10);
    EXPECT_NEAR(behind->y(), 489.5, 1e-12);
  }
  k.k1 = 0.05;
  k.k2 = -0.01;
  k.k3 = 0.002;
  k.k4 = -0.0003;
  const CameraModel model(k);
  const double t = theta * theta;
  const double theta_d =
      theta * (1 + 0.05 * t - 0.01 * t * t + 0.002 * t * t * t - 0.0003 * t * t * t * t);
  const std::optional<Vec2> pixel = model.Project(p);
  ASSERT_TRUE(pixel);
  EXPECT_NEAR(pixel->x(), 499.5 + 500 * theta_d * std::cos(phi), 1e-10);
  EXPECT_NEAR(pixel->y(), 489.5 + 510 * theta_d * std::sin(phi), 1e-10);

  // Small angles (the series branch near the axis) against theta_d directly.
  for (double small : {0.3, 1e-3, 1e-8}) {
    const double ts = small * small;
    const double ds = small * (1 + 0.05 * ts - 0.01 * ts * ts + 0.002 * ts * ts * ts -
                               0.0003 * ts * ts * ts * ts);
    const Vec3 q(std::sin(small) * std::cos(phi), std::sin(small) * std::sin(phi), std::cos(small));
    const std::optional<Vec2> px = model.Project(q);
    ASSERT_TRUE(px);
    EXPECT_NEAR(px->x(), 499.5 + 500 * ds * std::cos(phi), 1e-12);
    EXPECT_NEAR(px->y(), 489.5 + 510 * ds * std::sin(phi), 1e-12);
  }

  // On the axis: the principal point, with the pinhole Jacobian.
  Mat23 jacobian;
  const std::optional<Vec2> centre = model.Project(Vec3(0, 0, 5), &jacobian);
  ASSERT_TRUE(centre);
  EXPECT_NEAR((*centre - Vec2(499.5, 489.5)).norm(), 0, 1e-13);
  Mat23 expected;
  expected << 100, 0, 0,  //
      0, 102, 0;
  EXPECT_LT((jacobian - expected).cwiseAbs().maxCoeff(), 1e-12) << jacobian;
  const std::optional<Vec3> axis = model.Unproject(Vec2(499.5, 489.5));
  ASSERT_TRUE(axis);
  EXPECT_LT((*axis - Vec3(0, 0, 1)).norm(), 1e-16);

  EXPECT_FALSE(model.Project(Vec3(0, 0, -1)));  // The backward axis.
  EXPECT_FALSE(model.Project(Vec3(0, 0, 0)));
}

TEST(FisheyeTest, DomainClosedForms) {
  auto max_radius = [](double k1, double k2, double k3, double k4) {
    Intrinsics k = FisheyeIntrinsics();
    k.k1 = k1;
    k.k2 = k2;
    k.k3 = k3;
    k.k4 = k4;
    return CameraModel(k).max_radius();
  };
  EXPECT_DOUBLE_EQ(max_radius(0, 0, 0, 0), kPi);
  // k1 < 0 alone: 1 + 3 k1 theta^2 = 0 at theta = sqrt(-1 / (3 k1)), capped at pi.
  EXPECT_NEAR(max_radius(-0.05, 0, 0, 0), std::sqrt(1 / 0.15), 1e-15);
  EXPECT_DOUBLE_EQ(max_radius(-0.01, 0, 0, 0), kPi);
  // k4 alone: 1 + 9 k4 theta^8 = 0.
  EXPECT_NEAR(max_radius(0, 0, 0, -0.001), std::pow(1 / 0.009, 1.0 / 8), 1e-14);
  // The typical calibration: against a brute-force scan of the slope in theta.
  const Intrinsics k = FisheyeIntrinsics();
  auto slope = [&](double theta) {
    const double t = theta * theta;
    return 1 + 3 * k.k1 * t + 5 * k.k2 * t * t + 7 * k.k3 * t * t * t + 9 * k.k4 * t * t * t * t;
  };
  const double brute = BruteForceFirstNonPositive(slope, kPi, 10000000);
  const double r = CameraModel(k).max_radius();
  EXPECT_NEAR(r, brute, 1e-6);
  EXPECT_NEAR(slope(r), 0, 1e-12);
  EXPECT_GT(r, Rad(95));
}

TEST(FisheyeTest, DomainEdge) {
  Intrinsics k = FisheyeIntrinsics();
  k.k1 = -0.05;
  k.k2 = k.k3 = k.k4 = 0;
  const CameraModel model(k);
  const double theta_max = std::sqrt(1 / 0.15);
  const double theta_d_max = theta_max * (1 - 0.05 * theta_max * theta_max);
  for (double phi : {0.3, 2.5}) {
    auto point = [&](double theta) {
      return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                  std::cos(theta));
    };
    EXPECT_TRUE(model.Project(point(theta_max * (1 - 1e-9))));
    EXPECT_FALSE(model.Project(point(theta_max * (1 + 1e-9))));
    const Vec2 dir(std::cos(phi), std::sin(phi));
    const Vec2 centre(k.cx, k.cy);
    const Vec2 inside = centre + theta_d_max * (1 - 1e-6) * Vec2(k.fx * dir.x(), k.fy * dir.y());
    const Vec2 outside = centre + theta_d_max * (1 + 1e-9) * Vec2(k.fx * dir.x(), k.fy * dir.y());
    const std::optional<Vec3> ray = model.Unproject(inside);
    ASSERT_TRUE(ray);
    const std::optional<Vec2> back = model.Project(*ray);
    ASSERT_TRUE(back);
    EXPECT_LT((*back - inside).norm(), 1e-6);
    EXPECT_FALSE(model.Unproject(outside));
  }
}

TEST(FisheyeTest, RoundTrips190Degrees) {
  const CameraModel model(FisheyeIntrinsics());
  int failures = 0;
  EXPECT_LT(MaxPixelRoundTripError(model, 5000, &failures), 1e-9);
  EXPECT_EQ(failures, 0);
  EXPECT_LT(MaxRayRoundTripError(model, model.max_field_angle(), 5000, &failures), 1e-12);
  EXPECT_EQ(failures, 0);
  EXPECT_GT(model.max_field_angle(), kPi / 2);
}

TEST(FisheyeTest, EdgeOf190DegreeLens) {
  Intrinsics k = FisheyeIntrinsics();
  k.k1 = k.k2 = k.k3 = k.k4 = 0;
  k.fy = k.fx;
  k.cx = 959.5;
  const CameraModel model(k);
  for (const Vec2& pixel : {Vec2(-0.5, k.cy), Vec2(1919.5, k.cy)}) {
    const std::optional<Vec3> ray = model.Unproject(pixel);
    ASSERT_TRUE(ray);
    EXPECT_NEAR(std::atan2(ray->head<2>().norm(), ray->z()), Rad(95), 1e-14);
    EXPECT_LT(ray->z(), 0);
    const std::optional<Vec2> back = model.Project(*ray * 2);
    ASSERT_TRUE(back);
    EXPECT_LT((*back - pixel).norm(), 1e-9);
  }
  // The distorted lens: the edge pixel's ray round-trips too.
  const CameraModel distorted(FisheyeIntrinsics());
  const Vec2 edge(-0.5, FisheyeIntrinsics().cy);
  const std::optional<Vec3> ray = distorted.Unproject(edge);
  ASSERT_TRUE(ray);
  const std::optional<Vec2> back = distorted.Project(*ray);
  ASSERT_TRUE(back);
  EXPECT_LT((*back - edge).norm(), 1e-9);
}

TEST(FisheyeTest, JacobianMatchesFiniteDifferences) {
  const CameraModel model(FisheyeIntrinsics());
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> depth(0.2, 50);
  for (int i = 0; i < 500; ++i) {
    const std::optional<Vec3> ray = model.Unproject(RandomPixel(model, rng));
    ASSERT_TRUE(ray);
    ExpectJacobianMatches(model, *ray * depth(rng));
  }
  // Near the axis (series branch), across the branch switch at 0.5 rad, behind the camera, and
  // close to the domain edge.
  for (double theta :
       {0.0, 1e-12, 1e-9, 1e-6, 1e-4, 1e-2, 0.3, 0.4999, 0.5001, 1.0, 1.6, 2.0, 2.3}) {
    for (double phi : {0.0, 1.0, 2.5, 4.0}) {
      const Vec3 p = 3 * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
      ExpectJacobianMatches(model, p);
    }
  }
  // On the axis, the Jacobian is the pinhole one.
  Mat23 jacobian;
  ASSERT_TRUE(model.Project(Vec3(1e-10, -1e-10, 2), &jacobian));
  EXPECT_NEAR(jacobian(0, 0), model.intrinsics().fx / 2, 1e-9);
  EXPECT_NEAR(jacobian(1, 1), model.intrinsics().fy / 2, 1e-9);
  EXPECT_NEAR(jacobian(0, 2), 0, 1e-6);
}

TEST(FisheyeTest, UndistortedJacobianAgainstEquidistantClosedForm) {
  // theta_d = theta: u - cx = fx theta X / r. On the x axis (Y = 0, X > 0):
  // du/dX = fx d(theta)/dX = fx Z / rho^2, du/dZ = -fx X / rho^2, dv/dY = fy theta / X.
  Intrinsics k = FisheyeIntrinsics();
  k.k1 = k.k2 = k.k3 = k.k4 = 0;
  const CameraModel model(k);
  const double x = 2, z = 1.5, rho2 = x * x + z * z;
  Mat23 jacobian;
  ASSERT_TRUE(model.Project(Vec3(x, 0, z), &jacobian));
  EXPECT_NEAR(jacobian(0, 0), k.fx * z / rho2, 1e-12);
  EXPECT_NEAR(jacobian(0, 1), 0, 1e-12);
  EXPECT_NEAR(jacobian(0, 2), -k.fx * x / rho2, 1e-12);
  EXPECT_NEAR(jacobian(1, 1), k.fy * std::atan2(x, z) / x, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Field of view.

TEST(FieldOfViewTest, UndistortedPinholeCorner) {
  Intrinsics k;
  k.width = 1280;
  k.height = 720;
  k.fx = 900;
  k.fy = 950;
  k.cx = 600;  // Off-centre: the farthest corner is on the right.
  k.cy = 380;
  const CameraModel model(k);
  double corner = 0;
  for (double u : {-0.5, 1279.5}) {
    for (double v : {-0.5, 719.5}) {
      corner = std::max(corner, std::hypot((u - k.cx) / k.fx, (v - k.cy) / k.fy));
    }
  }
  EXPECT_GE(model.max_field_angle(), std::atan(corner));
  EXPECT_NEAR(model.max_field_angle(), std::atan(corner), 2e-6 * std::atan(corner));
  const Eigen::Vector4d expected((-0.5 - k.cx) / k.fx, (1279.5 - k.cx) / k.fx, (-0.5 - k.cy) / k.fy,
                                 (719.5 - k.cy) / k.fy);
  const Eigen::Vector4d& bounds = model.normalized_bounds();
  EXPECT_LE(bounds(0), expected(0));
  EXPECT_GE(bounds(1), expected(1));
  EXPECT_LE(bounds(2), expected(2));
  EXPECT_GE(bounds(3), expected(3));
  EXPECT_LT((bounds - expected).cwiseAbs().maxCoeff(), 2e-6);
}

TEST(FieldOfViewTest, WidePinhole) {
  const CameraModel model(PinholeIntrinsics(170, 1920, 1080));
  const double corner = std::hypot(960.0, 540.0) / model.intrinsics().fx;
  EXPECT_NEAR(model.max_field_angle(), std::atan(corner), 2e-6 * std::atan(corner));
  EXPECT_LT(model.max_field_angle(), kPi / 2);
  EXPECT_NEAR(model.normalized_bounds()(1), 960.0 / model.intrinsics().fx, 1e-4);
}

// Brute force over the border at quarter-pixel steps and an interior grid: every ray lies inside
// the reported bounds, and the bounds are tight.
void ExpectFieldBoundsMatchBruteForce(const CameraModel& model, double interior_step = 7.3) {
  double max_angle = 0;
  Eigen::Vector4d ext(kInf, -kInf, kInf, -kInf);
  auto visit = [&](double u, double v) {
    const std::optional<Vec3> ray = model.Unproject(Vec2(u, v));
    ASSERT_TRUE(ray) << u << " " << v;
    max_angle = std::max(max_angle, std::atan2(ray->head<2>().norm(), ray->z()));
    const double x = ray->x() / ray->z(), y = ray->y() / ray->z();
    ext = Eigen::Vector4d(std::min(ext(0), x), std::max(ext(1), x), std::min(ext(2), y),
                          std::max(ext(3), y));
  };
  const double w = model.width() - 0.5, h = model.height() - 0.5;
  for (double u = -0.5; u <= w; u += 0.25) {
    visit(u, -0.5);
    visit(u, h);
  }
  for (double v = -0.5; v <= h; v += 0.25) {
    visit(-0.5, v);
    visit(w, v);
  }
  for (double u = -0.5; u <= w; u += interior_step) {
    for (double v = -0.5; v <= h; v += interior_step) visit(u, v);
  }
  // Conservative, with a margin of about 1e-6 relative, and tight.
  EXPECT_GT(model.max_field_angle(), max_angle * (1 + 1e-7));
  EXPECT_LT(model.max_field_angle(), max_angle * (1 + 1e-5));
  const Eigen::Vector4d& bounds = model.normalized_bounds();
  EXPECT_LT(bounds(0), ext(0));
  EXPECT_GT(bounds(1), ext(1));
  EXPECT_LT(bounds(2), ext(2));
  EXPECT_GT(bounds(3), ext(3));
  EXPECT_LT((bounds - ext).cwiseAbs().maxCoeff(), 1e-5) << bounds.transpose() << "\n"
                                                        << ext.transpose();
}

TEST(FieldOfViewTest, BarrelMatchesBruteForce) {
  ExpectFieldBoundsMatchBruteForce(CameraModel(BarrelIntrinsics()));
}

TEST(FieldOfViewTest, PincushionMatchesBruteForce) {
  // Pincushion: the extremes of x/z lie mid-edge, not at the corners.
  const CameraModel model(PincushionIntrinsics());
  ExpectFieldBoundsMatchBruteForce(model);
  const std::optional<Vec3> corner = model.Unproject(Vec2(1919.5, -0.5));
  ASSERT_TRUE(corner);
  EXPECT_GT(model.normalized_bounds()(1), corner->x() / corner->z() + 1e-3);
}

TEST(FieldOfViewTest, StrongPincushionOnLargeSensor) {
  // 8000 px across with 256 border samples per edge: the mid-edge extremes fall between samples
  // (by up to ~1e-6 relative here) and must be refined.
  Intrinsics k;
  k.width = 8000;
  k.height = 6000;
  k.fx = k.fy = 2500;
  k.cx = 3999.5 + 13.37;
  k.cy = 2999.5 - 11.71;
  k.model = LensModel::kBrownConrady;
  k.k1 = 0.4;
  k.p1 = 2e-4;
  const CameraModel model(k);
  ASSERT_EQ(model.max_radius(), kInf);
  ExpectFieldBoundsMatchBruteForce(model, 97.3);
}

TEST(FieldOfViewTest, FisheyeBeyondHemisphere) {
  const CameraModel model(FisheyeIntrinsics());
  double corner_angle = 0;
  for (double u : {-0.5, 1919.5}) {
    for (double v : {-0.5, 1079.5}) {
      const std::optional<Vec3> ray = model.Unproject(Vec2(u, v));
      ASSERT_TRUE(ray);
      corner_angle = std::max(corner_angle, std::atan2(ray->head<2>().norm(), ray->z()));
    }
  }
  EXPECT_GE(model.max_field_angle(), corner_angle);
  EXPECT_NEAR(model.max_field_angle(), corner_angle, 1e-5);
  EXPECT_GT(model.max_field_angle(), kPi / 2);
  const Eigen::Vector4d& bounds = model.normalized_bounds();
  EXPECT_EQ(bounds, Eigen::Vector4d(-kInf, kInf, -kInf, kInf));
}

// ---------------------------------------------------------------------------------------------
// Posed cameras.

TEST(LookAtTest, HorizontalViewAlongX) {
  const std::optional<Eigen::Isometry3d> pose = LookAt(Vec3(0, 0, 0), Vec3(5, 0, 0), Vec3(0, 0, 1));
  ASSERT_TRUE(pose);
  const Mat3 r = pose->linear();
  EXPECT_LT((r.col(0) - Vec3(0, -1, 0)).norm(), 1e-15);  // Camera x: world -Y.
  EXPECT_LT((r.col(1) - Vec3(0, 0, -1)).norm(), 1e-15);  // Camera y (down): world -Z.
  EXPECT_LT((r.col(2) - Vec3(1, 0, 0)).norm(), 1e-15);   // Camera z: world +X.
  EXPECT_LT(pose->translation().norm(), 1e-15);
}

TEST(LookAtTest, RandomPosesAreProperRotations) {
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0, 3);
  Camera camera;
  camera.model = CameraModel(PinholeIntrinsics(60, 640, 480));
  for (int i = 0; i < 200; ++i) {
    const Vec3 position(n(rng), n(rng), n(rng)), target(n(rng), n(rng), n(rng));
    const Vec3 up(0.2 * n(rng), 0.2 * n(rng), 1);
    const std::optional<Eigen::Isometry3d> pose = LookAt(position, target, up);
    ASSERT_TRUE(pose);
    const Mat3 r = pose->linear();
    EXPECT_LT((r.transpose() * r - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(r.determinant(), 1, 1e-14);
    EXPECT_LT((r.col(2) - (target - position).normalized()).norm(), 1e-14);
    EXPECT_NEAR(r.col(0).dot(up), 0, 1e-14);  // Image rows are level.
    EXPECT_LT(r.col(1).dot(up), 0);           // Image down is world down.
    EXPECT_LT((pose->translation() - position).norm(), 1e-15);
    // The target projects to the principal point.
    camera.world_from_camera = *pose;
    const std::optional<Vec2> pixel = camera.Project(target);
    ASSERT_TRUE(pixel);
    EXPECT_LT((*pixel - Vec2(319.5, 239.5)).norm(), 1e-9);
  }
}

TEST(LookAtTest, Degenerate) {
  EXPECT_FALSE(LookAt(Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(0, 0, 1)));
  EXPECT_FALSE(LookAt(Vec3(0, 0, 0), Vec3(0, 0, 5), Vec3(0, 0, 1)));
  EXPECT_FALSE(LookAt(Vec3(0, 0, 0), Vec3(0, 0, -5), Vec3(0, 0, 1)));
  EXPECT_FALSE(LookAt(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 0)));
  EXPECT_TRUE(LookAt(Vec3(0, 0, 0), Vec3(1e-3, 0, 5), Vec3(0, 0, 1)));
}

TEST(CameraTest, ProjectHandComputed) {
  Camera camera;
  camera.world_from_camera = *LookAt(Vec3(1, 2, 3), Vec3(11, 2, 3), Vec3(0, 0, 1));
  Intrinsics k;
  k.width = 1000;
  k.height = 800;
  k.fx = 800;
  k.fy = 820;
  k.cx = 499.5;
  k.cy = 399.5;
  camera.model = CameraModel(k);
  EXPECT_EQ(camera.center(), Vec3(1, 2, 3));
  // Camera frame: x = -(Y - 2) = 1, y = -(Z - 3) = -1, z = X - 1 = 10.
  Mat23 jacobian;
  const std::optional<Vec2> pixel = camera.Project(Vec3(11, 1, 4), &jacobian);
  ASSERT_TRUE(pixel);
  EXPECT_NEAR(pixel->x(), 499.5 + 80, 1e-12);
  EXPECT_NEAR(pixel->y(), 399.5 - 82, 1e-12);
  // d(u)/d(world) = fx (d x/d world / z - x/z^2 d z/d world) with x = 2 - Y, z = X - 1.
  Mat23 expected;
  expected << -800 * 1.0 / 100, -800 / 10.0, 0,  //
      -820 * -1.0 / 100, 0, -820 / 10.0;
  EXPECT_LT((jacobian - expected).cwiseAbs().maxCoeff(), 1e-12) << jacobian;
  Mat23 numeric;
  ASSERT_TRUE(NumericJacobian([&](const Vec3& q) { return camera.Project(q); }, Vec3(11, 1, 4),
                              1e-5, &numeric));
  EXPECT_LT(RelativeError(jacobian, numeric), 1e-8);
  // Behind the camera.
  EXPECT_FALSE(camera.Project(Vec3(0, 2, 3)));
}

TEST(CameraTest, BehindCameraFisheyeProjects) {
  Camera pinhole;
  pinhole.world_from_camera = *LookAt(Vec3(0, 0, 2), Vec3(10, 0, 2), Vec3(0, 0, 1));
  pinhole.model = CameraModel(PinholeIntrinsics(120, 1920, 1080));
  // An equidistant 190 degree fisheye: the left and right image edges are at 95 degrees.
  Intrinsics k = FisheyeIntrinsics();
  k.k1 = k.k2 = k.k3 = k.k4 = 0;
  k.fy = k.fx;
  k.cx = 959.5;
  k.cy = 539.5;
  Camera fisheye = pinhole;
  fisheye.model = CameraModel(k);
  // 3 degrees behind the camera plane, to the left (world +Y): theta = 93 degrees.
  const Vec3 behind(-5 * std::sin(Rad(3)), 5 * std::cos(Rad(3)), 2);
  EXPECT_FALSE(pinhole.Project(behind));
  Mat23 jacobian;
  const std::optional<Vec2> pixel = fisheye.Project(behind, &jacobian);
  ASSERT_TRUE(pixel);
  EXPECT_TRUE(fisheye.model.InImage(*pixel));
  EXPECT_NEAR(pixel->x(), 959.5 - k.fx * Rad(93), 1e-9);
  EXPECT_NEAR(pixel->y(), 539.5, 1e-9);
  const std::optional<Vec3> ray = fisheye.model.Unproject(*pixel);
  ASSERT_TRUE(ray);
  EXPECT_NEAR(std::atan2(ray->head<2>().norm(), ray->z()), Rad(93), 1e-12);
  Mat23 numeric;
  ASSERT_TRUE(
      NumericJacobian([&](const Vec3& q) { return fisheye.Project(q); }, behind, 1e-5, &numeric));
  EXPECT_LT(RelativeError(jacobian, numeric), 1e-6);
}

}  // namespace
}  // namespace pandora
