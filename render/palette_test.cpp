// Camera colours that stay apart (render/palette.h), the colour key in renders, the default
// brightness and the legends' units.
#include "render/palette.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>

#include "analysis/primitives.h"
#include "analysis/ray_caster.h"
#include "analysis/scene.h"
#include "render/colormap.h"
#include "render/render.h"

namespace pandora {
namespace {

// Sharma, Wu and Dalal (2005), Table 1: pairs 1, 7, 17 and 25 with their CIEDE2000 differences.
TEST(Palette, Ciede2000MatchesThePublishedTestData) {
  EXPECT_NEAR(DeltaE2000(Vec3(50, 2.6772, -79.7751), Vec3(50, 0, -82.7485)), 2.0425, 1e-4);
  EXPECT_NEAR(DeltaE2000(Vec3(50, 0, 0), Vec3(50, -1, 2)), 2.3669, 1e-4);
  EXPECT_NEAR(DeltaE2000(Vec3(50, 2.5, 0), Vec3(73, 25, -18)), 27.1492, 1e-4);
  EXPECT_NEAR(DeltaE2000(Vec3(60.2574, -34.0099, 36.2677), Vec3(60.4626, -34.1751, 39.4387)),
              1.2644, 1e-4);
  // D65 white is L* = 100 with no chroma; sRGB red is (53.24, 80.09, 67.20) (Lindbloom).
  const Vec3 white = LabFromLinearRgb(Vec3::Ones());
  EXPECT_NEAR(white.x(), 100.0, 1e-3);
  EXPECT_NEAR(std::hypot(white.y(), white.z()), 0.0, 1e-2);
  const Vec3 red = LabFromLinearRgb(Vec3(1, 0, 0));
  EXPECT_NEAR(red.x(), 53.24, 0.01);
  EXPECT_NEAR(red.y(), 80.09, 0.02);
  EXPECT_NEAR(red.z(), 67.20, 0.02);
}

// The smallest CIEDE2000 difference between any two of the first n palette colours.
double MinDistance(int n, bool de2000) {
  double best = 1e9;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const Vec3 a = LabFromLinearRgb(CameraPaletteColor(i)),
                 b = LabFromLinearRgb(CameraPaletteColor(j));
      best = std::min(best, de2000 ? DeltaE2000(a, b) : (a - b).norm());
    }
  return best;
}

TEST(Palette, TwentyFourColoursStayApart) {
  // A CIEDE2000 difference of about 2 is just noticeable; these are at least 7 times that apart,
  // and every prefix (a rig of fewer cameras) is spread out further.
  EXPECT_GE(MinDistance(24, true), 14.0);
  EXPECT_GE(MinDistance(12, true), 20.8);
  EXPECT_GE(MinDistance(8, true), 26.1);
  EXPECT_GE(MinDistance(24, false), 19.0);  // CIE76 (Euclidean in CIELAB)
  // The old default cycled 8 colours: cameras 0 and 8 were the same. Now they differ; the palette
  // cycles at 24.
  EXPECT_GT(
      DeltaE2000(LabFromLinearRgb(CameraPaletteColor(0)), LabFromLinearRgb(CameraPaletteColor(8))),
      14.0);
  EXPECT_EQ(CameraPaletteColor(24), CameraPaletteColor(0));
  for (int i = 0; i < kCameraPaletteSize; ++i) {
    const Vec3 lab = LabFromLinearRgb(CameraPaletteColor(i));
    EXPECT_GE(lab.x(), 45.0) << CameraPaletteHex(i);  // bright enough to show as light
    EXPECT_GE(std::hypot(lab.y(), lab.z()), 45.0) << CameraPaletteHex(i);  // a colour, not a grey
  }
  EXPECT_STREQ(CameraPaletteHex(0), "#e61a1a");
  EXPECT_NEAR(CameraPaletteColor(0).x(), LinearFromSrgb(0xe6 / 255.0), 1e-12);
}

std::string CameraJson(int i, bool color) {
  return "{\"id\": \"c" + std::to_string(i) + "\", \"position\": [" + std::to_string(i) +
         ", -3, 2], \"look_at\": [0, 0, 0], \"resolution\": [64, 48], \"hfov_deg\": 50" +
         (color ? ", \"color\": [0.1, 0.2, 0.3]" : "") + "}";
}

TEST(Palette, ApplyKeepsTheFilesColoursAndGivesTheRestDistinctOnes) {
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "pandora_palette.json";
  std::string text = "{\"rigs\": [{\"name\": \"twelve\", \"cameras\": [";
  for (int i = 0; i < 12; ++i) text += (i ? ", " : "") + CameraJson(i, i == 3 || i == 9);
  text += "]}], \"study\": {\"region\": {\"box\": {\"min\": [-1, -1, 0], \"max\": [1, 1, 1]}}}}";
  std::ofstream(path) << text;
  Scene scene = LoadScene(path.string());
  EXPECT_EQ(scene.rigs[0].cameras[0].color, scene.rigs[0].cameras[8].color);  // the loader's 8
  ApplyCameraPalette(&scene);
  std::set<std::string> seen;
  for (int i = 0; i < 12; ++i) {
    const Vec3& c = scene.rigs[0].cameras[i].color;
    if (i == 3 || i == 9) {
      EXPECT_EQ(c, Vec3(0.1, 0.2, 0.3)) << i;
    } else {
      EXPECT_EQ(c, CameraPaletteColor(i)) << i;
      EXPECT_TRUE(seen.insert(CameraPaletteHex(i)).second);
    }
  }
  // A text that is not a scene leaves nothing to tell; a mismatch leaves the colours alone.
  EXPECT_TRUE(CamerasWithColor("not json").empty());
  std::ofstream(path) << "{\"rigs\": []}";
  Scene other = scene;
  ApplyCameraPalette(&other);
  EXPECT_EQ(other.rigs[0].cameras[0].color, scene.rigs[0].cameras[0].color);
  std::filesystem::remove(path);
}

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
