// The colour key in renders, the default brightness and the legends' units (docs/rendering.md).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/palette.h"
#include "render/colormap.h"
#include "render/render.h"

namespace pandora {
namespace {

// n identical cameras above a floor, looking straight down, each of colour `color`.
struct Stack {
  Scene scene;
  std::unique_ptr<RayCaster> caster;
  Stack(int n, const Vec3& color) {
    SceneObject floor;
    floor.name = "floor";
    floor.mesh = MakePlane(Vec2(20, 20));
    scene.objects.push_back(floor);
    Rig rig;
    rig.name = "stack";
    for (int i = 0; i < n; ++i) {
      Camera c;
      c.id = c.name = "cam" + std::to_string(i);
      c.color = color;
      c.world_from_camera = *LookAt(Vec3(0, 0, 3), Vec3(0, 0, 0), Vec3(0, 1, 0));
      Intrinsics k;
      k.width = 64;
      k.height = 48;
      k.fx = k.fy = 64;
      k.cx = 31.5;
      k.cy = 23.5;
      c.model = CameraModel(k);
      rig.cameras.push_back(c);
    }
    scene.rigs.push_back(rig);
    scene.study.region.box.min = Vec3(-1, -1, 0);
    scene.study.region.box.max = Vec3(1, 1, 1);
    caster = MakeEmbreeRayCaster(scene.AllTriangles());
  }
};

RenderOptions Black() {
  RenderOptions o;
  o.surface = Surface::kBlack;
  o.background = Vec3::Zero();
  o.overlays.cameras = false;
  o.overlays.key = false;
  return o;
}

TEST(Brightness, DefaultScalesWithTheEnabledCameras) {
  EXPECT_EQ(DefaultBrightness(1), 1.0);
  EXPECT_EQ(DefaultBrightness(3), 1.0);
  EXPECT_DOUBLE_EQ(DefaultBrightness(12), 0.25);
  EXPECT_DOUBLE_EQ(DefaultBrightness(24), 0.125);
  // Six cameras light the image centre: by default 6 * (3 / 6) = 3 times one light; an explicit
  // brightness wins; disabled cameras do not count.
  const Vec3 color(0.1, 0.05, 0.02);
  Stack s(6, color);
  RenderView view;
  view.from = Vec3(0, 0.01, 5);
  view.at = Vec3(0, 0, 0);
  view.up = Vec3(0, 1, 0);
  view.width = 32;
  view.height = 24;
  view.fov_deg = 10;
  const Rig& rig = s.scene.rigs[0];
  auto centre = [&](const Rig& r, const RenderOptions& o) {
    return Render(s.scene, r, *s.caster, view, o).Rgb(16, 12);
  };
  EXPECT_TRUE(centre(rig, Black()).isApprox(3.0 * color, 1e-6));
  RenderOptions explicit_one = Black();
  explicit_one.brightness = 1.0;
  EXPECT_TRUE(centre(rig, explicit_one).isApprox(6.0 * color, 1e-6));
  Rig four = rig;
  four.cameras[4].enabled = four.cameras[5].enabled = false;
  EXPECT_TRUE(centre(four, Black()).isApprox(3.0 * color, 1e-6));  // 4 * 3 / 4
}

TEST(Key, ShowsEachEnabledCamerasColourInRowsAndColumns) {
  Stack s(30, Vec3(0.2, 0.2, 0.2));
  Rig& rig = s.scene.rigs[0];
  for (int i = 0; i < 30; ++i) rig.cameras[i].color = CameraPaletteColor(i);
  rig.cameras[1].enabled = false;  // not in the key: the key's second entry is cam2
  RenderView view;
  view.from = Vec3(0, 0.01, 5);
  view.at = Vec3(0, 0, 0);
  view.up = Vec3(0, 1, 0);
  view.fov_deg = 20;  // every pixel inside the cameras' footprint: lit
  view.width = 400;
  view.height = 100;  // below 400: scale 1; margin 4, rows 8 px, swatches 8 x 5 px
  RenderOptions o = Black();
  const Image off = Render(s.scene, rig, *s.caster, view, o);
  o.overlays.key = true;
  const Image on = Render(s.scene, rig, *s.caster, view, o);
  // (100 - 12) / 8 = 11 rows fit; 29 enabled cameras take 3 columns of 10 rows.
  const int col_w = 8 + 3 + TextWidth("cam29", 1) + 8;
  auto swatch = [&](int entry) {
    const int col = entry / 10, row = entry % 10;
    return on.Rgb(8 + col * col_w + 2, 8 + row * 8 + 2);
  };
  EXPECT_TRUE(swatch(0).isApprox(CameraPaletteColor(0).cast<float>().cast<double>(), 1e-6));
  EXPECT_TRUE(swatch(1).isApprox(CameraPaletteColor(2).cast<float>().cast<double>(), 1e-6));
  EXPECT_TRUE(swatch(10).isApprox(CameraPaletteColor(11).cast<float>().cast<double>(), 1e-6));
  EXPECT_TRUE(swatch(28).isApprox(CameraPaletteColor(29).cast<float>().cast<double>(), 1e-6));
  // Behind the key the image is darkened to a fifth; far from it nothing changed.
  const Vec3 behind = off.Rgb(5, 5);
  ASSERT_GT(behind.norm(), 0.1);
  EXPECT_TRUE(on.Rgb(5, 5).isApprox(0.2 * behind, 1e-5)) << on.Rgb(5, 5).transpose();
  EXPECT_EQ(on.Rgb(390, 90), off.Rgb(390, 90));
  // A key wider than half the image is left out.
  view.width = 100;
  const Image narrow = Render(s.scene, rig, *s.caster, view, o);
  o.overlays.key = false;
  EXPECT_EQ(narrow.rgb, Render(s.scene, rig, *s.caster, view, o).rgb);
}

TEST(Legend, FieldsCarryTheirUnits) {
  EXPECT_EQ(FieldUnitLabel("coverage"), "coverage [cameras]");
  EXPECT_EQ(FieldUnitLabel("resolution"), "resolution [px/m]");
  EXPECT_EQ(FieldUnitLabel("sigma_max"), "sigma_max [mm]");
  EXPECT_EQ(FieldUnitLabel("sigma_mean_steady"), "sigma_mean_steady [mm]");
  EXPECT_EQ(FieldUnitLabel("triangulation_angle"), "triangulation_angle [deg]");
  EXPECT_EQ(FieldUnitLabel("condition"), "condition [1]");
  // The legend font draws brackets (not the "unknown character" box).
  std::vector<float> a(3 * 8 * 8, 0.f), b(3 * 8 * 8, 0.f);
  DrawText(a.data(), 8, 8, 0, 0, "[", Vec3::Ones(), 1);
  DrawText(b.data(), 8, 8, 0, 0, "\x01", Vec3::Ones(), 1);
  EXPECT_NE(a, b);
}

}  // namespace
}  // namespace pandora
