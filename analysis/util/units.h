#pragma once
/// \file units.h
/// Angles: the one place that says what pi is and which way degrees and radians convert. Scene
/// files and everything a person reads are in degrees; the arithmetic is in radians. Each function
/// is the expression the code used before it came here, so results are the same to the bit. And
/// the length units a file or an option may name.

#include <string>

namespace pandora {

inline constexpr double kPi = 3.14159265358979323846;
/// Radians in one degree (pi / 180) and degrees in one radian (180 / pi), for multiplying.
inline constexpr double kRadPerDeg = kPi / 180.0;
inline constexpr double kDegPerRad = 180.0 / kPi;

/// Degrees to radians: deg * pi / 180 (in that order).
constexpr double Rad(double deg) { return deg * kPi / 180.0; }
/// Radians to degrees: rad * 180 / pi (in that order).
constexpr double Deg(double rad) { return rad * 180.0 / kPi; }

/// Metres per length unit named "m", "cm", "mm", "in" or "ft" (a scene file's "units",
/// import-plan's --units); 0 for any other name.
inline double MetresPerUnitNamed(const std::string& name) {
  struct UnitScale {
    const char* name;
    double metres;
  };
  constexpr UnitScale kUnits[] = {
      {"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"in", 0.0254}, {"ft", 0.3048}};
  for (const UnitScale& u : kUnits)
    if (name == u.name) return u.metres;
  return 0;
}

}  // namespace pandora
