// The light rule (render/light.h) against closed-form values. These inputs double as the test
// vectors for a GPU port of the rule (docs/rendering.md, "The light rule"): a shader evaluated at
// them must give the same light within float round-off.
#include "render/light.h"

#include <gtest/gtest.h>

#include <vector>

namespace pandora {
namespace {

using V3 = Eigen::Vector3d;

CameraAtPoint Seeing(const V3& color) {
  CameraAtPoint c;
  c.sees = true;
  c.color = color;
  return c;
}

CameraAtPoint OnGrid(const V3& color, double u, double v, double du, double dv) {
  CameraAtPoint c = Seeing(color);
  c.projects = true;
  c.u = u;
  c.v = v;
  c.du = du;
  c.dv = dv;
  return c;
}

TEST(Light, UniformOverlapsAddScaledByBrightnessAndShadowedCamerasAddNothing) {
  LightRule rule;
  rule.brightness = 0.5;
  std::vector<CameraAtPoint> cams = {Seeing(V3(1, 0, 0)), Seeing(V3(0, 1, 0)), Seeing(V3(0, 0, 1))};
  cams[2].sees = false;  // in shadow (or outside its image, out of range, facing away)
  EXPECT_EQ(SurfaceLight(rule, cams.data(), cams.size()), V3(0.5, 0.5, 0));
  EXPECT_EQ(CameraLight(rule, cams[2]), V3::Zero());
  EXPECT_EQ(CameraLightWeight(rule, cams[2]), 0.0);
  // No camera: no light.
  EXPECT_EQ(SurfaceLight(rule, cams.data(), 0), V3::Zero());
  // Two cameras of the same colour give twice one light.
  cams = {Seeing(V3(0.2, 0.4, 0.8)), Seeing(V3(0.2, 0.4, 0.8))};
  EXPECT_EQ(SurfaceLight(rule, cams.data(), cams.size()), V3(0.2, 0.4, 0.8));
}

TEST(Light, DefaultBrightnessIsMinOfOneAndThreeOverN) {
  EXPECT_EQ(DefaultBrightness(0), 1.0);
  EXPECT_EQ(DefaultBrightness(3), 1.0);
  EXPECT_EQ(DefaultBrightness(4), 0.75);
  EXPECT_EQ(DefaultBrightness(24), 0.125);
  EXPECT_EQ(DefaultBrightness(1000), 0.003);
  // n identical lights at the default brightness sum to three lights for any n > 3.
  for (int n : {4, 10, 64, 65, 1000}) {
    LightRule rule;
    rule.brightness = DefaultBrightness(n);
    std::vector<CameraAtPoint> cams(n, Seeing(V3(1, 1, 1)));
    EXPECT_NEAR(SurfaceLight(rule, cams.data(), cams.size()).x(), 3.0, 1e-12) << n;
  }
}

TEST(Light, SumRunsInCameraOrderOverAnyNumberOfCameras) {
  // 1000 cameras, camera c of colour (c, 1000 - c, 1) / 1000, every third one in shadow: the sum
  // is the closed form over the others, and equals adding CameraLight in order bit for bit (what
  // the renderer does).
  LightRule rule;
  rule.brightness = 0.25;
  std::vector<CameraAtPoint> cams;
  V3 expected = V3::Zero(), in_order = V3::Zero();
  for (int c = 0; c < 1000; ++c) {
    cams.push_back(Seeing(V3(c, 1000 - c, 1) / 1000.0));
    cams.back().sees = c % 3 != 0;
    if (cams.back().sees) expected += 0.25 * V3(c, 1000 - c, 1) / 1000.0;
    in_order += CameraLight(rule, cams.back());
  }
  const V3 light = SurfaceLight(rule, cams.data(), cams.size());
  EXPECT_EQ(light, in_order);
  // Cameras 1..999 not divisible by 3: 666 of them; the sum of c over them is
  // 999 * 1000 / 2 - 3 * 333 * 334 / 2 = 332,667.
  EXPECT_NEAR(light.x(), 0.25 * 332667 / 1000.0, 1e-9);
  EXPECT_NEAR(light.y(), 0.25 * (666 * 1000 - 332667) / 1000.0, 1e-9);
  EXPECT_NEAR(light.z(), 0.25 * 666 / 1000.0, 1e-9);
  EXPECT_NEAR((light - expected).norm(), 0.0, 1e-12);
}

TEST(Light, GridLinesLieOnTheCamerasPixelBordersWithBoxFilteredWidth) {
  LightRule rule;
  rule.pattern = Pattern::kGrid;
  rule.grid_pixels = 8;
  rule.grid_fill = 0.15;
  rule.line_width_px = 1.2;
  const V3 white(1, 1, 1);
  // One camera pixel per output pixel (du = dv = 1): lines 8 output pixels apart, no fading.
  // On a line (u = 8k - 1/2): coverage min(1, 0.6 + 0.5 - 0) = 1, weight 1.
  EXPECT_DOUBLE_EQ(CameraLightWeight(rule, OnGrid(white, 15.5, 3.0, 1, 1)), 1.0);
  EXPECT_DOUBLE_EQ(CameraLightWeight(rule, OnGrid(white, -0.5, 3.0, 1, 1)), 1.0);
  // Half a pixel from a line: 0.6 + 0.5 - 0.5 = 0.6; weight 0.15 + 0.85 * 0.6 = 0.66.
  EXPECT_NEAR(CameraLightWeight(rule, OnGrid(white, 16.0, 3.0, 1, 1)), 0.66, 1e-15);
  // Half a pixel from a u line and from a v line: 1 - 0.4 * 0.4 = 0.84; weight 0.15 + 0.85 * 0.84.
  EXPECT_NEAR(CameraLightWeight(rule, OnGrid(white, 16.0, 7.0, 1, 1)), 0.15 + 0.85 * 0.84, 1e-15);
  // Far from every line: the fill.
  EXPECT_NEAR(CameraLightWeight(rule, OnGrid(white, 11.5, 3.5, 1, 1)), 0.15, 1e-15);
  // Two camera pixels per output pixel: 1 camera pixel from the line is 0.5 output pixels: 0.6.
  EXPECT_NEAR(GridLineCoverage(16.5, 2.0, 8, 1.2), 0.6, 1e-15);
  // Half a camera pixel per output pixel: 0.25 camera pixels from the line is 0.5 output pixels.
  EXPECT_NEAR(GridLineCoverage(15.75, 0.5, 8, 1.2), 0.6, 1e-15);
  // The term: (brightness * w) * colour.
  rule.brightness = 0.5;
  EXPECT_EQ(
      CameraLight(rule, OnGrid(V3(1, 0.5, 0), 11.5, 3.5, 1, 1)),
      (0.5 * CameraLightWeight(rule, OnGrid(V3(1, 0.5, 0), 11.5, 3.5, 1, 1))) * V3(1, 0.5, 0));
}

TEST(Light, DenseGridLinesFadeToTheirMeanCoverage) {
  // Spacing s = n / g output pixels; below 3 pixels the line fades into min(1, width / s):
  // fade f = clamp((3 - s) / 1.5, 0, 1).
  // s = 1.5 (n = 8, g = 16/3): fully faded, coverage 1.2 / 1.5 = 0.8 wherever u is.
  for (double u : {7.5, 9.0, 11.5})
    EXPECT_NEAR(GridLineCoverage(u, 16.0 / 3.0, 8, 1.2), 0.8, 1e-12) << u;
  // s = 2.25 (g = 32/9): f = 0.5; on a line 0.5 * 1 + 0.5 * 1.2 / 2.25.
  EXPECT_NEAR(GridLineCoverage(7.5, 32.0 / 9.0, 8, 1.2), 0.5 + 0.5 * 1.2 / 2.25, 1e-12);
  // Midway between lines (4 camera pixels = 1.125 output pixels away): the line part is 0.
  EXPECT_NEAR(GridLineCoverage(11.5, 32.0 / 9.0, 8, 1.2), 0.5 * 1.2 / 2.25, 1e-12);
  // s = 3 exactly: no fading yet.
  EXPECT_NEAR(GridLineCoverage(7.5, 8.0 / 3.0, 8, 1.2), 1.0, 1e-12);
}

TEST(Light, DegenerateGradientsAndUnprojectablePointsGetTheFillOnly) {
  LightRule rule;
  rule.pattern = Pattern::kGrid;
  rule.grid_pixels = 8;
  for (double g : {0.0, -1.0, std::numeric_limits<double>::infinity(), std::nan("")})
    EXPECT_EQ(GridLineCoverage(7.5, g, 8, 1.2), 0.0) << g;
  CameraAtPoint c = OnGrid(V3(1, 1, 1), 7.5, 7.5, 1, 1);
  c.projects = false;
  EXPECT_EQ(CameraLightWeight(rule, c), rule.grid_fill);
  // grid_pixels below 1 counts as 1: every pixel border is a line; u = 0.5 is on one.
  rule.grid_pixels = 0;
  EXPECT_EQ(CameraLightWeight(rule, OnGrid(V3(1, 1, 1), 0.5, 0.0, 0.25, 0.25)),
            rule.grid_fill + (1 - rule.grid_fill) * GridLineCoverage(0.5, 0.25, 1, 1.2));
}

TEST(Light, MaterialColourIsAlbedoTimesLightPlusShadedAmbient) {
  const V3 albedo(0.8, 0.5, 0.2), light(0.5, 1.0, 2.0);
  // Facing the eye (cos 1): shade 1; grazing (cos 0): shade 0.4; the sign of cos does not matter.
  EXPECT_TRUE(MaterialColor(albedo, light, 0.15, 1.0)
                  .isApprox(V3(0.4 + 0.12, 0.5 + 0.075, 0.4 + 0.03), 1e-15));
  EXPECT_TRUE(MaterialColor(albedo, light, 0.15, -1.0)
                  .isApprox(MaterialColor(albedo, light, 0.15, 1.0), 1e-15));
  EXPECT_TRUE(MaterialColor(albedo, V3::Zero(), 0.15, 0.0).isApprox(0.15 * 0.4 * albedo, 1e-15));
  EXPECT_TRUE(MaterialColor(albedo, light, 0.0, 0.3).isApprox(V3(0.4, 0.5, 0.4), 1e-15));
}

}  // namespace
}  // namespace pandora
