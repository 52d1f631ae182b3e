// Rigs of any size: a generated rig of 1000 cameras renders with every pixel's coverage equal to a
// brute-force count with VisibilityTester at the point the pixel shows, and its colour equal to the
// light rule's sum over all 1000 cameras; the per-pixel camera bitmask is kept for rigs of up to
// 64 cameras (bit 63 included) and dropped above, in memory and in the EXR file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/units.h"
#include "render/light.h"
#include "render/prepared_scene.h"
#include "render/render.h"
#include "render/test_options.h"

namespace pandora {
namespace {

// Uniform in [a, b) from the generator's raw output (std::uniform_real_distribution differs
// between standard libraries; this does not).
double Uniform(std::mt19937& g, double a, double b) { return a + (b - a) * (g() / 4294967296.0); }

// A floor with two boxes on it, and `n` cameras around and above them, each aimed at a point of
// the floor with one of eight fields of view; every seventh camera reaches only 4.5 m (working
// range).
Scene ManyCameraScene(int n) {
  Scene scene;
  scene.path = "many_cameras.json";
  SceneObject floor;
  floor.name = "floor";
  floor.mesh = MakePlane(Vec2(30, 30));
  scene.objects.push_back(floor);
  for (const auto& [size, centre] : {std::pair{Vec3(0.6, 0.6, 0.8), Vec3(0, 0, 0.4)},
                                     std::pair{Vec3(0.3, 0.3, 1.4), Vec3(0.9, -0.5, 0.7)}}) {
    SceneObject box;
    box.name = "box";
    box.mesh = MakeBox(size);
    for (Vec3& v : box.mesh.vertices) v += centre;
    scene.objects.push_back(box);
  }
  Rig rig;
  rig.name = "stage";
  // Eight lenses (fields of view 20 to 45 degrees), shared: a CameraModel is costly to construct.
  std::vector<CameraModel> lenses;
  for (int i = 0; i < 8; ++i) {
    Intrinsics k;
    k.width = 64;
    k.height = 48;
    k.fx = k.fy = FocalFromHfov((20 + 25 * i / 7.0) * kPi / 180.0, 64, LensModel::kPinhole);
    k.cx = 31.5;
    k.cy = 23.5;
    lenses.emplace_back(k);
  }
  std::mt19937 g(20240611);
  for (int c = 0; c < n; ++c) {
    const double azimuth = Uniform(g, 0, 2 * kPi), radius = Uniform(g, 2.5, 5.0);
    const Vec3 position(radius * std::cos(azimuth), radius * std::sin(azimuth),
                        Uniform(g, 0.8, 4.0));
    const Vec3 target(Uniform(g, -2.5, 2.5), Uniform(g, -2.5, 2.5), Uniform(g, 0.0, 0.5));
    Camera cam;
    cam.id = cam.name = "c" + std::to_string(c);
    cam.color = Vec3((c % 10) / 9.0, (c / 10 % 10) / 9.0, (c / 100) / 9.0);
    cam.world_from_camera = *LookAt(position, target, Vec3(0, 0, 1));
    cam.model = lenses[g() % 8];
    if (c % 7 == 3) cam.far = 4.5;
    rig.cameras.push_back(cam);
  }
  scene.rigs.push_back(rig);
  return scene;
}

RenderOptions Plain() { return LightOnlyOptions(); }

TEST(ManyCameras, ThousandCameraCoverageEqualsABruteForceVisibilityCount) {
  const Scene scene = ManyCameraScene(1000);
  const Rig& rig = scene.rigs[0];
  // Double-precision brute force, so the renderer's packets and the single-ray picks and tests
  // below hit and occlude exactly alike.
  const auto caster = MakeBruteForceRayCaster(scene.AllTriangles());
  const PreparedScene prepared(scene, *caster);
  RenderView view;
  view.from = Vec3(3.5, -4.0, 4.5);
  view.at = Vec3(0, 0, 0.3);
  view.fov_deg = 50;
  view.width = 64;
  view.height = 48;
  const RenderOptions options = Plain();
  const Image img = Render(prepared, rig, view, options);
  EXPECT_TRUE(img.cameras.empty());  // no bitmask beyond 64 cameras
  const PixelPicker picker(prepared, rig, view);
  const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
  LightRule rule;
  rule.brightness = DefaultBrightness(1000);
  int max_coverage = 0, beyond_64 = 0, seen_by_high = 0;
  std::vector<CameraAtPoint> at(rig.cameras.size());
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const std::size_t p = std::size_t(y) * view.width + x;
      const auto pick = picker.Pick(x, y);
      ASSERT_TRUE(pick) << x << "," << y;  // the floor fills the view
      int count = 0;
      for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
        at[c] = CameraAtPoint();
        at[c].color = rig.cameras[c].color;
        at[c].sees = tester.Test(int(c), pick->lit_point, &pick->normal) == ViewResult::kSeen;
        count += at[c].sees;
        seen_by_high += at[c].sees && c >= 64;
      }
      ASSERT_EQ(img.coverage[p], float(count)) << x << "," << y;
      EXPECT_EQ(int(pick->cameras.size()), count);
      const Vec3 light = SurfaceLight(rule, at.data(), at.size());
      for (int k = 0; k < 3; ++k) EXPECT_EQ(img.rgb[3 * p + k], float(light[k])) << x << "," << y;
      max_coverage = std::max(max_coverage, count);
      beyond_64 += count > 64;
    }
  // The test means something: many pixels are seen by more than 64 cameras, and cameras past the
  // 64th light them.
  EXPECT_GT(max_coverage, 150);
  EXPECT_GT(beyond_64, 1000);
  EXPECT_GT(seen_by_high, 100000);
  // The float file keeps the counts and has no camera set.
  const std::string exr = ::testing::TempDir() + "/thousand.exr";
  WriteExr(img, exr, 1000);
  const Image back = ReadExr(exr);
  EXPECT_EQ(back.coverage, img.coverage);
  EXPECT_EQ(back.rgb, img.rgb);
  EXPECT_TRUE(back.cameras.empty());
}

// At the boundary: 64 cameras keep the bitmask, bit 63 included; 65 drop it. Identical cameras
// stacked above a floor, so every lit pixel is seen by all of them.
TEST(ManyCameras, BitmaskUpTo64CamerasAndNoneBeyond) {
  for (int n : {64, 65}) {
    Scene scene;
    SceneObject floor;
    floor.name = "floor";
    floor.mesh = MakePlane(Vec2(20, 20));
    scene.objects.push_back(floor);
    Rig rig;
    rig.name = "stack";
    for (int c = 0; c < n; ++c) {
      Camera cam;
      cam.id = cam.name = "c" + std::to_string(c);
      cam.color = Vec3(1, 1, 1);
      cam.world_from_camera = *LookAt(Vec3(0, 0, 3), Vec3(0, 0, 0), Vec3(0, 1, 0));
      Intrinsics k;
      k.width = 64;
      k.height = 48;
      k.fx = k.fy = 64;
      k.cx = 31.5;
      k.cy = 23.5;
      cam.model = CameraModel(k);
      rig.cameras.push_back(cam);
    }
    const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
    RenderView view;
    view.camera = 0;  // the cameras' own view: every pixel on the floor, seen by all of them
    view.width = 32;
    view.height = 24;
    const Image img = Render(scene, rig, *caster, view, Plain());
    SCOPED_TRACE(n);
    if (n == 64) {
      ASSERT_EQ(img.cameras.size(), std::size_t(32 * 24));
      for (std::size_t p = 0; p < img.cameras.size(); ++p) {
        EXPECT_EQ(img.cameras[p], ~uint64_t(0)) << p;  // bits 0 .. 63
        EXPECT_EQ(img.coverage[p], 64.0f);
      }
      const std::string exr = ::testing::TempDir() + "/stack64.exr";
      WriteExr(img, exr, 64);
      EXPECT_EQ(ReadExr(exr).cameras, img.cameras);
    } else {
      EXPECT_TRUE(img.cameras.empty());
      for (float c : img.coverage) EXPECT_EQ(c, 65.0f);
      // Default brightness 3 / 65 per camera: 65 white lights sum to 3.
      for (float v : img.rgb) EXPECT_NEAR(v, 3.0, 1e-5);
      // A camera set for more than 64 cameras, or none for up to 64, is refused.
      EXPECT_THROW(WriteExr(img, ::testing::TempDir() + "/stack65.exr", 64), std::invalid_argument);
    }
  }
}

}  // namespace
}  // namespace pandora
