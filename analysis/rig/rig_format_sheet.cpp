// A rig as an installation sheet, CSV (analysis/rig/rig_formats.h, docs/tool-chain.md).
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "analysis/geometry/pose.h"
#include "analysis/rig/rig_format_text.h"
#include "analysis/rig/rig_formats.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "analysis/util/units.h"

namespace pandora {

using namespace rig_format;  // NOLINT: the formats' shared helpers

namespace {

std::string Csv(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string Fixed(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  std::string s = text;
  // No "-0.0".
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);
  return s;
}

}  // namespace

std::string RigToSheetCsv(const Rig& rig) {
  std::string out =
      "id,name,colour,x_cm,y_cm,z_cm,pan_deg,tilt_deg,roll_deg,hfov_deg,vfov_deg,fx_px,fy_px,"
      "cx_px,cy_px,lens,width_px,height_px,enabled\n";
  for (const Camera& camera : rig.cameras) {
    const Intrinsics& k = camera.model.intrinsics();
    const Vec3 p = camera.center() * 100.0;
    const Vec3 ypr = YawPitchRollDeg(camera.world_from_camera.linear());
    char colour[8];
    const auto byte = [](double linear) {
      return static_cast<int>(std::lround(std::clamp(SrgbFromLinear(linear), 0.0, 1.0) * 255.0));
    };
    std::snprintf(colour, sizeof colour, "#%02x%02x%02x", byte(camera.color.x()),
                  byte(camera.color.y()), byte(camera.color.z()));
    out += Csv(camera.id) + "," + Csv(camera.name) + "," + colour + "," + Fixed(p.x(), 1) + "," +
           Fixed(p.y(), 1) + "," + Fixed(p.z(), 1) + "," + Fixed(ypr.x(), 2) + "," +
           Fixed(ypr.y(), 2) + "," + Fixed(ypr.z(), 2) + "," +
           Fixed(HfovFromFocal(k.fx, k.width, k.model) * 180.0 / kPi, 2) + "," +
           Fixed(HfovFromFocal(k.fy, k.height, k.model) * 180.0 / kPi, 2) + "," + Fixed(k.fx, 1) +
           "," + Fixed(k.fy, 1) + "," + Fixed(k.cx, 1) + "," + Fixed(k.cy, 1) + "," +
           LensModelName(k.model) + "," + std::to_string(k.width) + "," + std::to_string(k.height) +
           "," + (camera.enabled ? "yes" : "no") + "\n";
  }
  return out;
}

}  // namespace pandora
