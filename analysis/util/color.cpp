// The colour module (analysis/util/color.h).
#include "analysis/util/color.h"

namespace pandora {

double SrgbFromLinear(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

double LinearFromSrgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

Vec3 ViridisSrgb(double t) {
  const std::array<double, 3> c = ViridisUnit(t);
  return Vec3(c[0], c[1], c[2]);
}

Vec3 ViridisLinear(double t) {
  const Vec3 s = ViridisSrgb(t);
  return Vec3(LinearFromSrgb(s.x()), LinearFromSrgb(s.y()), LinearFromSrgb(s.z()));
}

Rgb8 Rgb8FromLinear(const Vec3& linear) {
  auto byte = [](double v) {
    return static_cast<std::uint8_t>(std::lround(255.0 * SrgbFromLinear(v)));
  };
  return {byte(linear.x()), byte(linear.y()), byte(linear.z())};
}

std::string HexOfLinear(const Vec3& linear) { return HexColor(Rgb8FromLinear(linear)).data(); }

}  // namespace pandora
