// The colour module (analysis/util/color.h): viridis against the published table, the sRGB curve
// against its definition (IEC 61966-2-1) both ways, 8-bit and "#rrggbb" forms.
#include "analysis/util/color.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace pandora {
namespace {

TEST(Viridis, EndsAndMiddleOfThePublishedTable) {
  EXPECT_EQ(std::string(HexColor(Viridis(0.0)).data()), "#440154");
  EXPECT_EQ(std::string(HexColor(Viridis(0.5)).data()), "#21918c");
  EXPECT_EQ(std::string(HexColor(Viridis(1.0)).data()), "#fde725");
  EXPECT_EQ(std::string(HexColor(Viridis(std::nan(""))).data()), "#440154");
  EXPECT_EQ(std::string(HexColor(Viridis(-3.0)).data()), "#440154");
  EXPECT_EQ(std::string(HexColor(Viridis(7.0)).data()), "#fde725");
  // Within 5 steps of the table sampled at k/9 (R's viridis(10), a different set of points than the
  // nine stops).
  const int reference[10][3] = {{0x44, 0x01, 0x54}, {0x48, 0x28, 0x78}, {0x3E, 0x4A, 0x89},
                                {0x31, 0x68, 0x8E}, {0x26, 0x82, 0x8E}, {0x1F, 0x9E, 0x89},
                                {0x35, 0xB7, 0x79}, {0x6D, 0xCD, 0x59}, {0xB4, 0xDE, 0x2C},
                                {0xFD, 0xE7, 0x25}};
  for (int k = 0; k < 10; ++k) {
    const Rgb8 c = Viridis(k / 9.0);
    EXPECT_LE(std::abs(c.r - reference[k][0]), 5) << k;
    EXPECT_LE(std::abs(c.g - reference[k][1]), 5) << k;
    EXPECT_LE(std::abs(c.b - reference[k][2]), 5) << k;
  }
  // Monotonic in lightness (sum of channels) along the map, as viridis is.
  int previous = -1;
  for (int k = 0; k <= 64; ++k) {
    const Rgb8 c = Viridis(k / 64.0);
    const int sum = 2 * c.r + 7 * c.g + c.b;  // rough luma
    EXPECT_GE(sum, previous);
    previous = sum;
  }
}

TEST(Viridis, LinearIsTheDecodedSrgbForm) {
  for (int k = 0; k <= 20; ++k) {
    const double t = k / 20.0;
    const std::array<double, 3> s = ViridisUnit(t);
    const Vec3 linear = ViridisLinear(t);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(ViridisSrgb(t)[c], s[c]);
      EXPECT_NEAR(SrgbFromLinear(linear[c]), s[c], 1e-12);
    }
  }
}

TEST(Srgb, CurveMatchesItsDefinitionAndInverts) {
  // The two pieces and their ends: 0 -> 0, 1 -> 1, the linear toe below 0.0031308.
  EXPECT_EQ(SrgbFromLinear(0.0), 0.0);
  EXPECT_NEAR(SrgbFromLinear(1.0), 1.0, 1e-15);
  EXPECT_DOUBLE_EQ(SrgbFromLinear(0.002), 12.92 * 0.002);
  EXPECT_DOUBLE_EQ(SrgbFromLinear(0.5), 1.055 * std::pow(0.5, 1 / 2.4) - 0.055);
  EXPECT_DOUBLE_EQ(LinearFromSrgb(0.02), 0.02 / 12.92);
  EXPECT_DOUBLE_EQ(LinearFromSrgb(0.5), std::pow((0.5 + 0.055) / 1.055, 2.4));
  // Clamped outside [0, 1].
  EXPECT_EQ(SrgbFromLinear(-1.0), 0.0);
  EXPECT_NEAR(SrgbFromLinear(4.0), 1.0, 1e-15);
  EXPECT_EQ(LinearFromSrgb(-1.0), 0.0);
  // Round trip over every 8-bit code.
  for (int i = 0; i < 256; ++i)
    EXPECT_NEAR(SrgbFromLinear(LinearFromSrgb(i / 255.0)), i / 255.0, 1e-12) << i;
}

TEST(Rgb8, FromLinearAndHex) {
  EXPECT_EQ(HexOfLinear(Vec3(1, 1, 1)), "#ffffff");
  EXPECT_EQ(HexOfLinear(Vec3(0, 0, 0)), "#000000");
  EXPECT_EQ(HexOfLinear(Vec3(2, -1, 0.5)),
            "#ff00bc");  // clamped; sRGB(0.5) = 0.7354 -> 187.5 -> 188
  for (int i = 0; i < 256; ++i) {
    const Rgb8 c = Rgb8FromLinear(Vec3::Constant(LinearFromSrgb(i / 255.0)));
    EXPECT_EQ(c.r, i);
    EXPECT_EQ(c.b, i);
  }
  EXPECT_EQ(std::string(HexColor(Rgb8{0x0a, 0xbc, 0xff}).data()), "#0abcff");
}

}  // namespace
}  // namespace pandora
