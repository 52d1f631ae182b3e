// A rig as a COLMAP text model, written and read (analysis/rig/rig_formats.h,
// docs/tool-chain.md).
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
namespace {

using namespace rig_format;  // NOLINT: the formats' shared helpers

// ---------------------------------------------------------------------------------------------
// COLMAP

std::string PercentEncode(const std::string& s) {
  std::string out;
  for (unsigned char c : s) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.') {
      out += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

bool PercentDecode(const std::string& s, std::string* out) {
  out->clear();
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      *out += s[i];
      continue;
    }
    if (i + 2 >= s.size() || !std::isxdigit(static_cast<unsigned char>(s[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(s[i + 2])))
      return false;
    *out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
    i += 2;
  }
  return true;
}

std::vector<std::string> Tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

const char* kColmapImageExtensions[] = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".exr"};

}  // namespace

ColmapText RigToColmap(const Rig& rig) {
  ColmapText out;
  const std::size_t n = rig.cameras.size();
  out.cameras =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: " +
      std::to_string(n) + "\n";
  out.images =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: " +
      std::to_string(n) + ", mean observations per image: 0\n";
  out.points3d =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: 0, mean track length: 0\n";
  for (std::size_t i = 0; i < n; ++i) {
    const Camera& camera = rig.cameras[i];
    const Intrinsics& k = camera.model.intrinsics();
    const std::string id = std::to_string(i + 1);
    const std::string cx = LongNum(static_cast<long double>(k.cx) + 0.5L);
    const std::string cy = LongNum(static_cast<long double>(k.cy) + 0.5L);
    std::string line = id + " ";
    const std::string common = std::to_string(k.width) + " " + std::to_string(k.height) + " " +
                               Num(k.fx) + " " + Num(k.fy) + " " + cx + " " + cy;
    if (k.model == LensModel::kPinhole) {
      line += "PINHOLE " + common;
    } else if (k.model == LensModel::kFisheye) {
      line += "OPENCV_FISHEYE " + common + " " + Num(k.k1) + " " + Num(k.k2) + " " + Num(k.k3) +
              " " + Num(k.k4);
    } else if (k.k3 == 0) {
      line += "OPENCV " + common + " " + Num(k.k1) + " " + Num(k.k2) + " " + Num(k.p1) + " " +
              Num(k.p2);
    } else {
      line += "FULL_OPENCV " + common + " " + Num(k.k1) + " " + Num(k.k2) + " " + Num(k.p1) + " " +
              Num(k.p2) + " " + Num(k.k3) + " 0 0 0";
    }
    out.cameras += line + "\n";
    const Eigen::Isometry3d cw = camera.camera_from_world();
    Eigen::Quaterniond q(cw.linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const Vec3 t = cw.translation();
    out.images += id + " " + Num(q.w()) + " " + Num(q.x()) + " " + Num(q.y()) + " " + Num(q.z()) +
                  " " + Num(t.x()) + " " + Num(t.y()) + " " + Num(t.z()) + " " + id + " " +
                  ColmapImageName(camera) + "\n\n";
  }
  return out;
}

std::string ColmapImageName(const Camera& camera) { return PercentEncode(camera.id) + ".png"; }

namespace {

// A COLMAP camera: its intrinsics and the line of cameras.txt that gives them.
struct ColmapCamera {
  Intrinsics k;
  int line = 0;
};

// Throws the InputError of a line (and field) of a COLMAP text file.
void ColmapFail(const std::string& path, int line, const std::string& field,
                const std::string& reason, const std::string& hint = "") {
  throw InputError(path, "line " + std::to_string(line) + (field.empty() ? "" : ": " + field),
                   reason, hint);
}

// The intrinsics of a cameras.txt line from its model `m`, parameters `p` and size.
Intrinsics ColmapIntrinsics(const std::string& m, const std::vector<long double>& p, long long w,
                            long long h, const std::string& cameras_path, int number) {
  Intrinsics k;
  k.width = static_cast<int>(w);
  k.height = static_cast<int>(h);
  std::size_t next;
  if (m == "SIMPLE_PINHOLE" || m == "SIMPLE_RADIAL" || m == "RADIAL") {
    k.fx = k.fy = static_cast<double>(p[0]);
    k.cx = static_cast<double>(p[1] - 0.5L);
    k.cy = static_cast<double>(p[2] - 0.5L);
    next = 3;
  } else {
    k.fx = static_cast<double>(p[0]);
    k.fy = static_cast<double>(p[1]);
    k.cx = static_cast<double>(p[2] - 0.5L);
    k.cy = static_cast<double>(p[3] - 0.5L);
    next = 4;
  }
  const auto c = [&](std::size_t j) { return static_cast<double>(p[next + j]); };
  if (m == "SIMPLE_RADIAL" || m == "RADIAL") {
    k.model = LensModel::kBrownConrady;
    k.k1 = c(0);
    if (m == "RADIAL") k.k2 = c(1);
  } else if (m == "OPENCV" || m == "FULL_OPENCV") {
    k.model = LensModel::kBrownConrady;
    k.k1 = c(0), k.k2 = c(1), k.p1 = c(2), k.p2 = c(3);
    if (m == "FULL_OPENCV") {
      k.k3 = c(4);
      if (c(5) != 0 || c(6) != 0 || c(7) != 0)
        ColmapFail(
            cameras_path, number, "PARAMS[9..11]",
            "k4 k5 k6 (the rational model) are not zero: Pandora models k1 k2 p1 p2 k3 only");
    }
  } else if (m == "OPENCV_FISHEYE") {
    k.model = LensModel::kFisheye;
    k.k1 = c(0), k.k2 = c(1), k.k3 = c(2), k.k4 = c(3);
  }
  return k;
}

// The cameras of cameras.txt by CAMERA_ID.
std::map<long long, ColmapCamera> ReadColmapCameras(const std::string& cameras_text,
                                                    const std::string& cameras_path) {
  std::map<long long, ColmapCamera> cams;
  const std::vector<std::string> camera_lines = SplitLines(cameras_text);
  for (std::size_t i = 0; i < camera_lines.size(); ++i) {
    const int number = static_cast<int>(i) + 1;
    const std::string line = Trim(camera_lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> t = Tokens(line);
    if (t.size() < 4)
      ColmapFail(cameras_path, number, "", "expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    long long id = 0, w = 0, h = 0;
    if (!ParseInt(t[0], 0, 2147483647LL, &id))
      ColmapFail(cameras_path, number, "CAMERA_ID",
                 "expected a whole number, got '" + t[0].substr(0, 40) + "'");
    if (cams.count(id))
      ColmapFail(cameras_path, number, "CAMERA_ID", "camera " + t[0] + " appears twice");
    if (!ParseInt(t[2], 1, kMaxResolution, &w))
      ColmapFail(cameras_path, number, "WIDTH",
                 "expected a whole number in [1, 65536], got '" + t[2].substr(0, 40) + "'");
    if (!ParseInt(t[3], 1, kMaxResolution, &h))
      ColmapFail(cameras_path, number, "HEIGHT",
                 "expected a whole number in [1, 65536], got '" + t[3].substr(0, 40) + "'");
    static const std::map<std::string, std::size_t> kParams = {
        {"SIMPLE_PINHOLE", 3}, {"PINHOLE", 4},      {"SIMPLE_RADIAL", 4}, {"RADIAL", 5},
        {"OPENCV", 8},         {"FULL_OPENCV", 12}, {"OPENCV_FISHEYE", 8}};
    const auto model = kParams.find(t[1]);
    if (model == kParams.end())
      ColmapFail(
          cameras_path, number, "MODEL", "unsupported camera model '" + t[1].substr(0, 40) + "'",
          "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV, OPENCV_FISHEYE");
    if (t.size() - 4 != model->second)
      ColmapFail(cameras_path, number, "PARAMS",
                 model->first + " has " + std::to_string(model->second) + " parameters, got " +
                     std::to_string(t.size() - 4));
    std::vector<long double> p;
    for (std::size_t j = 4; j < t.size(); ++j) {
      long double v = 0;
      if (!ParseDouble(t[j], &v) || !(std::fabs(v) <= 1e300L))
        ColmapFail(cameras_path, number, "PARAMS[" + std::to_string(j - 4) + "]",
                   "expected a finite number, got '" + t[j].substr(0, 40) + "'");
      p.push_back(v);
    }
    const Intrinsics k = ColmapIntrinsics(model->first, p, w, h, cameras_path, number);
    cams[id] = {k, number};
  }
  if (cams.empty())
    ColmapFail(cameras_path, static_cast<int>(camera_lines.size()), "", "no cameras");
  return cams;
}

// The camera id an image line's NAME gives: percent-decoded, without an image extension.
std::string ColmapImageId(const std::vector<std::string>& t, const std::string& images_path,
                          int number) {
  std::string name = t[9], id;
  if (!PercentDecode(name, &id))
    ColmapFail(images_path, number, "NAME", "bad percent escape in '" + name.substr(0, 40) + "'");
  for (const char* ext : kColmapImageExtensions) {
    const std::size_t n = std::strlen(ext);
    if (id.size() > n) {
      std::string tail = id.substr(id.size() - n);
      for (char& ch : tail) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (tail == ext) {
        id.resize(id.size() - n);
        break;
      }
    }
  }
  if (id.empty()) ColmapFail(images_path, number, "NAME", "empty image name");
  if (const std::string bad = CheckPrintableUtf8(id); !bad.empty())
    ColmapFail(images_path, number, "NAME", "the image name (a camera id) holds " + bad);
  return id;
}

// Checks the POINTS2D line that follows image line `number`.
void CheckColmapPoints2d(const std::string& points_line, const std::string& images_path,
                         int number) {
  const std::vector<std::string> pts = Tokens(points_line);
  if (pts.size() % 3 != 0)
    ColmapFail(
        images_path, number + 1, "POINTS2D",
        "expected (X, Y, POINT3D_ID) triples, got " + std::to_string(pts.size()) + " numbers");
  for (std::size_t j = 0; j < pts.size(); ++j) {
    long double x = 0;
    long long pid = 0;
    const bool ok =
        j % 3 == 2 ? ParseInt(pts[j], -1, 9223372036854775807LL, &pid) : ParseDouble(pts[j], &x);
    if (!ok)
      ColmapFail(images_path, number + 1, "POINTS2D[" + std::to_string(j) + "]",
                 "expected a number, got '" + pts[j].substr(0, 40) + "'");
  }
}

}  // namespace

Rig ParseColmap(const std::string& cameras_text, const std::string& cameras_path,
                const std::string& images_text, const std::string& images_path,
                const std::string& rig_name) {
  std::map<long long, ColmapCamera> cams = ReadColmapCameras(cameras_text, cameras_path);

  Rig rig;
  rig.name = rig_name;
  std::set<long long> image_ids;
  const std::vector<std::string> image_lines = SplitLines(images_text);
  for (std::size_t i = 0; i < image_lines.size(); ++i) {
    const int number = static_cast<int>(i) + 1;
    const std::string line = Trim(image_lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> t = Tokens(line);
    if (t.size() != 10)
      ColmapFail(images_path, number, "",
                 "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 fields), got " +
                     std::to_string(t.size()));
    long long image_id = 0, camera_id = 0;
    if (!ParseInt(t[0], 0, 2147483647LL, &image_id))
      ColmapFail(images_path, number, "IMAGE_ID",
                 "expected a whole number, got '" + t[0].substr(0, 40) + "'");
    if (!image_ids.insert(image_id).second)
      ColmapFail(images_path, number, "IMAGE_ID", "image " + t[0] + " appears twice");
    static const char* kNames[] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
    double v[7];
    for (int j = 0; j < 7; ++j) {
      long double x = 0;
      if (!ParseDouble(t[1 + j], &x) || !(std::fabs(x) <= 1e300L))
        ColmapFail(images_path, number, kNames[j],
                   "expected a finite number, got '" + t[1 + j].substr(0, 40) + "'");
      v[j] = static_cast<double>(x);
    }
    if (!ParseInt(t[8], 0, 2147483647LL, &camera_id) || !cams.count(camera_id))
      ColmapFail(images_path, number, "CAMERA_ID",
                 "no camera '" + t[8].substr(0, 40) + "' in the cameras file");
    Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
    if (!(std::abs(q.norm() - 1) <= 1e-6))
      ColmapFail(images_path, number, "QW QX QY QZ",
                 "not a unit quaternion (norm " + Num(q.norm()) + ")");
    q.normalize();
    const std::string id = ColmapImageId(t, images_path, number);
    if (rig.FindCamera(id) >= 0)
      ColmapFail(images_path, number, "NAME", "two images give the camera id '" + id + "'");
    // The POINTS2D line follows directly (COLMAP reads it even when empty).
    if (i + 1 >= image_lines.size())
      ColmapFail(images_path, number, "POINTS2D", "missing the POINTS2D line after the image line");
    ++i;
    CheckColmapPoints2d(image_lines[i], images_path, number);
    if (static_cast<long long>(rig.cameras.size()) >= SceneLimits::kMaxCameras)
      ColmapFail(images_path, number, "", "more than 10000 images");
    const auto bad = [&](const std::string& what, const std::string& reason) {
      const int at = what == "rotation" || what == "translation" ? number : cams[camera_id].line;
      ColmapFail(what == "rotation" || what == "translation" ? images_path : cameras_path, at, what,
                 reason);
    };
    rig.cameras.push_back(
        MakeCamera(id, "", cams[camera_id].k, q.toRotationMatrix(), Vec3(v[4], v[5], v[6]), bad));
  }
  if (rig.cameras.empty())
    ColmapFail(images_path, static_cast<int>(image_lines.size()), "", "no images (one per camera)");
  return rig;
}

}  // namespace pandora
