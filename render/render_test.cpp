// Analytic image tests of the projective-light renderer: every expected pixel value is computed in
// closed form here (ray-plane and ray-sphere intersection, the camera model's projection), not by
// the renderer.
#include "render/render.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "render/colormap.h"
#include "render/prepared_scene.h"
#include "tests/fixtures.h"

namespace pandora {
namespace {

Camera MakeCamera(const std::string& id, const Vec3& from, const Vec3& at, const Vec3& up, int w,
                  int h, double hfov_deg, const Vec3& color, LensModel lens = LensModel::kPinhole,
                  double k1 = 0, double k2 = 0) {
  Camera c = testing::WithIntrinsics(testing::TestCamera(id, from, at, hfov_deg, w, h, lens, up),
                                     [&](Intrinsics& k) {
                                       k.k1 = k1;
                                       k.k2 = k2;
                                     });
  c.color = color;
  return c;
}

// A floor: 20 m square at z = 0, normal +z.
SceneObject Floor() {
  SceneObject o;
  o.name = "floor";
  o.source = "plane";
  o.mesh = MakePlane(Vec2(20, 20));
  return o;
}

SceneObject Sphere(const Vec3& center, double radius, int segments) {
  SceneObject o;
  o.name = "ball";
  o.source = "sphere";
  o.mesh = MakeSphere(radius, segments);
  for (Vec3& v : o.mesh.vertices) v += center;
  return o;
}

// The eye ray of output pixel (x, y) of a pinhole RenderView, computed independently of render.cpp.
Vec3 EyeRay(const RenderView& v, double x, double y) {
  const Eigen::Isometry3d pose = *LookAt(v.from, v.at, v.up);
  const double f = 0.5 * v.width / std::tan(0.5 * v.fov_deg * kPi / 180.0);
  const Vec3 d((x - (0.5 * v.width - 0.5)) / f, (y - (0.5 * v.height - 0.5)) / f, 1.0);
  return (pose.linear() * d).normalized();
}

// Where the eye ray meets the plane z = 0 (t > 0), or nullopt.
std::optional<Vec3> HitFloor(const Vec3& eye, const Vec3& d) {
  if (d.z() >= 0) return std::nullopt;
  const double t = -eye.z() / d.z();
  return eye + t * d;
}

RenderOptions BlackOptions() {
  RenderOptions o;
  o.surface = Surface::kBlack;
  o.background = Vec3::Zero();
  o.overlays.cameras = false;
  o.overlays.key = false;  // the colour key has its own test (palette_test.cpp)
  return o;
}

// Camera pixel distance to the image border (negative outside); nullopt when not projectable.
std::optional<double> BorderMargin(const Camera& cam, const Vec3& X) {
  const auto px = cam.Project(X);
  if (!px) return std::nullopt;
  const double w = cam.model.width() - 0.5, h = cam.model.height() - 0.5;
  return std::min({px->x() + 0.5, w - px->x(), px->y() + 0.5, h - px->y()});
}

// A floor lit by one red camera with strong barrel distortion (the footprint's edges are curves,
// not the pinhole's straight lines), seen from above at an angle.
struct OneCameraFloor {
  Scene scene;
  Rig rig;
  RenderView view;
};
OneCameraFloor MakeOneCameraFloor(int width, int height) {
  OneCameraFloor s;
  s.scene.objects.push_back(Floor());
  s.rig.name = "one";
  s.rig.cameras.push_back(MakeCamera("c0", Vec3(0.2, -0.1, 2.0), Vec3(0.5, 0.3, 0.0), Vec3(0, 1, 0),
                                     64, 48, 70, Vec3(1, 0, 0), LensModel::kBrownConrady, -0.25,
                                     0.05));
  s.view.from = Vec3(-1.5, -2.5, 3.5);
  s.view.at = Vec3(0.4, 0.2, 0.0);
  s.view.fov_deg = 75;
  s.view.width = width;
  s.view.height = height;
  return s;
}

TEST(Render, OptionsCheckNamesTheFieldAtFault) {
  const auto fault = [](const std::function<void(RenderOptions&)>& set) {
    RenderOptions o;
    set(o);
    try {
      o.Check();
    } catch (const InputError& e) {
      return e.file();
    }
    return std::string("ok");
  };
  EXPECT_EQ(fault([](RenderOptions&) {}), "ok");
  EXPECT_EQ(fault([](RenderOptions& o) { o.brightness = 1e6; }), "ok");
  EXPECT_EQ(fault([](RenderOptions& o) { o.brightness = 0; }), "{brightness}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.ambient = 1.5; }), "{ambient}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.grid_pixels = 0; }), "{grid_pixels}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.grid_fill = NAN; }), "{grid_fill}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.line_width_px = 0; }), "{line_width_px}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.line_grey = -0.1; }), "{line_grey}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.samples = 16; }), "ok");
  EXPECT_EQ(fault([](RenderOptions& o) { o.samples = 17; }), "{samples}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.background.x() = INFINITY; }), "{background}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.pixel_sigma = 0; }), "{pixel_sigma}");
  EXPECT_EQ(fault([](RenderOptions& o) { o.ptz_all.push_back({0, -1}); }), "{budget_s}");
}

TEST(Render, SingleCameraLightsExactlyItsDistortedFootprint) {
  const OneCameraFloor setup = MakeOneCameraFloor(160, 120);
  const Scene& scene = setup.scene;
  const Rig& rig = setup.rig;
  const RenderView& view = setup.view;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Image img = Render(scene, rig, *caster, view, BlackOptions());
  ASSERT_EQ(img.width, 160);
  const Camera& cam = rig.cameras[0];
  Camera pin = cam;
  Intrinsics k = cam.model.intrinsics();
  k.model = LensModel::kPinhole;
  k.k1 = k.k2 = 0;
  pin.model = CameraModel(k);
  int lit = 0, dark = 0, checked = 0, curved = 0;
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const auto X = HitFloor(view.from, EyeRay(view, x, y));
      ASSERT_TRUE(X) << x << "," << y;
      const auto margin = BorderMargin(cam, *X);
      // The renderer's hit point carries Embree's float round-off (~1e-6 m here, far below
      // 1e-3 camera pixels): pixels that close to the footprint's edge are not decided here.
      if (margin && std::abs(*margin) < 1e-3) continue;
      const bool expected = margin && *margin > 0;
      const Vec3 rgb = img.Rgb(x, y);
      ++checked;
      if (expected) {
        ++lit;
        EXPECT_EQ(rgb, Vec3(1, 0, 0)) << "pixel " << x << "," << y;
        EXPECT_EQ(img.coverage[y * img.width + x], 1.0f);
        EXPECT_EQ(img.cameras[y * img.width + x], 1u);
      } else {
        ++dark;
        EXPECT_EQ(rgb, Vec3::Zero()) << "pixel " << x << "," << y;
        EXPECT_EQ(img.coverage[y * img.width + x], 0.0f);
      }
      // Pixels the distorted footprint lights but the pinhole one (same intrinsics, k = 0) would
      // not: the test must see the distortion.
      const auto pm = BorderMargin(pin, *X);
      if (expected != (pm && *pm > 0)) ++curved;
    }
  EXPECT_GT(lit, 1000);
  EXPECT_GT(dark, 1000);
  EXPECT_GT(curved, 50);  // barrel distortion widens the footprint
  EXPECT_GE(checked, view.width * view.height - 20);
}

// Antialiasing: with samples = 3 each pixel's colour is the share of its 3 x 3 stratified sample
// points (at x - 0.5 + (i + 0.5) / 3) inside the distorted footprint, in closed form; the layers
// still come from the pixel centre.
TEST(Render, StratifiedSamplesAverageTheFootprintInsideEachPixel) {
  const OneCameraFloor setup = MakeOneCameraFloor(80, 60);
  const Scene& scene = setup.scene;
  const Rig& rig = setup.rig;
  const RenderView& view = setup.view;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderOptions options = BlackOptions();
  options.samples = 3;
  const Image img = Render(scene, rig, *caster, view, options);
  const Camera& cam = rig.cameras[0];
  int partial = 0, checked = 0;
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      int inside = 0;
      bool undecided = false;
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
          const auto X =
              HitFloor(view.from, EyeRay(view, x - 0.5 + (i + 0.5) / 3, y - 0.5 + (j + 0.5) / 3));
          ASSERT_TRUE(X);
          const auto margin = BorderMargin(cam, *X);
          if (margin && std::abs(*margin) < 1e-3) undecided = true;
          inside += margin && *margin > 0;
        }
      if (undecided) continue;
      ++checked;
      partial += inside > 0 && inside < 9;
      EXPECT_NEAR(img.Rgb(x, y).x(), inside / 9.0, 1e-6) << "pixel " << x << "," << y;
      EXPECT_EQ(img.Rgb(x, y).y(), 0.0f);
      const auto centre = BorderMargin(cam, *HitFloor(view.from, EyeRay(view, x, y)));
      if (centre && std::abs(*centre) > 1e-3) {
        EXPECT_EQ(img.coverage[y * img.width + x], *centre > 0 ? 1.0f : 0.0f) << x << "," << y;
      }
    }
  EXPECT_GT(partial, 40);  // the footprint's edge crosses many pixels part-way
  EXPECT_GE(checked, view.width * view.height - 20);
}

TEST(Render, SphereCastsThePredictedShadow) {
  Scene scene;
  scene.objects.push_back(Floor());
  const Vec3 center(0.1, 0.05, 1.2);
  const double r = 0.3;
  const int segments = 96;
  scene.objects.push_back(Sphere(center, r, segments));
  Rig rig;
  rig.name = "top";
  rig.cameras.push_back(
      MakeCamera("top", Vec3(0, 0, 3), Vec3(0, 0, 0), Vec3(0, 1, 0), 80, 80, 90, Vec3(0, 0.5, 1)));
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderView view;
  view.from = Vec3(2.5, -1.5, 4.0);
  view.at = Vec3(0, 0, 0);
  view.fov_deg = 60;
  view.width = 128;
  view.height = 96;
  const Image img = Render(scene, rig, *caster, view, BlackOptions());
  const Camera& cam = rig.cameras[0];
  // The tessellated sphere lies between the sphere of radius r (its vertices) and the sphere of
  // radius r cos^2(pi / segments) (its faces' nearest points, generously): decided outside that
  // band.
  const double r_in = r * std::pow(std::cos(kPi / segments), 2);
  auto distance_to_segment = [&](const Vec3& a, const Vec3& b) {
    const Vec3 ab = b - a;
    const double s = std::clamp((center - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    return (a + s * ab - center).norm();
  };
  int shadowed = 0, lit = 0;
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const Vec3 d = EyeRay(view, x, y);
      // Skip pixels whose eye ray may meet the ball itself.
      if (distance_to_segment(view.from, view.from + 10.0 * d) < r + 1e-9) continue;
      const auto X = HitFloor(view.from, d);
      ASSERT_TRUE(X);
      const auto margin = BorderMargin(cam, *X);
      if (!margin || *margin < 1e-3) continue;  // outside the footprint (or at its edge)
      const double dist = distance_to_segment(cam.center(), *X);
      if (dist > r_in - 1e-6 && dist < r + 1e-6) continue;
      const bool expect_lit = dist >= r;
      const Vec3 rgb = img.Rgb(x, y);
      if (expect_lit) {
        ++lit;
        EXPECT_EQ(rgb, Vec3(0, 0.5, 1)) << x << "," << y;
      } else {
        ++shadowed;
        EXPECT_EQ(rgb, Vec3::Zero()) << x << "," << y;
      }
    }
  EXPECT_GT(shadowed, 200);
  EXPECT_GT(lit, 2000);
}

TEST(Render, OverlappingCamerasSumTheirColoursAndLayersMatchThePerPointComputation) {
  Scene scene;
  scene.objects.push_back(Floor());
  Rig rig;
  rig.name = "pair";
  rig.cameras.push_back(MakeCamera("a", Vec3(-0.6, 0, 2), Vec3(-0.2, 0, 0), Vec3(0, 1, 0), 40, 30,
                                   60, Vec3(1, 0, 0)));
  rig.cameras.push_back(MakeCamera("b", Vec3(0.6, 0.1, 2.2), Vec3(0.2, 0, 0), Vec3(0, 1, 0), 50, 40,
                                   55, Vec3(0, 1, 0)));
  rig.cameras[1].pixel_sigma = 0.8;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderView view;
  view.from = Vec3(0, -2.0, 3.0);
  view.at = Vec3(0, 0, 0);
  view.fov_deg = 70;
  view.width = 120;
  view.height = 90;
  RenderOptions options = BlackOptions();
  options.brightness = 0.5;
  options.pixel_sigma = 0.4;
  const Image rendered = Render(scene, rig, *caster, view, options);
  // The layers are checked as read back from the EXR file (WriteExr, then OpenEXR's reader).
  const std::string exr = ::testing::TempDir() + "/two_cameras.exr";
  WriteExr(rendered, exr, 2);
  const Image img = ReadExr(exr);
  ASSERT_EQ(img.width, rendered.width);
  int both = 0;
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const auto X = HitFloor(view.from, EyeRay(view, x, y));
      ASSERT_TRUE(X);
      const auto ma = BorderMargin(rig.cameras[0], *X), mb = BorderMargin(rig.cameras[1], *X);
      if ((ma && std::abs(*ma) < 1e-3) || (mb && std::abs(*mb) < 1e-3)) continue;
      const bool sa = ma && *ma > 0, sb = mb && *mb > 0;
      const Vec3 expected =
          0.5 * ((sa ? Vec3(1, 0, 0) : Vec3::Zero()) + (sb ? Vec3(0, 1, 0) : Vec3::Zero()));
      EXPECT_EQ(img.Rgb(x, y), expected) << x << "," << y;
      const std::size_t p = std::size_t(y) * img.width + x;
      EXPECT_EQ(img.coverage[p], float(sa + sb));
      EXPECT_EQ(img.cameras[p], uint64_t(sa) | (uint64_t(sb) << 1));
      // Resolution and sigma_max from the projection Jacobians at the closed-form point.
      double best = 0;
      InformationBuilder info;
      const double sigma[2] = {0.4, 0.8};
      for (int c = 0; c < 2; ++c) {
        if (!(c == 0 ? sa : sb)) continue;
        Mat23 J;
        ASSERT_TRUE(rig.cameras[c].Project(*X, &J));
        best = std::max(best, PixelDensity(J));
        info.Add(J, sigma[c]);
      }
      EXPECT_NEAR(img.resolution[p], best, 1e-4 * best + 1e-9);
      EXPECT_NEAR(img.depth[p], (*X - view.from).norm(), 1e-5);
      if (sa && sb) {
        ++both;
        const StaticUncertainty u = StaticFromInformation(info.Decompose(), 2);
        ASSERT_TRUE(u.triangulable);
        EXPECT_NEAR(img.sigma_max[p], 1e3 * u.sigma_max, 1e-3 * 1e3 * u.sigma_max);
      } else {
        EXPECT_TRUE(std::isinf(img.sigma_max[p]));
      }
    }
  EXPECT_GT(both, 300);
}

TEST(Render, GridPatternDrawsTheCamerasPixelGridInItsOwnEyeView) {
  Scene scene;
  scene.objects.push_back(Floor());
  Rig rig;
  rig.name = "grid";
  rig.cameras.push_back(
      MakeCamera("g", Vec3(0, 0, 2), Vec3(0, 0, 0), Vec3(0, 1, 0), 64, 48, 60, Vec3(1, 1, 1)));
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderView view;
  view.camera = 0;
  view.width = 64;
  view.height = 48;
  RenderOptions options = BlackOptions();
  options.pattern = Pattern::kGrid;
  options.grid_pixels = 8;
  options.line_width_px = 1.2;
  options.grid_fill = 0.15;
  const Image img = Render(scene, rig, *caster, view, options);
  // Tolerance 1e-4: the hit point carries Embree's float round-off.
  // Output pixel = camera pixel; lines lie on the pixel borders u = 8k - 0.5: the pixels on either
  // side are 0.5 px from a line and get the box-filtered coverage 0.6 + 0.5 - 0.5 = 0.6.
  auto line = [](int u) { return (u % 8 == 0 || u % 8 == 7) ? 0.6 : 0.0; };
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const double l = 1.0 - (1.0 - line(x)) * (1.0 - line(y));
      const double expected = 0.15 + 0.85 * l;
      EXPECT_NEAR(img.Rgb(x, y).x(), expected, 1e-4) << x << "," << y;
    }
}

// A camera mounted exactly on a wall's inner face (as `pandora rig --along` once placed two): the
// camera centre's side of the surface decides, for the fields and the renderer alike. Its own view
// shows the room, not a flat wall at distance 0, and every pixel it shows is a point the fields'
// visibility test says it sees, and lit by it in the image.
TEST(Render, CameraOnAWallFaceSeesTheRoomAsItsFieldsDo) {
  Scene scene;
  scene.objects.push_back(Floor());
  SceneObject wall;
  wall.name = "wall";
  wall.source = "box";
  wall.mesh = MakeBox(Vec3(0.2, 6, 3));
  for (Vec3& v : wall.mesh.vertices) v += Vec3(-2.1, 0, 1.5);  // inner face at x = -2
  scene.objects.push_back(wall);
  Rig rig;
  rig.name = "wall";
  rig.cameras.push_back(
      MakeCamera("w", Vec3(-2.0, 0, 1.5), Vec3(0, 0, 0), Vec3(0, 0, 1), 32, 24, 60, Vec3(1, 1, 1)));
  const PreparedScene prepared(scene);
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const VisibilityTester tester(rig.cameras, *caster, scene.Bounds().diagonal());
  RenderView view;
  view.camera = 0;
  view.width = 32;
  view.height = 24;
  const Image img = Render(scene, rig, *caster, view, BlackOptions());
  int floor_pixels = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 32; ++x) {
      const auto pick = PickPixel(prepared, rig, view, x, y);
      if (!pick) continue;
      // Never the wall the camera sits on (at depth 0): the floor, metres away.
      EXPECT_NE(scene.objects[pick->object].name, "wall")
          << x << "," << y << " depth " << pick->depth;
      EXPECT_GT(pick->depth, 0.5) << x << "," << y;
      // The fields' rule says the camera sees the point the image shows there, and the image lights
      // it.
      EXPECT_EQ(tester.Test(0, pick->lit_point, &pick->normal), ViewResult::kSeen) << x << "," << y;
      EXPECT_GT(img.Rgb(x, y).x(), 0.0) << x << "," << y;
      ++floor_pixels;
    }
  EXPECT_GT(floor_pixels, 32 * 24 / 3);  // looking down at the floor from 1.5 m
}

TEST(Render, CamerasEyeViewThroughAFisheyeSeesOnlyWhatItLights) {
  Scene scene;
  scene.objects.push_back(Floor());
  scene.objects.push_back(Sphere(Vec3(0.3, 0.2, 0.8), 0.25, 48));
  Rig rig;
  rig.name = "fish";
  rig.cameras.push_back(MakeCamera("f", Vec3(0, 0, 2), Vec3(0, 0, 0), Vec3(0, 1, 0), 64, 64, 150,
                                   Vec3(1, 1, 0), LensModel::kFisheye, 0.02, 0.0));
  rig.cameras.push_back(
      MakeCamera("side", Vec3(3, 0, 1), Vec3(0, 0, 0), Vec3(0, 0, 1), 32, 32, 40, Vec3(0, 0, 1)));
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderView view;
  view.camera = 0;
  view.width = 64;
  view.height = 64;
  const Image img = Render(scene, rig, *caster, view, BlackOptions());
  int hits = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const std::size_t p = std::size_t(y) * 64 + x;
      if (!std::isfinite(img.depth[p])) continue;
      ++hits;
      // Everything a camera images (first surface along its own rays) it also lights.
      EXPECT_TRUE(img.cameras[p] & 1u) << x << "," << y;
      EXPECT_EQ(img.Rgb(x, y).x(), 1.0);
      // And the depth is the distance to that first surface along the camera's unprojected ray.
      const auto dir = rig.cameras[0].model.Unproject(Vec2(x, y));
      ASSERT_TRUE(dir);
      const Vec3 d = rig.cameras[0].world_from_camera.linear() * *dir;
      const auto hit = caster->Intersect(Ray{rig.cameras[0].center(), d, 0, 1e9});
      ASSERT_TRUE(hit);
      EXPECT_NEAR(img.depth[p], hit->t, 1e-5);
    }
  EXPECT_GT(hits, 64 * 64 / 2);
}

TEST(Render, HiddenLineDrawsBoxEdgesButNotCoplanarDiagonals) {
  Scene scene;
  SceneObject box;
  box.name = "box";
  box.source = "box";
  box.mesh = MakeBox(Vec3(1, 1, 1));
  for (Vec3& v : box.mesh.vertices) v += Vec3(0, 0, 0.5);
  scene.objects.push_back(box);
  Rig rig;
  rig.name = "none";
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderView view;
  view.from = Vec3(0.0, -0.2, 3.0);  // looking down at the top face (z = 1), nearly head-on
  view.at = Vec3(0.0, 0.0, 1.0);
  view.up = Vec3(0, 1, 0);
  view.fov_deg = 50;
  view.width = 101;
  view.height = 101;
  RenderOptions options = BlackOptions();
  options.surface = Surface::kHiddenLine;
  options.line_width_px = 1.5;
  const Image img = Render(scene, rig, *caster, view, options);
  // Project the top face's corners with the view's pinhole to find its edges on screen.
  const Eigen::Isometry3d cfw = LookAt(view.from, view.at, view.up)->inverse();
  const double f = 0.5 * view.width / std::tan(0.5 * view.fov_deg * kPi / 180.0);
  auto project = [&](const Vec3& X) {
    const Vec3 p = cfw * X;
    return Vec2(f * p.x() / p.z() + 50.0, f * p.y() / p.z() + 50.0);
  };
  // Every pixel whose centre ray meets the top face (z = 1, |x|, |y| < 0.5; the eye is above it,
  // so nothing else is visible) shows grey * box-filtered line coverage of the nearest projected
  // face edge (distance from the pixel centre to the projected edge line); the face's diagonal is
  // between coplanar triangles and is not drawn. Silhouette edges are drawn on the face's side.
  const Vec2 corners[4] = {project(Vec3(-0.5, -0.5, 1)), project(Vec3(0.5, -0.5, 1)),
                           project(Vec3(0.5, 0.5, 1)), project(Vec3(-0.5, 0.5, 1))};
  int near_edges = 0, interior = 0;
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const Vec3 d = EyeRay(view, x, y);
      const double t = (1.0 - view.from.z()) / d.z();
      const Vec3 X = view.from + t * d;
      if (std::abs(X.x()) > 0.5 - 1e-6 || std::abs(X.y()) > 0.5 - 1e-6) continue;
      double dist = 1e9;
      for (int e = 0; e < 4; ++e) {
        const Vec2 a = corners[e], b = corners[(e + 1) % 4];
        const Vec2 n = Vec2(-(b - a).y(), (b - a).x()).normalized();
        dist = std::min(dist, std::abs(n.dot(Vec2(x, y) - a)));
      }
      const double expected =
          options.line_grey * std::clamp(0.5 * options.line_width_px + 0.5 - dist, 0.0, 1.0);
      // The renderer linearises the projection at the hit point (ray differentials): second-order
      // differences within a pixel of the edge stay below 1e-3 here.
      EXPECT_NEAR(img.Rgb(x, y).x(), expected, 1e-3) << x << "," << y << " distance " << dist;
      if (expected > 0)
        ++near_edges;
      else
        ++interior;
    }
  EXPECT_GT(near_edges, 150);
  EXPECT_GT(interior, 1000);
}

TEST(Render, ContoursOutlineAPlateAboveTheFloor) {
  Scene scene;
  scene.objects.push_back(Floor());
  SceneObject plate;
  plate.name = "plate";
  plate.mesh = MakePlane(Vec2(1, 1));
  for (Vec3& v : plate.mesh.vertices) v.z() += 1.0;
  scene.objects.push_back(plate);
  Rig rig;
  rig.name = "none";
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderView view;
  view.from = Vec3(0.1, 0.05, 3.0);
  view.at = Vec3(0.1, 0.05, 0.0);
  view.up = Vec3(0, 1, 0);
  view.fov_deg = 60;
  view.width = 90;
  view.height = 70;
  RenderOptions options = BlackOptions();
  options.surface = Surface::kContours;
  const Image img = Render(scene, rig, *caster, view, options);
  // Which object each pixel centre sees, in closed form: the plate where the ray meets z = 1 within
  // |x|, |y| < 0.5, else the floor. The contour is drawn on the plate's (nearer) pixels that have a
  // floor pixel among their four neighbours; nothing else is grey (floor and plate are flat and
  // parallel: no crease, no depth jump within either).
  auto object = [&](int x, int y, bool* ambiguous) {
    const Vec3 d = EyeRay(view, x, y);
    const Vec3 X = view.from + ((1.0 - view.from.z()) / d.z()) * d;
    const double m = 0.5 - std::max(std::abs(X.x()), std::abs(X.y()));
    *ambiguous = std::abs(m) < 1e-6;
    return m > 0 ? 1 : 0;
  };
  int outline = 0;
  for (int y = 1; y + 1 < view.height; ++y)
    for (int x = 1; x + 1 < view.width; ++x) {
      bool amb = false, a2 = false;
      const int o = object(x, y, &amb);
      bool edge = false;
      const int n[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
      for (const auto& k : n) {
        edge |= object(x + k[0], y + k[1], &a2) != o;
        amb |= a2;
      }
      if (amb) continue;
      const double expected = (o == 1 && edge) ? options.line_grey : 0.0;
      EXPECT_NEAR(img.Rgb(x, y).x(), expected, 1e-7) << x << "," << y;
      EXPECT_EQ(img.object[y * view.width + x], o);
      outline += expected > 0;
    }
  EXPECT_GT(outline, 80);
}

TEST(Render, EmbreeAndTheDoublePrecisionBruteForceCasterGiveTheSameImage) {
  Scene scene;
  scene.objects.push_back(Floor());
  scene.objects.push_back(Sphere(Vec3(0.2, -0.1, 0.6), 0.35, 24));
  SceneObject box;
  box.name = "box";
  box.mesh = MakeBox(Vec3(0.5, 0.3, 0.8));
  for (Vec3& v : box.mesh.vertices) v += Vec3(-0.6, 0.4, 0.4);
  scene.objects.push_back(box);
  Rig rig;
  rig.name = "three";
  rig.cameras.push_back(MakeCamera("a", Vec3(1.5, -1.5, 2), Vec3(0, 0, 0.3), Vec3(0, 0, 1), 64, 48,
                                   60, Vec3(1, 0, 0), LensModel::kBrownConrady, -0.1, 0.01));
  rig.cameras.push_back(MakeCamera("b", Vec3(-1.5, -1.2, 1.8), Vec3(0, 0, 0.3), Vec3(0, 0, 1), 64,
                                   48, 70, Vec3(0, 1, 0)));
  rig.cameras.push_back(MakeCamera("c", Vec3(0.2, 1.8, 2.2), Vec3(0, 0, 0.3), Vec3(0, 0, 1), 64, 48,
                                   80, Vec3(0, 0, 1), LensModel::kFisheye, 0.01));
  const TriangleMesh all = scene.AllTriangles();
  const auto embree = MakeEmbreeRayCaster(all);
  const auto brute = MakeBruteForceRayCaster(all);
  RenderView view;
  view.from = Vec3(0.5, -3.0, 2.5);
  view.at = Vec3(0, 0, 0.4);
  view.fov_deg = 55;
  view.width = 80;
  view.height = 60;
  for (Pattern pattern : {Pattern::kUniform, Pattern::kGrid}) {
    RenderOptions options;
    options.pattern = pattern;
    options.grid_pixels = 8;
    const Image a = Render(scene, rig, *embree, view, options);
    const Image b = Render(scene, rig, *brute, view, options);
    int same_cameras = 0, close = 0;
    for (int p = 0; p < a.width * a.height; ++p) {
      same_cameras += a.cameras[p] == b.cameras[p];
      const Vec3 d = a.Rgb(p % a.width, p / a.width) - b.Rgb(p % a.width, p / a.width);
      close += d.cwiseAbs().maxCoeff() < 1e-3;
    }
    // Single against double precision: rays through shared edges and silhouettes may differ.
    EXPECT_GE(same_cameras, a.width * a.height - 12);
    EXPECT_GE(close, a.width * a.height - 24);
  }
}

TEST(Render, ViridisMatchesThePublishedTable) {
  // matplotlib's _viridis_data entries 0, 128 and 255.
  EXPECT_LT((ViridisSrgb(0.0) - Vec3(0.267004, 0.004874, 0.329415)).cwiseAbs().maxCoeff(), 0.012);
  EXPECT_LT((ViridisSrgb(128.0 / 255) - Vec3(0.128729, 0.563265, 0.551229)).cwiseAbs().maxCoeff(),
            0.012);
  EXPECT_LT((ViridisSrgb(1.0) - Vec3(0.993248, 0.906157, 0.143936)).cwiseAbs().maxCoeff(), 0.015);
  // Perceptually ordered: lightness (here luma) increases monotonically.
  double last = -1;
  for (int i = 0; i <= 100; ++i) {
    const Vec3 c = ViridisLinear(i / 100.0);
    const double luma = 0.2126 * c.x() + 0.7152 * c.y() + 0.0722 * c.z();
    EXPECT_GT(luma, last);
    last = luma;
  }
}

TEST(Render, ExrAndPngRoundTrip) {
  Image img;
  img.width = 7;
  img.height = 5;
  const std::size_t n = 35;
  for (std::size_t i = 0; i < n; ++i) {
    img.rgb.insert(img.rgb.end(), {0.01f * i, 0.5f, 2.0f});
    img.coverage.push_back(float(i % 4));
    img.cameras.push_back((uint64_t(1) << (i % 40)) | 1u);
    img.resolution.push_back(100.0f + i);
    img.sigma_max.push_back(i % 3 ? 1.5f * i : std::numeric_limits<float>::infinity());
    img.depth.push_back(i % 5 ? 0.25f * i : std::numeric_limits<float>::infinity());
    img.object.push_back(0);
  }
  const std::string dir = ::testing::TempDir();
  const std::string exr = dir + "/round_trip.exr", png = dir + "/round_trip.png";
  WriteExr(img, exr, 40);
  const Image back = ReadExr(exr);
  ASSERT_EQ(back.width, 7);
  ASSERT_EQ(back.height, 5);
  EXPECT_EQ(back.rgb, img.rgb);
  EXPECT_EQ(back.coverage, img.coverage);
  EXPECT_EQ(back.cameras, img.cameras);
  EXPECT_EQ(back.resolution, img.resolution);
  EXPECT_EQ(back.sigma_max, img.sigma_max);
  EXPECT_EQ(back.depth, img.depth);
  WritePng(img, png);
  const Image p = ReadPng(png);
  ASSERT_EQ(p.width, 7);
  for (std::size_t i = 0; i < 3 * n; ++i) {
    const double expected = std::clamp(double(img.rgb[i]), 0.0, 1.0);
    // 8-bit sRGB: half a code step in sRGB space, mapped back to linear.
    const double step =
        LinearFromSrgb(std::min(1.0, SrgbFromLinear(expected) + 0.5 / 255)) - expected;
    EXPECT_NEAR(p.rgb[i], expected, std::abs(step) + 1e-6) << i;
  }
  // The file is the bytes EncodePng gives in memory.
  std::ifstream in(png, std::ios::binary);
  const std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(file, EncodePng(img));
  // 8-bit sRGB codes are stored as they are: read back through the inverse curve, each code.
  std::vector<std::uint8_t> codes(3 * n);
  for (std::size_t i = 0; i < codes.size(); ++i) codes[i] = std::uint8_t((37 * i) % 256);
  WriteFileAtomically(png, EncodePngSrgb8(7, 5, codes));
  const Image q = ReadPng(png);
  for (std::size_t i = 0; i < codes.size(); ++i)
    EXPECT_EQ(q.rgb[i], float(LinearFromSrgb(codes[i] / 255.0))) << i;
  EXPECT_THROW(EncodePngSrgb8(7, 5, std::vector<std::uint8_t>(3)), std::invalid_argument);
  // The EXR's channels are the layer table's (and R, G, B, cameras, cameras_hi).
  EXPECT_EQ(ImageFloatLayers().size(), 4u);
  for (const ImageLayer& layer : ImageFloatLayers()) EXPECT_EQ((back.*layer.values).size(), n);
}

}  // namespace
}  // namespace pandora

namespace pandora {
namespace {

// Reference images of the trauma room (tests/data/render/). The analytic tests above pin the
// semantics; these catch unintended changes to everything together (shading, overlays, patterns).
// Threshold: at least 99 % of the pixels within 2 codes (8-bit sRGB) on every channel and a mean
// absolute difference below 0.5 codes. Exact equality is not required because Embree's float
// traversal may resolve rays through shared triangle edges differently on other CPUs (ISA-specific
// BVH builds); such rays change a handful of pixels by a whole surface colour. Regenerate after an
// intended change with PANDORA_UPDATE_RENDER_REFERENCES=1 and look at the images before committing.
struct Reference {
  const char* file;
  const char* view;  // scene view, or "" for the camera's-eye view of camera 0
  Pattern pattern;
  Surface surface;
  int width, height;
};

std::vector<int> Codes(const Image& img) {
  std::vector<int> codes(img.rgb.size());
  for (std::size_t i = 0; i < codes.size(); ++i)
    codes[i] = int(std::lround(255.0 * SrgbFromLinear(img.rgb[i])));
  return codes;
}

TEST(RenderReference, TraumaRoomImagesMatchTheCommittedReferences) {
  const Scene scene = LoadScene("examples/trauma_room/scene.json");
  const Rig& rig = scene.FindRig("");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Reference refs[] = {
      {"trauma_overview_material.png", "overview", Pattern::kUniform, Surface::kMaterial, 192, 108},
      {"trauma_overview_grid_hidden_line.png", "overview", Pattern::kGrid, Surface::kHiddenLine,
       192, 108},
      {"trauma_overview_contours.png", "overview", Pattern::kUniform, Surface::kContours, 192, 108},
      {"trauma_camera0_eye.png", "", Pattern::kUniform, Surface::kMaterial, 128, 96},
  };
  const bool update = std::getenv("PANDORA_UPDATE_RENDER_REFERENCES") != nullptr;
  for (const Reference& ref : refs) {
    SCOPED_TRACE(ref.file);
    RenderView view;
    if (*ref.view) {
      view = ViewFromScene(scene.views.at(ref.view), ref.width, ref.height);
    } else {
      view.camera = 0;
      view.width = ref.width;
      view.height = ref.height;
    }
    RenderOptions options;
    options.pattern = ref.pattern;
    options.surface = ref.surface;
    options.grid_pixels = 64;
    options.brightness = 0.6;
    options.overlays.key = false;  // the colour key has its own test (palette_test.cpp)
    const Image img = Render(scene, rig, *caster, view, options);
    const std::string path = std::string("tests/data/render/") + ref.file;
    if (update) {
      std::filesystem::create_directories("tests/data/render");
      WritePng(img, path);
      continue;
    }
    const Image expected = ReadPng(path);
    ASSERT_EQ(expected.width, img.width);
    ASSERT_EQ(expected.height, img.height);
    const std::vector<int> a = Codes(img), b = Codes(expected);
    std::size_t close = 0;
    double sum = 0;
    for (int p = 0; p < img.width * img.height; ++p) {
      int worst = 0;
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(a[3 * p + k] - b[3 * p + k]));
      close += worst <= 2;
      for (int k = 0; k < 3; ++k) sum += std::abs(a[3 * p + k] - b[3 * p + k]);
    }
    const double pixels = img.width * img.height;
    EXPECT_GE(close / pixels, 0.99);
    EXPECT_LT(sum / (3 * pixels), 0.5);
  }
}

// Textures end to end: an OBJ quad with texture coordinates and a 2x2 PNG (red, green / blue,
// white; map_Kd in its MTL file), loaded as a scene and rendered from straight above with no camera
// light: each quadrant shows its texel times the ambient shading, with v = 0 at the image's bottom.
TEST(Render, ObjTextureAppearsOnItsQuadrants) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "pandora_texture_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Image tex;
  tex.width = tex.height = 2;
  tex.rgb = {1, 0, 0, 0, 1, 0,   // top row: red, green
             0, 0, 1, 1, 1, 1};  // bottom row: blue, white
  WritePng(tex, (dir / "checker.png").string());
  std::ofstream(dir / "quad.mtl") << "newmtl checker\nKd 1 1 1\nmap_Kd checker.png\n";
  std::ofstream(dir / "quad.obj") << "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl checker\n"
                                     "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
  std::ofstream(dir / "scene.json")
      << R"({"pandora": 1, "objects": [{"name": "quad", "mesh": {"file": "quad.obj", "up_axis": "z"}}],
  "rigs": [{"name": "away", "cameras": [{"id": "a", "position": [5, 5, 5], "look_at": [9, 9, 9],
  "resolution": [64, 48], "hfov_deg": 40}]}],
  "study": {"region": {"box": {"min": [0, 0, 0], "max": [1, 1, 0.5]}}, "voxel_size": 0.1}})";
  const Scene scene = LoadScene((dir / "scene.json").string());
  ASSERT_EQ(scene.objects.size(), 1u);
  ASSERT_EQ(scene.objects[0].mesh.corner_uvs.size(), scene.objects[0].mesh.triangles.size());
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RenderView view;
  view.from = Vec3(0.5, 0.5, 2.0);
  view.at = Vec3(0.5, 0.5, 0.0);
  view.up = Vec3(0, 1, 0);
  view.fov_deg = 40;
  view.width = view.height = 101;
  RenderOptions options;
  options.surface = Surface::kMaterial;
  options.overlays.cameras = false;
  options.overlays.key = false;
  const Image img = Render(scene, scene.rigs[0], *caster, view, options);
  // Quadrant centres (u, v) -> expected texel; the pixel whose centre ray hits nearest each.
  const struct {
    double u, v;
    Vec3 texel;
  } quadrants[] = {{0.25, 0.75, Vec3(1, 0, 0)},
                   {0.75, 0.75, Vec3(0, 1, 0)},
                   {0.25, 0.25, Vec3(0, 0, 1)},
                   {0.75, 0.25, Vec3(1, 1, 1)}};
  for (const auto& q : quadrants) {
    double best = 1e9;
    int bx = -1, by = -1;
    Vec3 bd;
    for (int y = 0; y < view.height; ++y)
      for (int x = 0; x < view.width; ++x) {
        const Vec3 d = EyeRay(view, x, y);
        const auto X = HitFloor(view.from, d);
        if (!X) continue;
        const double e = std::hypot(X->x() - q.u, X->y() - q.v);
        if (e < best) best = e, bx = x, by = y, bd = d;
      }
    ASSERT_LT(best, 0.01);
    // No camera light: colour = ambient * (0.4 + 0.6 |n.d|) * texel; bilinear weights of the
    // neighbouring texels are at most 2 * 2 * best.
    const double k = options.ambient * (0.4 + 0.6 * std::abs(bd.z()));
    const Vec3 rgb = img.Rgb(bx, by);
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(rgb[c], k * q.texel[c], 4 * best * k + 1e-6) << "quadrant " << q.u << "," << q.v;
  }
}

// Textures are read like every other input: a special file or a PNG whose header asks for gigabytes
// is refused with one InputError, before any allocation.
TEST(ReadPng, SpecialFilesAndHugeHeadersAreRefused) {
  auto reason = [](const std::string& path) -> std::string {
    try {
      ReadPng(path);
    } catch (const InputError& e) {
      return e.reason();
    }
    return "accepted";
  };
  EXPECT_NE(reason("/dev/zero").find("character device"), std::string::npos);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("pandora_png_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string fifo = (dir / "fifo.png").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(reason(fifo).find("FIFO"), std::string::npos);
  // A valid 1 x 1 PNG whose IHDR then claims 100000 x 100000 pixels, with the chunk's CRC
  // recomputed so that libpng accepts the header: Pandora's size cap must refuse it.
  Image one;
  one.width = one.height = 1;
  one.rgb = {0.5f, 0.5f, 0.5f};
  const std::string png = (dir / "huge.png").string();
  WritePng(one, png);
  std::string bytes;
  {
    std::ifstream in(png, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  ASSERT_GT(bytes.size(), 24u);
  const unsigned char big[4] = {0x00, 0x01, 0x86, 0xA0};  // 100000, big endian
  for (int k = 0; k < 4; ++k)
    bytes[16 + k] = static_cast<char>(big[k]), bytes[20 + k] = static_cast<char>(big[k]);
  std::uint32_t crc = 0xFFFFFFFFu;  // CRC-32 of "IHDR" and its 13 data bytes (offsets 12..28)
  for (int i = 12; i < 29; ++i) {
    crc ^= static_cast<unsigned char>(bytes[i]);
    for (int b = 0; b < 8; ++b) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xFFFFFFFFu;
  for (int k = 0; k < 4; ++k) bytes[29 + k] = static_cast<char>(crc >> (24 - 8 * k));
  std::ofstream(png, std::ios::binary) << bytes;
  EXPECT_NE(reason(png).find("at most 64 Mpx"), std::string::npos) << reason(png);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pandora
