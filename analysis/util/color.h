#pragma once
/// \file color.h
/// The one colour module: the sRGB transfer curve both ways, 8-bit colours and their "#rrggbb"
/// form, and the viridis colour map (perceptually uniform, readable in greyscale and by
/// colour-blind readers) that field images, surface-sample colours, legends and the renderer's
/// slices share. Viridis here is piecewise linear in sRGB through nine evenly spaced stops of
/// matplotlib's viridis table (#440154 ... #fde725); against the table's samples at k/9 (R's
/// viridis(10)) it is within 5 8-bit steps per channel (color_test), invisible in a figure.
///
/// The cameras' light colours (a palette picked under CIEDE2000) are analysis/util/palette.h.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

namespace pandora {

/// Linear or sRGB colours are Eigen 3-vectors: the same type as analysis/geometry/geometry.h's
/// Vec3 (declaring the alias again is allowed), so util needs no geometry header.
using Vec3 = Eigen::Vector3d;

/// An 8-bit sRGB colour.
struct Rgb8 {
  std::uint8_t r = 0, g = 0, b = 0;
};

/// The sRGB transfer curve, per channel: a linear value in [0, 1] (clamped) to its sRGB encoding.
double SrgbFromLinear(double v);

/// Its inverse, per channel: an sRGB value in [0, 1] (clamped) to linear.
double LinearFromSrgb(double v);

/// Viridis at t in [0, 1] (clamped; NaN gives the t = 0 colour) as sRGB components in [0, 1],
/// unrounded.
inline std::array<double, 3> ViridisUnit(double t) {
  static constexpr std::array<std::array<int, 3>, 9> kStops{{{0x44, 0x01, 0x54},
                                                             {0x47, 0x2d, 0x7b},
                                                             {0x3b, 0x52, 0x8b},
                                                             {0x2c, 0x72, 0x8e},
                                                             {0x21, 0x91, 0x8c},
                                                             {0x28, 0xae, 0x80},
                                                             {0x5e, 0xc9, 0x62},
                                                             {0xad, 0xdc, 0x30},
                                                             {0xfd, 0xe7, 0x25}}};
  if (!(t > 0)) t = 0;  // also NaN
  if (t > 1) t = 1;
  const double x = t * (kStops.size() - 1);
  const int i = std::min(static_cast<int>(x), static_cast<int>(kStops.size()) - 2);
  const double f = x - i;
  std::array<double, 3> c;
  for (int k = 0; k < 3; ++k) c[k] = (kStops[i][k] + f * (kStops[i + 1][k] - kStops[i][k])) / 255.0;
  return c;
}

/// Viridis at t as an 8-bit sRGB colour (each component rounded to nearest).
inline Rgb8 Viridis(double t) {
  const std::array<double, 3> c = ViridisUnit(t);
  auto byte = [](double v) { return static_cast<std::uint8_t>(std::lround(255.0 * v)); };
  return {byte(c[0]), byte(c[1]), byte(c[2])};
}

/// Viridis at t as sRGB components in [0, 1] (ViridisUnit as a vector).
Vec3 ViridisSrgb(double t);

/// Viridis at t in linear RGB (what the renderer composites in).
Vec3 ViridisLinear(double t);

/// "#rrggbb" of a colour.
inline std::array<char, 8> HexColor(Rgb8 c) {
  static constexpr char kHex[] = "0123456789abcdef";
  return {'#',
          kHex[c.r >> 4],
          kHex[c.r & 15],
          kHex[c.g >> 4],
          kHex[c.g & 15],
          kHex[c.b >> 4],
          kHex[c.b & 15],
          '\0'};
}

/// The 8-bit sRGB colour of a linear-RGB colour (each channel clamped to [0, 1], encoded with the
/// sRGB curve and rounded to nearest): what an 8-bit PNG of it shows.
Rgb8 Rgb8FromLinear(const Vec3& linear);

/// "#rrggbb" of a linear-RGB colour (Rgb8FromLinear), e.g. a camera's light in an HTML swatch.
std::string HexOfLinear(const Vec3& linear);

}  // namespace pandora
