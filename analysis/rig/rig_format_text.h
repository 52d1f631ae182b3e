#pragma once
/// \file rig_format_text.h
/// Private to the rig formats (rig_format_*.cpp): number text both ways, the limits of imported
/// values, and the checks every imported camera passes (MakeCamera).

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/scene/scene.h"
#include "analysis/util/text.h"

namespace pandora::rig_format {

using json = nlohmann::json;

// Imported values beyond these are damage, not calibration (scene-format limits where they exist).
constexpr double kMaxFocalPx = 1e7;
constexpr double kMaxPrincipalPx = 1e7;
constexpr double kMaxCoefficient = 1e6;
constexpr int kMaxResolution = 65536;

inline std::string Num(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v == 0 ? 0.0 : v);  // no "-0"
  return text;
}

// A double as OpenCV writes reals: with a '.' or an exponent, so that it reads back as a real.
inline std::string Real(double v) {
  std::string s = Num(v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".";
  return s;
}

// Long double text for COLMAP's principal point (Pandora's + 0.5): 21 digits carry a 64-bit
// mantissa, so that reading back and subtracting 0.5 in long double gives Pandora's value exactly.
inline std::string LongNum(long double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.21Lg", v);
  return text;
}

inline std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

inline std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::string line;
  std::istringstream in(text);
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// Strict number: the whole token, finite.
inline bool ParseDouble(const std::string& token, long double* out) {
  if (token.empty()) return false;
  const char* begin = token.c_str();
  char* end = nullptr;
  errno = 0;
  const long double v = std::strtold(begin, &end);
  if (end == begin || *end != '\0' || errno == ERANGE || !std::isfinite(v)) return false;
  // strtold accepts "nan", "inf", hex floats: only decimal text here.
  for (char c : token)
    if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+' ||
          c == 'e' || c == 'E'))
      return false;
  *out = v;
  return true;
}

inline bool ParseInt(const std::string& token, long long min, long long max, long long* out) {
  if (token.empty() || token.size() > 18) return false;
  std::size_t i = token[0] == '-' || token[0] == '+' ? 1 : 0;
  if (i == token.size()) return false;
  for (std::size_t j = i; j < token.size(); ++j)
    if (!std::isdigit(static_cast<unsigned char>(token[j]))) return false;
  const long long v = std::stoll(token);
  if (v < min || v > max) return false;
  *out = v;
  return true;
}

// Checks the values every imported camera must have, then builds it. `fail(field, reason)` throws.
template <class Fail>
Camera MakeCamera(const std::string& id, const std::string& name, Intrinsics k, const Mat3& r_cw,
                  const Vec3& t_cw, const Fail& fail) {
  if (!(k.fx > 0 && k.fx <= kMaxFocalPx) || !(k.fy > 0 && k.fy <= kMaxFocalPx))
    fail("focal length",
         "fx and fy must be in (0, 1e7] pixels, got " + Num(k.fx) + ", " + Num(k.fy));
  if (!(std::abs(k.cx) <= kMaxPrincipalPx) || !(std::abs(k.cy) <= kMaxPrincipalPx))
    fail("principal point",
         "cx and cy must be within 1e7 pixels, got " + Num(k.cx) + ", " + Num(k.cy));
  for (double c : {k.k1, k.k2, k.p1, k.p2, k.k3, k.k4})
    if (!(std::abs(c) <= kMaxCoefficient))
      fail("distortion", "coefficient " + Num(c) + " is beyond 1e6 in magnitude");
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(r_cw(i, j))) fail("rotation", "not finite");
  const double orthogonality = (r_cw.transpose() * r_cw - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!(orthogonality <= 1e-6) || !(r_cw.determinant() > 0))
    fail("rotation", "not a rotation matrix (R^T R differs from I by " + Num(orthogonality) +
                         ", det " + Num(r_cw.determinant()) + ")");
  const Vec3 centre = -(r_cw.transpose() * t_cw);
  if (!(centre.cwiseAbs().maxCoeff() <= SceneLimits::kMaxCoordinate))
    fail("translation", "the camera centre lies beyond 1e7 m");
  // Ids and names become JSON strings of the scene file: printable UTF-8 only.
  if (const std::string bad = CheckPrintableUtf8(id); !bad.empty())
    fail("id", "the camera id holds " + bad);
  if (const std::string bad = CheckPrintableUtf8(name); !bad.empty())
    fail("name", "the camera name holds " + bad);
  Camera camera;
  camera.id = id;
  camera.name = name.empty() ? id : name;
  camera.world_from_camera.linear() = r_cw.transpose();
  camera.world_from_camera.translation() = centre;
  camera.model = CameraModel(k);
  return camera;
}

}  // namespace pandora::rig_format
