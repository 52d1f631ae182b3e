#include "analysis/scene/fiducial.h"

#include <algorithm>
#include <cmath>

#include "analysis/scene/scene.h"

namespace pandora {
namespace {

// OpenCV 4.6's PREDEFINED_DICTIONARY_NAME, in its order.
constexpr ArucoDictionaryInfo kDictionaries[] = {
    {"DICT_4X4_50", 0, 4, 50},
    {"DICT_4X4_100", 1, 4, 100},
    {"DICT_4X4_250", 2, 4, 250},
    {"DICT_4X4_1000", 3, 4, 1000},
    {"DICT_5X5_50", 4, 5, 50},
    {"DICT_5X5_100", 5, 5, 100},
    {"DICT_5X5_250", 6, 5, 250},
    {"DICT_5X5_1000", 7, 5, 1000},
    {"DICT_6X6_50", 8, 6, 50},
    {"DICT_6X6_100", 9, 6, 100},
    {"DICT_6X6_250", 10, 6, 250},
    {"DICT_6X6_1000", 11, 6, 1000},
    {"DICT_7X7_50", 12, 7, 50},
    {"DICT_7X7_100", 13, 7, 100},
    {"DICT_7X7_250", 14, 7, 250},
    {"DICT_7X7_1000", 15, 7, 1000},
    {"DICT_ARUCO_ORIGINAL", 16, 5, 1024},
    {"DICT_APRILTAG_16h5", 17, 4, 30},
    {"DICT_APRILTAG_25h9", 18, 5, 35},
    {"DICT_APRILTAG_36h10", 19, 6, 2320},
    {"DICT_APRILTAG_36h11", 20, 6, 587},
};

}  // namespace

const ArucoDictionaryInfo* FindArucoDictionary(const std::string& name) {
  for (const ArucoDictionaryInfo& d : kDictionaries)
    if (name == d.name) return &d;
  return nullptr;
}

std::vector<std::string> ArucoDictionaryNames() {
  std::vector<std::string> names;
  for (const ArucoDictionaryInfo& d : kDictionaries) names.emplace_back(d.name);
  return names;
}

const char* FiducialKindName(Fiducial::Kind kind) {
  switch (kind) {
    case Fiducial::Kind::kMarker:
      return "marker";
    case Fiducial::Kind::kCharuco:
      return "charuco";
    default:
      return "checkerboard";
  }
}

int Fiducial::Markers() const {
  switch (kind) {
    case Kind::kMarker:
      return 1;
    case Kind::kCharuco:
      return squares_x * squares_y / 2;
    default:
      return 0;
  }
}

int Fiducial::PatternTexelsX() const {
  const ArucoDictionaryInfo* d = FindArucoDictionary(dictionary);
  const int cells = d ? d->bits + 2 : 6;
  switch (kind) {
    case Kind::kMarker:
      return 12 * cells;
    case Kind::kCharuco:
      return squares_x * static_cast<int>(std::ceil(12.0 * cells * square_m / marker_m - 1e-9));
    default:
      return squares_x * 24;
  }
}

int Fiducial::PatternTexelsY() const {
  return kind == Kind::kMarker ? PatternTexelsX() : PatternTexelsX() / squares_x * squares_y;
}

int Fiducial::MarginTexels() const {
  return static_cast<int>(std::lround(margin_m * TexelsPerMetre()));
}

std::vector<FiducialCorner> FiducialCorners(const Fiducial& f) {
  std::vector<FiducialCorner> corners;
  if (f.kind == Fiducial::Kind::kMarker) {
    const double h = 0.5 * f.square_m;
    const Vec2 xy[4] = {Vec2(-h, h), Vec2(h, h), Vec2(h, -h), Vec2(-h, -h)};
    for (int k = 0; k < 4; ++k) corners.push_back({4 * f.id + k, xy[k]});
    return corners;
  }
  const double w = f.PatternWidth(), h = f.PatternHeight();
  for (int y = 0; y + 1 < f.squares_y; ++y)
    for (int x = 0; x + 1 < f.squares_x; ++x)
      corners.push_back({y * (f.squares_x - 1) + x,
                         Vec2((x + 1) * f.square_m - 0.5 * w, 0.5 * h - (y + 1) * f.square_m)});
  return corners;
}

void FiducialTextureSize(const Fiducial& f, int* width, int* height) {
  *width = f.PatternTexelsX() + 2 * f.MarginTexels() + 2;
  *height = f.PatternTexelsY() + 2 * f.MarginTexels() + 2;
}

TriangleMesh FiducialSheet(const Fiducial& f, int tw, int th) {
  const double hx = 0.5 * f.SheetWidth(), hy = 0.5 * f.SheetHeight(), z = -f.thickness_m;
  TriangleMesh mesh;
  mesh.vertices = {Vec3(-hx, -hy, 0), Vec3(hx, -hy, 0), Vec3(hx, hy, 0), Vec3(-hx, hy, 0),
                   Vec3(-hx, -hy, z), Vec3(hx, -hy, z), Vec3(hx, hy, z), Vec3(-hx, hy, z)};
  mesh.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3), Eigen::Vector3i(4, 6, 5),
                    Eigen::Vector3i(4, 7, 6)};
  // v = 0 is the print's bottom row (render/frame.cpp's SampleTexture); the sheet's edges sit one
  // texel inside the print, on the inner edge of its white ring.
  const double u0 = 1.0 / tw, u1 = 1.0 - 1.0 / tw, v0 = 1.0 / th, v1 = 1.0 - 1.0 / th;
  const Eigen::Vector2d a(u0, v0), b(u1, v0), c(u1, v1), d(u0, v1);
  const Eigen::Vector2d white(0.5 / tw, 0.5 / th);
  mesh.corner_uvs = {{a, b, c}, {a, c, d}, {white, white, white}, {white, white, white}};
  return mesh;
}

int AddFiducial(Scene* scene, Fiducial f, const Eigen::Affine3d& world_from_pattern,
                const std::string& group) {
  int tw = 0, th = 0;
  FiducialTextureSize(f, &tw, &th);
  Material print;
  print.name = f.name + " (print)";
  print.color = Vec3::Constant(0.85);  // paper
  scene->materials.push_back(print);
  f.material = static_cast<int>(scene->materials.size()) - 1;
  f.object = static_cast<int>(scene->objects.size());
  SceneObject sheet;
  sheet.name = f.name;
  sheet.source = f.kind == Fiducial::Kind::kMarker ? "marker" : "board";
  sheet.mesh = FiducialSheet(f, tw, th);
  for (Vec3& v : sheet.mesh.vertices) v = world_from_pattern * v;
  sheet.material = f.material;
  sheet.group = group;
  scene->objects.push_back(std::move(sheet));
  scene->fiducials.push_back(std::move(f));
  return static_cast<int>(scene->fiducials.size()) - 1;
}

Vec3 FiducialPoint(const Scene& scene, const Fiducial& f, const Vec2& xy) {
  const std::vector<Vec3>& v = scene.objects[f.object].mesh.vertices;
  const double hx = 0.5 * f.SheetWidth(), hy = 0.5 * f.SheetHeight();
  return v[0] + ((xy.x() + hx) / (2 * hx)) * (v[1] - v[0]) +
         ((xy.y() + hy) / (2 * hy)) * (v[3] - v[0]);
}

Vec3 FiducialNormal(const Scene& scene, const Fiducial& f) {
  const std::vector<Vec3>& v = scene.objects[f.object].mesh.vertices;
  return (v[1] - v[0]).cross(v[3] - v[0]).normalized();
}

}  // namespace pandora
