// Visibility: each rule in isolation against closed forms, then Embree against the brute-force
// reference on randomized scenes (>= 10^4 point-camera pairs).
#include "analysis/geometry/visibility.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <random>

#include "analysis/util/units.h"
#include "tests/fixtures.h"
#include "tests/random_scene.h"

namespace pandora {
namespace {

// A pinhole camera (tests/fixtures.h) with Z up and a working range.
Camera MakePinhole(const Vec3& position, const Vec3& target, double hfov_deg, int w, int h,
                   double near = 0.0, double far = std::numeric_limits<double>::infinity()) {
  Camera cam = testing::TestCamera("c", position, target, hfov_deg, w, h, LensModel::kPinhole,
                                   Vec3(0, 0, 1));
  cam.near = near;
  cam.far = far;
  return cam;
}

TEST(Visibility, EachRuleInIsolation) {
  // A camera at the origin looking along +x; a wall (two triangles) at x = 5 facing -x.
  TriangleMesh wall;
  wall.vertices = {Vec3(5, -10, -10), Vec3(5, 10, -10), Vec3(5, 10, 10), Vec3(5, -10, 10)};
  wall.triangles = {Eigen::Vector3i(0, 2, 1), Eigen::Vector3i(0, 3, 2)};
  const auto caster = MakeEmbreeRayCaster(wall);
  std::vector<Camera> cams{MakePinhole(Vec3::Zero(), Vec3(1, 0, 0), 60, 640, 480, 0.5, 8.0)};
  const VisibilityTester vis(cams, *caster, 20.0);

  EXPECT_EQ(vis.Test(0, Vec3(3, 0, 0)), ViewResult::kSeen);
  EXPECT_EQ(vis.Test(0, Vec3(6, 0, 0)), ViewResult::kOccluded);         // behind the wall
  EXPECT_EQ(vis.Test(0, Vec3(0.3, 0, 0)), ViewResult::kOutOfRange);     // nearer than near
  EXPECT_EQ(vis.Test(0, Vec3(-3, 0, 0)), ViewResult::kNotProjectable);  // behind the camera
  EXPECT_EQ(vis.Test(0, Vec3(3, 3, 0)), ViewResult::kOutsideImage);     // 45 deg > 30 deg half-FOV
  // A point on the wall is not occluded by the wall itself, but must face the camera.
  const Vec3 on_wall(5, 0.7, -0.4);
  const Vec3 facing(-1, 0, 0), away(1, 0, 0);
  EXPECT_EQ(vis.Test(0, on_wall, &facing), ViewResult::kSeen);
  EXPECT_EQ(vis.Test(0, on_wall, &away), ViewResult::kBackFacing);
  cams[0].enabled = false;
  const VisibilityTester disabled(cams, *caster, 20.0);
  EXPECT_EQ(disabled.Test(0, Vec3(3, 0, 0)), ViewResult::kDisabled);

  // The horizontal half-FOV boundary at depth 3: y = 3 tan(30 deg) maps to the image edge.
  const double edge = 3.0 * std::tan(kPi / 6);
  EXPECT_EQ(vis.Test(0, Vec3(3, -0.999 * edge, 0)), ViewResult::kSeen);
  EXPECT_EQ(vis.Test(0, Vec3(3, -1.001 * edge, 0)), ViewResult::kOutsideImage);
}

TEST(Visibility, PixelDensityMatchesPinholeClosedForm) {
  const TriangleMesh none;
  const auto caster = MakeEmbreeRayCaster(none);
  std::vector<Camera> cams{MakePinhole(Vec3::Zero(), Vec3(0, 1, 0), 90, 1000, 1000)};
  const double f = cams[0].model.intrinsics().fx;
  ASSERT_NEAR(f, 500.0, 1e-9);
  const VisibilityTester vis(cams, *caster, 10.0);
  for (double z : {0.5, 2.0, 7.0}) {
    Mat23 J;
    ASSERT_EQ(vis.Test(0, Vec3(0, z, 0), nullptr, &J), ViewResult::kSeen);
    EXPECT_NEAR(PixelDensity(J), f / z, 1e-9 * f / z);
  }
  // Off axis at normalized (x, y): the two singular values are f/Z sqrt(1+r^2) and f/Z, so the
  // density is f/Z (1 + r^2)^(1/4).
  Mat23 J;
  const double Z = 2.0, x = 0.6;
  ASSERT_EQ(vis.Test(0, Vec3(x * Z, Z, 0), nullptr, &J), ViewResult::kSeen);
  EXPECT_NEAR(PixelDensity(J), f / Z * std::pow(1 + x * x, 0.25), 1e-9 * f);
}

// PixelDensityLanes against PixelDensity rounded to float, bit for bit: random Jacobians over 40
// binades, rank-one and zero ones, and entries whose determinant overflows, underflows, or is
// NaN or infinite (those give 0); an odd count, so the vector loop's tail runs too.
TEST(Visibility, PixelDensityLanesGiveTheOnePointBits) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), binade(-20.0, 20.0);
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  constexpr int n = 4099;
  std::vector<double> rows[6];
  for (auto& r : rows) r.resize(n);
  for (int m = 0; m < n; ++m) {
    const double scale = std::exp2(binade(rng));
    for (auto& r : rows) r[m] = unit(rng) * scale;
    switch (m % 9) {
      case 1:  // rank one: the second row a multiple of the first
        for (int k = 0; k < 3; ++k) rows[3 + k][m] = 0.5 * rows[k][m];
        break;
      case 2:
        for (auto& r : rows) r[m] = 0.0;
        break;
      case 3:
        rows[m % 6][m] = 1e200;  // det overflows
        break;
      case 4:
        for (auto& r : rows) r[m] *= 1e-160;  // det underflows
        break;
      case 5:
        rows[m % 6][m] = (m % 2) ? inf : -inf;
        break;
      case 6:
        rows[m % 6][m] = nan;
        break;
      default:
        break;
    }
  }
  const double* const jac[6] = {rows[0].data(), rows[1].data(), rows[2].data(),
                                rows[3].data(), rows[4].data(), rows[5].data()};
  std::vector<float> lanes(n, -1.0f);
  PixelDensityLanes(n, jac, lanes.data());
  int zeros = 0;
  for (int m = 0; m < n; ++m) {
    Mat23 J;
    J << rows[0][m], rows[1][m], rows[2][m], rows[3][m], rows[4][m], rows[5][m];
    const float expected = static_cast<float>(PixelDensity(J));
    ASSERT_EQ(std::memcmp(&expected, &lanes[m], sizeof(float)), 0)
        << "m " << m << ": " << expected << " vs " << lanes[m];
    zeros += expected == 0.0f ? 1 : 0;
  }
  EXPECT_GT(zeros, n / 9 * 3);  // the degenerate cases took the zero branch
  EXPECT_LT(zeros, n / 9 * 7);
}

// The vectorised batch test against the one-point test, bit for bit: random cameras of every lens
// (strong Brown-Conrady distortion that folds, fisheye through the one-point fallback, a disabled
// camera, a working range) and random points around them, in front, behind, beyond the image and
// the range, and near the image's edges.
TEST(Visibility, BatchTestGivesTheOnePointBits) {
  const TriangleMesh none;
  const auto caster = MakeEmbreeRayCaster(none);
  std::mt19937 rng(20261124);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Camera> cams;
  for (int c = 0; c < 12; ++c) {
    const Vec3 position(3 * u(rng), 3 * u(rng), 1 + u(rng));
    const LensModel lens = c % 4 == 3   ? LensModel::kFisheye
                           : c % 4 == 0 ? LensModel::kPinhole
                                        : LensModel::kBrownConrady;
    Camera cam = testing::TestCamera("c" + std::to_string(c), position, Vec3(u(rng), u(rng), 0),
                                     lens == LensModel::kFisheye ? 180 : 40 + 60 * (u(rng) + 1),
                                     640, 480, lens, Vec3(0, 0, 1));
    cam = testing::WithIntrinsics(cam, [&](Intrinsics& k) {
      if (k.model == LensModel::kBrownConrady) {
        k.k1 = (c % 3 == 1 ? -0.4 : 0.1) * (u(rng) + 1);  // c % 3 == 1: barrel that folds back
        k.k2 = 0.1 * u(rng);
        k.k3 = 0.01 * u(rng);
        k.p1 = 0.002 * u(rng);
        k.p2 = 0.002 * u(rng);
      }
      k.cx += 20 * u(rng);
    });
    cam.near = c % 2 ? 0.3 : 0.0;
    cam.far = c % 5 == 1 ? 3.0 : std::numeric_limits<double>::infinity();
    cam.enabled = c != 6;
    cams.push_back(cam);
  }
  const VisibilityTester vis(cams, *caster, 10.0);
  int seen_total = 0, compared = 0;
  for (int round = 0; round < 40; ++round) {
    const int n = 1 + static_cast<int>((u(rng) + 1) * 255.5);  // 1..512
    std::vector<double> x(n), y(n), z(n);
    for (int i = 0; i < n; ++i) {
      x[i] = 4 * u(rng);
      y[i] = 4 * u(rng);
      z[i] = 1.5 * u(rng) + 0.5;
    }
    for (int c = 0; c < int(cams.size()); ++c) {
      auto batch = std::make_unique<VisibilityTester::GeometryBatch>();
      vis.TestGeometryBatch(c, n, x.data(), y.data(), z.data(), batch.get());
      const int m = batch->count;
      int k = 0;
      for (int i = 0; i < n; ++i) {
        Ray segment;
        Mat23 J;
        const ViewResult r =
            vis.TestGeometryCameraFrame(c, Vec3(x[i], y[i], z[i]), nullptr, &segment, &J);
        ++compared;
        if (r != ViewResult::kSeen) continue;
        ASSERT_LT(k, m) << "camera " << c << " point " << i;
        ASSERT_EQ(batch->index[k], i) << "camera " << c;
        // Bit for bit (== on doubles, NaN excluded by construction).
        const Ray got = batch->segment(k);
        EXPECT_TRUE(got.origin == segment.origin && got.direction == segment.direction &&
                    got.t_near == segment.t_near && got.t_far == segment.t_far)
            << "camera " << c << " point " << i;
        EXPECT_TRUE(batch->jacobian(k) == J) << "camera " << c << " point " << i << "\n"
                                             << batch->jacobian(k) << "\n"
                                             << J;
        ++k;
      }
      EXPECT_EQ(k, m) << "camera " << c;
      seen_total += m;
    }
  }
  EXPECT_GT(compared, 50000);
  EXPECT_GT(seen_total, compared / 20);  // enough seen points to compare their values
  EXPECT_LT(seen_total, compared / 2);   // and enough rejected ones
}

// The acceptance test: 10^4+ random point-camera pairs, Embree against brute force, no
// disagreement outside the grazing tolerance.
TEST(Visibility, EmbreeAgreesWithBruteForceOnRandomScenes) {
  int pairs = 0, seen = 0, occluded = 0, grazing = 0;
  for (int seed = 0; seed < 3; ++seed) {
    std::mt19937_64 rng(100 + seed);
    const double scale = seed == 1 ? 1e3 : 1.0;
    const Vec3 offset = seed == 2 ? Vec3(2e4, -1e4, 50) : Vec3::Zero();
    const TriangleMesh mesh = testing::RandomScene(rng, scale, offset, 40, 40);
    const auto embree = MakeEmbreeRayCaster(mesh);
    const auto brute = MakeBruteForceRayCaster(mesh);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<Camera> cams;
    for (int c = 0; c < 8; ++c) {
      const Vec3 pos = offset + scale * Vec3(u(rng), u(rng), u(rng));
      const Vec3 at = offset + scale * Vec3(u(rng), u(rng), u(rng));
      cams.push_back(MakePinhole(pos, at, 40 + 80 * u(rng), 800, 600));
    }
    const double scene_scale = scale * std::sqrt(3.0);
    const VisibilityTester ve(cams, *embree, scene_scale);
    const VisibilityTester vb(cams, *brute, scene_scale);
    const double tol = 10 * ve.epsilon();
    for (int i = 0; i < 15000; ++i) {
      Vec3 X = offset + scale * Vec3(u(rng), u(rng), u(rng));
      Vec3 normal;
      const Vec3* n = nullptr;
      int own = -1;
      if (i % 4 == 0) {  // a quarter are surface points with normals
        own = static_cast<int>(rng() % mesh.triangles.size());
        const Eigen::Vector3i& t = mesh.triangles[own];
        double a = u(rng), b = u(rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const Vec3 &p0 = mesh.vertices[t[0]], &p1 = mesh.vertices[t[1]], &p2 = mesh.vertices[t[2]];
        X = p0 + a * (p1 - p0) + b * (p2 - p0);
        normal = (p1 - p0).cross(p2 - p0);
        n = &normal;
      }
      const int c = static_cast<int>(rng() % cams.size());
      const ViewResult re = ve.Test(c, X, n);
      const ViewResult rb = vb.Test(c, X, n);
      ++pairs;
      if (re != rb) {
        // Only the occlusion step can differ; it must be a grazing segment.
        ASSERT_TRUE((re == ViewResult::kOccluded || re == ViewResult::kSeen) &&
                    (rb == ViewResult::kOccluded || rb == ViewResult::kSeen));
        Ray seg;
        ASSERT_EQ(ve.TestGeometry(c, X, n, &seg), ViewResult::kSeen);
        const Vec3 a = seg.origin + seg.t_near * seg.direction;
        const Vec3 b = seg.origin + seg.t_far * seg.direction;
        // A surface point seen at under ~0.6 degrees from its own plane is grazing too: the segment
        // end is then within float round-off of that plane.
        const bool shallow = n && std::abs(n->normalized().dot(seg.direction)) < 0.01;
        ASSERT_TRUE(shallow || testing::IsGrazing(mesh, a, b, tol, own))
            << "seed " << seed << " pair " << i << ": embree " << ViewResultName(re) << ", brute "
            << ViewResultName(rb);
        ++grazing;
        continue;
      }
      seen += re == ViewResult::kSeen;
      occluded += re == ViewResult::kOccluded;
    }
  }
  EXPECT_GE(pairs, 10000);
  EXPECT_GE(seen + occluded, 10000);  // pairs that reached the occlusion test
  EXPECT_GT(seen, pairs / 20);
  EXPECT_GT(occluded, pairs / 20);
  EXPECT_LT(grazing, pairs / 1000);
  std::printf("pairs %d, seen %d, occluded %d, grazing disagreements %d\n", pairs, seen, occluded,
              grazing);
}

// Far cameras and a small object (the outside audit's case: cameras 300 m from a 2 cm object). The
// reference is the double-precision brute force with segments shortened by only 1 nm. Embree casts
// in single precision, so its rays and triangles are rounded by about 2^-24 of their distance from
// the caster's centre (here ~20 um at 300 m): the tester's per-ray tolerance must cover that, and
// it must not be sized from the far cameras (a 1e-5 share of the whole scene's diagonal would be 6
// mm, a third of the object). Every disagreement with the reference must be explained by the
// tolerance: the point lies within it of a surface, or the segment passes within it of a triangle
// edge (grazing); any other disagreement fails.
TEST(Visibility, FarCamerasSmallObjectToleranceFromFloatError) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  const double size = 0.02;
  // Three thin plates and a cube of 2 cm near the origin.
  TriangleMesh mesh = testing::RandomScene(rng, size, Vec3::Constant(-size / 2), 6, 6);
  const auto embree = MakeEmbreeRayCaster(mesh);
  const auto brute = MakeBruteForceRayCaster(mesh);
  std::vector<Camera> cams;
  for (int c = 0; c < 8; ++c) {
    const double az = 2 * kPi * c / 8, el = 0.3 + 0.1 * c;
    const Vec3 pos =
        300.0 * Vec3(std::cos(az) * std::cos(el), std::sin(az) * std::cos(el), std::sin(el));
    cams.push_back(MakePinhole(pos, Vec3::Zero(), 0.01, 1000, 1000));  // 5 cm across at 300 m
  }
  const double geometry_scale = mesh.Bounds().diagonal();
  const VisibilityTester ve(cams, *embree, geometry_scale);
  // The reference: exact segments from the camera to 1 nm short of the point.
  int pairs = 0, disagree = 0, far_from_surfaces = 0;
  double worst_tolerance = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 X = size * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    const int c = static_cast<int>(rng() % cams.size());
    Ray seg;
    ASSERT_EQ(ve.TestGeometry(c, X, nullptr, &seg), ViewResult::kSeen);
    const double tolerance = std::max(seg.t_near, (X - seg.origin).norm() - seg.t_far);
    worst_tolerance = std::max(worst_tolerance, tolerance);
    Ray exact = seg;
    exact.t_near = 1e-9;
    exact.t_far = (X - seg.origin).norm() - 1e-9;
    const bool truth = brute->Occluded(exact);
    const bool embree_says = ve.Test(c, X) == ViewResult::kOccluded;
    ++pairs;
    if (truth == embree_says) continue;
    ++disagree;
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3i& t : mesh.triangles)
      nearest =
          std::min(nearest, testing::PointTriangleDistance(
                                X, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]));
    const Vec3 a = seg.origin + seg.t_near * seg.direction,
               b = seg.origin + seg.t_far * seg.direction;
    if (!(nearest <= tolerance) && !testing::IsGrazing(mesh, a, b, tolerance, -1)) {
      ++far_from_surfaces;
      ADD_FAILURE() << "pair " << i << ": point " << nearest * 1e6
                    << " um from the nearest surface, "
                    << "tolerance " << tolerance * 1e6 << " um; reference "
                    << (truth ? "occluded" : "seen");
    }
  }
  std::printf(
      "far cameras: %d pairs, %d disagreements (all grazing or near a surface, within the "
      "tolerance), worst tolerance %.1f um\n",
      pairs, disagree, worst_tolerance * 1e6);
  EXPECT_EQ(far_from_surfaces, 0);
  // The tolerance follows the float error (2^-24 of ~300 m, times a small factor), not the scene.
  EXPECT_GT(worst_tolerance, 300.0 * std::ldexp(1.0, -24));
  EXPECT_LT(worst_tolerance, 2 * VisibilityTester::kFloatErrorFactor * 0x1p-24 * 700.0);
  EXPECT_LT(disagree, pairs / 100);
}

}  // namespace
}  // namespace pandora
