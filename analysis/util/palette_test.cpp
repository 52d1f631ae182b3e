// Camera colours that stay apart (analysis/util/palette.h), and the scene loader giving them out.
#include "analysis/util/palette.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "analysis/scene/scene.h"

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

TEST(Palette, TheLoaderKeepsTheFilesColoursAndGivesTheRestDistinctOnes) {
  std::string text = "{\"rigs\": [{\"name\": \"twelve\", \"cameras\": [";
  for (int i = 0; i < 12; ++i) text += (i ? ", " : "") + CameraJson(i, i == 3 || i == 9);
  text += "]}], \"study\": {\"region\": {\"box\": {\"min\": [-1, -1, 0], \"max\": [1, 1, 1]}}}}";
  const Scene scene = ParseScene(text, "palette.json");
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
}

}  // namespace
}  // namespace pandora
