// Report images: base64 against RFC 4648's test vectors, PNG bytes that decode to the same 8-bit
// values, slice colours from the colour map (analysis/util/color.h, tested by color_test) and the
// two special colours.
#include "app/report/report_images.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace pandora::report {
namespace {

TEST(Base64, Rfc4648TestVectors) {
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(Base64(std::string("\xff\xfe\x00", 3)), "//4A");
  EXPECT_EQ(DataUri("image/png", "foo"), "data:image/png;base64,Zm9v");
}

TEST(EncodePng, EveryEightBitValueSurvives) {
  // 256 x 3 pixels: row r holds value x in channel r and its complement elsewhere.
  Raster r;
  r.width = 256;
  r.height = 3;
  r.rgb.resize(3 * 256 * 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < 3; ++c) r.rgb[3 * (y * 256 + x) + c] = std::uint8_t(c == y ? x : 255 - x);
  const std::string png = EncodePng(r);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("report_images_test_" + std::to_string(::getpid()) + ".png"))
                               .string();
  std::ofstream(path, std::ios::binary) << png;
  const Image back = ReadPng(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.width, 256);
  ASSERT_EQ(back.height, 3);
  int worst = 0;
  for (std::size_t i = 0; i < r.rgb.size(); ++i) {
    // ReadPng returns linear RGB: encode with the sRGB curve to compare the stored bytes.
    const double s = SrgbFromLinear(back.rgb[i]);
    worst = std::max(worst, std::abs(int(std::lround(255 * s)) - int(r.rgb[i])));
  }
  EXPECT_EQ(worst, 0);
}

TEST(SliceRaster, ColoursAndScale) {
  FieldSlice s;
  s.width = 3;
  s.height = 1;
  s.inside = {1, 1, 0};
  s.has_value = {1, 0, 0};
  s.values = {5.0, 0.0, 0.0};
  const Raster r = SliceRaster(s, 0.0, 10.0, 2);
  ASSERT_EQ(r.width, 6);
  ASSERT_EQ(r.height, 2);
  auto at = [&](int x, int y) {
    const std::size_t i = 3 * (std::size_t(y) * r.width + x);
    return Rgb8{r.rgb[i], r.rgb[i + 1], r.rgb[i + 2]};
  };
  const Rgb8 mid = Viridis(0.5);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) {
      EXPECT_EQ(at(x, y).g, mid.g);
      EXPECT_EQ(at(2 + x, y).r, kNoValueColor.r);
      EXPECT_EQ(at(4 + x, y).r, kOutsideRegionColor.r);
    }
  // Above the scale: the top colour.
  s.values[0] = 50.0;
  EXPECT_EQ(SliceRaster(s, 0.0, 10.0, 1).rgb[1], Viridis(1.0).g);
}

}  // namespace
}  // namespace pandora::report
