// The cameras' colour palette and the CIELAB / CIEDE2000 arithmetic behind it
// (analysis/util/palette.h).
#include "analysis/util/palette.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "analysis/util/units.h"

namespace pandora {
namespace {

// Greedy farthest-point selection under CIEDE2000 from the sRGB colours on a 1/20 grid with
// L* >= 45, chroma >= 45 and a channel >= 0.8, seeded with red: every prefix is spread out too
// (min CIEDE2000 26.1 over the first 8, 20.8 over 12, 14.0 over all 24).
const char* const kPalette[kCameraPaletteSize] = {
    "#e61a1a", "#00ff00", "#0dbfff", "#991aff", "#ffb200", "#ffb2ff", "#00ccb2", "#f2268c",
    "#1a73d9", "#ff9980", "#ffff00", "#99a6ff", "#cc731a", "#b2cc73", "#b273cc", "#99ffbf",
    "#ff8ca6", "#26f2ff", "#00cc66", "#d96666", "#f2d980", "#7366cc", "#d9004c", "#ff00ff"};

int Index(int index) {
  const int i = index % kCameraPaletteSize;
  return i < 0 ? i + kCameraPaletteSize : i;
}

}  // namespace

const char* CameraPaletteHex(int index) { return kPalette[Index(index)]; }

Vec3 CameraPaletteColor(int index) {
  const char* hex = CameraPaletteHex(index);
  Vec3 c;
  for (int k = 0; k < 3; ++k)
    c[k] = LinearFromSrgb(std::stoi(std::string(hex + 1 + 2 * k, 2), nullptr, 16) / 255.0);
  return c;
}

Vec3 LabFromLinearRgb(const Vec3& rgb) {
  const double X = 0.4124564 * rgb.x() + 0.3575761 * rgb.y() + 0.1804375 * rgb.z();
  const double Y = 0.2126729 * rgb.x() + 0.7151522 * rgb.y() + 0.0721750 * rgb.z();
  const double Z = 0.0193339 * rgb.x() + 0.1191920 * rgb.y() + 0.9503041 * rgb.z();
  auto f = [](double t) {
    constexpr double d = 6.0 / 29.0;
    return t > d * d * d ? std::cbrt(t) : t / (3 * d * d) + 4.0 / 29.0;
  };
  const double fx = f(X / 0.95047), fy = f(Y / 1.0), fz = f(Z / 1.08883);
  return Vec3(116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz));
}

double DeltaE2000(const Vec3& lab1, const Vec3& lab2) {
  const double L1 = lab1.x(), a1 = lab1.y(), b1 = lab1.z();
  const double L2 = lab2.x(), a2 = lab2.y(), b2 = lab2.z();
  const double C1 = std::hypot(a1, b1), C2 = std::hypot(a2, b2);
  const double Cb7 = std::pow(0.5 * (C1 + C2), 7);
  const double G = 0.5 * (1 - std::sqrt(Cb7 / (Cb7 + std::pow(25.0, 7))));
  const double a1p = (1 + G) * a1, a2p = (1 + G) * a2;
  const double C1p = std::hypot(a1p, b1), C2p = std::hypot(a2p, b2);
  auto hue = [](double b, double a) {
    if (a == 0 && b == 0) return 0.0;
    const double h = Deg(std::atan2(b, a));
    return h < 0 ? h + 360 : h;
  };
  const double h1p = hue(b1, a1p), h2p = hue(b2, a2p);
  const double dLp = L2 - L1, dCp = C2p - C1p;
  double dhp = 0;
  if (C1p * C2p != 0) {
    dhp = h2p - h1p;
    if (dhp > 180) dhp -= 360;
    if (dhp < -180) dhp += 360;
  }
  const double dHp = 2 * std::sqrt(C1p * C2p) * std::sin(Rad(dhp / 2));
  const double Lbp = 0.5 * (L1 + L2), Cbp = 0.5 * (C1p + C2p);
  double hbp = h1p + h2p;
  if (C1p * C2p != 0) {
    if (std::abs(h1p - h2p) <= 180)
      hbp = 0.5 * (h1p + h2p);
    else
      hbp = h1p + h2p < 360 ? 0.5 * (h1p + h2p + 360) : 0.5 * (h1p + h2p - 360);
  }
  const double T = 1 - 0.17 * std::cos(Rad(hbp - 30)) + 0.24 * std::cos(Rad(2 * hbp)) +
                   0.32 * std::cos(Rad(3 * hbp + 6)) - 0.20 * std::cos(Rad(4 * hbp - 63));
  const double dtheta = 30 * std::exp(-std::pow((hbp - 275) / 25, 2));
  const double Cbp7 = std::pow(Cbp, 7);
  const double RC = 2 * std::sqrt(Cbp7 / (Cbp7 + std::pow(25.0, 7)));
  const double SL = 1 + 0.015 * (Lbp - 50) * (Lbp - 50) / std::sqrt(20 + (Lbp - 50) * (Lbp - 50));
  const double SC = 1 + 0.045 * Cbp, SH = 1 + 0.015 * Cbp * T;
  const double RT = -std::sin(Rad(2 * dtheta)) * RC;
  const double l = dLp / SL, c = dCp / SC, h = dHp / SH;
  return std::sqrt(l * l + c * c + h * h + RT * c * h);
}

}  // namespace pandora
