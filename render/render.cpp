// The projective-light renderer (render/render.h): primary rays through Embree (RayCaster), the
// visibility rules per camera (VisibilityTester), occlusion segments in packets per image tile.
#include "render/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <cctype>
#include <filesystem>
#include <cstdio>
#include <unordered_map>

#include "analysis/error.h"
#include "analysis/uncertainty.h"
#include "analysis/visibility.h"
#include "render/colormap.h"
#include "render/overlay_fields.h"
#include "volume/active_set.h"

namespace pandora {

double DefaultBrightness(int enabled_cameras) {
  return enabled_cameras <= 3 ? 1.0 : 3.0 / enabled_cameras;
}

std::string FieldUnitLabel(const std::string& field) {
  std::string base = field;
  const std::string steady = "_steady";
  if (base.size() > steady.size() && base.compare(base.size() - steady.size(), steady.size(), steady) == 0)
    base.resize(base.size() - steady.size());
  if (base == "coverage") return field + " [cameras]";
  if (base == "resolution") return field + " [px/m]";
  if (base == "sigma_max" || base == "sigma_mean") return field + " [mm]";
  if (base == "triangulation_angle") return field + " [deg]";
  if (base == "condition") return field + " [1]";
  return field;
}

RenderView ViewFromScene(const View& view, int width, int height, double default_fov_deg) {
  RenderView v;
  v.from = view.from;
  v.at = view.at;
  v.up = view.up;
  v.fov_deg = view.fov_deg.value_or(default_fov_deg);
  v.width = width;
  v.height = height;
  return v;
}

namespace {

// Texture coordinate at point X of triangle t (barycentric interpolation of its corners).
Eigen::Vector2d TextureCoordinate(const TriangleMesh& mesh, int t, const Vec3& X) {
  const Eigen::Vector3i& tri = mesh.triangles[t];
  const Vec3 a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
  const Vec3 n = (b - a).cross(c - a);
  const double area2 = n.squaredNorm();
  if (!(area2 > 0)) return mesh.corner_uvs[t][0];
  const double wb = (X - a).cross(c - a).dot(n) / area2;  // weight of b
  const double wc = (b - a).cross(X - a).dot(n) / area2;  // weight of c
  const auto& uv = mesh.corner_uvs[t];
  return (1.0 - wb - wc) * uv[0] + wb * uv[1] + wc * uv[2];
}

// Bilinear lookup with repeat wrapping, linear RGB; v = 0 is the image's bottom row (the OpenGL /
// OBJ / assimp convention), texel centres at (i + 0.5) / size.
Vec3 SampleTexture(const Image& tex, const Eigen::Vector2d& uv) {
  const double x = (uv.x() - std::floor(uv.x())) * tex.width - 0.5;
  const double y = (1.0 - (uv.y() - std::floor(uv.y()))) * tex.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  auto texel = [&](int i, int j) {
    i = ((i % tex.width) + tex.width) % tex.width;
    j = ((j % tex.height) + tex.height) % tex.height;
    const float* p = &tex.rgb[3 * (std::size_t(j) * tex.width + i)];
    return Vec3(p[0], p[1], p[2]);
  };
  const int i = int(fx), j = int(fy);
  return (1 - ay) * ((1 - ax) * texel(i, j) + ax * texel(i + 1, j)) +
         ay * ((1 - ax) * texel(i, j + 1) + ax * texel(i + 1, j + 1));
}

// Loads each textured material's PNG once; returns per object the index into `textures`, or -1.
// A texture that cannot be read (missing file, not a PNG) leaves that object its plain colour,
// with one warning line on stderr.
std::vector<int> LoadTextures(const Scene& scene, std::vector<Image>* textures) {
  std::vector<int> of_material(scene.materials.size(), -1);
  for (std::size_t m = 0; m < scene.materials.size(); ++m) {
    const std::string& path = scene.materials[m].texture;
    if (path.empty()) continue;
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    try {
      if (ext != ".png") throw std::runtime_error("only PNG textures are read");
      textures->push_back(ReadPng(path));
      of_material[m] = static_cast<int>(textures->size()) - 1;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "pandora: warning: texture %s not used (%s); the material colour stands in\n",
                   path.c_str(), e.what());
    }
  }
  std::vector<int> of_object(scene.objects.size(), -1);
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const int m = scene.objects[o].material;
    if (m >= 0 && m < int(of_material.size()) && !scene.objects[o].mesh.corner_uvs.empty())
      of_object[o] = of_material[m];
  }
  return of_object;
}


constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kTile = 16;  // tile edge in pixels: 256 centre samples share a packet per camera

// Primary rays of the view: a pinhole eye, or a rig camera's own lens (unprojected).
class ViewRays {
 public:
  ViewRays(const RenderView& view, const Rig& rig) : width_(view.width), height_(view.height) {
    if (view.camera >= 0) {
      cam_ = &rig.cameras[view.camera];
      eye_ = cam_->center();
      R_ = cam_->world_from_camera.linear();
      sx_ = double(cam_->model.width()) / width_;
      sy_ = double(cam_->model.height()) / height_;
      // Centre rays (one unprojection per pixel) and their exact per-pixel differentials: the
      // projection's Jacobian J at the unit direction has the ray in its null space, so
      // M = J^T (J J^T)^-1 is d(direction)/d(pixel), perpendicular to the direction.
      const std::size_t n = std::size_t(width_) * height_;
      table_.resize(n);
      tbb::parallel_for(0, height_, [&](int y) {
        for (int x = 0; x < width_; ++x) {
          Entry& e = table_[std::size_t(y) * width_ + x];
          const Vec2 pixel((x + 0.5) * sx_ - 0.5, (y + 0.5) * sy_ - 0.5);
          const auto dir = cam_->model.Unproject(pixel);
          if (!dir) continue;
          Mat23 J;
          if (!cam_->model.Project(*dir, &J)) continue;
          const Eigen::Matrix2d JJt = J * J.transpose();
          if (!(std::abs(JJt.determinant()) > 0)) continue;
          const Eigen::Matrix<double, 3, 2> M = J.transpose() * JJt.inverse();
          e.ok = true;
          e.d = R_ * *dir;
          e.dx = R_ * M.col(0) * sx_;
          e.dy = R_ * M.col(1) * sy_;
        }
      });
    } else {
      const auto pose = LookAt(view.from, view.at, view.up);
      eye_ = view.from;
      R_ = pose->linear();
      f_ = 0.5 * width_ / std::tan(0.5 * view.fov_deg * M_PI / 180.0);
      cx_ = 0.5 * width_ - 0.5;
      cy_ = 0.5 * height_ - 0.5;
      Intrinsics k;
      k.width = width_;
      k.height = height_;
      k.fx = k.fy = f_;
      k.cx = cx_;
      k.cy = cy_;
      pinhole_.model = CameraModel(k);
      pinhole_.world_from_camera = *pose;
    }
  }

  const Vec3& eye() const { return eye_; }
  bool perspective() const { return cam_ == nullptr; }
  const Camera& pinhole() const { return pinhole_; }

  // Unit direction through output pixel coordinates (px, py); false outside the lens's domain.
  bool Direction(double px, double py, Vec3* d) const {
    if (!cam_) {
      *d = (R_ * Vec3((px - cx_) / f_, (py - cy_) / f_, 1.0)).normalized();
      return true;
    }
    const Vec2 pixel((px + 0.5) * sx_ - 0.5, (py + 0.5) * sy_ - 0.5);
    const auto dir = cam_->model.Unproject(pixel);
    if (!dir) return false;
    *d = R_ * *dir;
    return true;
  }

  // The centre ray of pixel (x, y) and the derivatives of its unit direction per output pixel.
  // `ddx` and `ddy` may be null when the differentials are not needed.
  bool Center(int x, int y, Vec3* d, Vec3* ddx, Vec3* ddy) const {
    if (!cam_) {
      const Vec3 D = R_.col(2) + ((x - cx_) / f_) * R_.col(0) + ((y - cy_) / f_) * R_.col(1);
      const double len = D.norm();
      *d = D / len;
      if (ddx) {
        const Vec3 Dx = R_.col(0) / f_, Dy = R_.col(1) / f_;
        *ddx = (Dx - *d * d->dot(Dx)) / len;
        *ddy = (Dy - *d * d->dot(Dy)) / len;
      }
      return true;
    }
    const Entry& e = table_[std::size_t(y) * width_ + x];
    if (!e.ok) return false;
    *d = e.d;
    if (ddx) {
      *ddx = e.dx;
      *ddy = e.dy;
    }
    return true;
  }

 private:
  struct Entry {
    bool ok = false;
    Vec3 d, dx, dy;
  };
  int width_, height_;
  const Camera* cam_ = nullptr;
  Vec3 eye_;
  Mat3 R_;
  double f_ = 1, cx_ = 0, cy_ = 0;
  double sx_ = 1, sy_ = 1;
  std::vector<Entry> table_;
  Camera pinhole_;
};

// Which of each triangle's edges the hidden-line mode draws: edges between triangles that are not
// coplanar (dihedral angle above 1 degree) and boundary edges. Bit i: the edge opposite vertex i.
std::vector<uint8_t> DrawnEdges(const TriangleMesh& mesh) {
  struct Key {
    std::array<double, 6> v;
    bool operator==(const Key& o) const { return v == o.v; }
  };
  struct Hash {
    std::size_t operator()(const Key& k) const {
      std::size_t h = 0;
      for (double x : k.v) h = h * 1000003u ^ std::hash<double>()(x);
      return h;
    }
  };
  const std::size_t n = mesh.triangles.size();
  std::vector<Vec3> normals(n);
  for (std::size_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3 c = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                       .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
    const double len = c.norm();
    normals[t] = len > 0 ? Vec3(c / len) : Vec3::Zero();
  }
  std::unordered_map<Key, std::vector<std::pair<uint32_t, uint8_t>>, Hash> edges;
  edges.reserve(3 * n);
  for (std::size_t t = 0; t < n; ++t)
    for (int i = 0; i < 3; ++i) {
      Vec3 a = mesh.vertices[mesh.triangles[t][(i + 1) % 3]];
      Vec3 b = mesh.vertices[mesh.triangles[t][(i + 2) % 3]];
      if (std::lexicographical_compare(b.data(), b.data() + 3, a.data(), a.data() + 3)) std::swap(a, b);
      edges[Key{{a.x(), a.y(), a.z(), b.x(), b.y(), b.z()}}].push_back({uint32_t(t), uint8_t(i)});
    }
  const double cos_crease = std::cos(1.0 * M_PI / 180.0);
  std::vector<uint8_t> drawn(n, 0);
  for (const auto& [key, list] : edges) {
    bool draw = list.size() == 1;
    for (std::size_t a = 0; a < list.size() && !draw; ++a)
      for (std::size_t b = a + 1; b < list.size() && !draw; ++b)
        draw = std::abs(normals[list[a].first].dot(normals[list[b].first])) < cos_crease;
    if (draw)
      for (const auto& [t, i] : list) drawn[t] |= uint8_t(1u << i);
  }
  return drawn;
}

// Box-filtered coverage of a line `width` pixels wide at `distance` pixels from the pixel centre.
inline double LineCoverage(double distance, double width) {
  return std::clamp(0.5 * width + 0.5 - distance, 0.0, 1.0);
}

// Coverage of one family of grid lines (every `n` camera pixels along one camera axis) at camera
// coordinate `u`, whose gradient per output pixel has norm `g` (camera pixels per output pixel).
double GridLine(double u, double g, int n, double width) {
  const double f = (u + 0.5) / n;
  const double du = std::abs(f - std::round(f)) * n;  // camera pixels to the nearest line
  if (!(g > 0) || !std::isfinite(g)) return 0.0;
  const double spacing = n / g;                        // output pixels between lines
  const double line = LineCoverage(du / g, width);
  // Lines closer than ~3 output pixels would alias: fade to their mean coverage.
  const double mean = std::min(1.0, width / spacing);
  const double fade = std::clamp((3.0 - spacing) / 1.5, 0.0, 1.0);
  return (1.0 - fade) * line + fade * mean;
}

// What one sample (a ray through the pixel) found.
struct Sample {
  int pixel = 0;          // index in the tile
  double px = 0, py = 0;  // output pixel coordinates
  bool layers = false;    // the pixel's centre ray: fills the layers
  double weight = 0;      // share of the pixel's colour
  bool hit = false;
  double t = kInf;
  int triangle = -1;
  Vec3 d, ddx, ddy;       // direction and its per-pixel derivatives
  Vec3 X, n;              // hit point and geometric normal facing the eye
  Vec3 light = Vec3::Zero();
  uint64_t seen = 0;
};

// Antialiased 3D line segments with hidden parts dimmed, into an overlay (alpha, colour) buffer that
// keeps the strongest line per pixel.
class LineOverlay {
 public:
  LineOverlay(const Camera& view, const Image& image)
      : view_(view), cfw_(view.camera_from_world()), image_(image),
        alpha_(std::size_t(image.width) * image.height, 0.0f),
        color_(std::size_t(image.width) * image.height, 0) {}

  // Segments drawn after this call use `color` (up to 255 colours per overlay).
  std::size_t colors() const { return palette_.size(); }
  void SetColor(const Vec3& color) {
    palette_.push_back(color);
    current_ = uint8_t(palette_.size() - 1);
  }

  void Segment(const Vec3& A, const Vec3& B, double width) {
    Vec3 a = cfw_ * A, b = cfw_ * B;
    constexpr double kNear = 1e-3;
    if (a.z() < kNear && b.z() < kNear) return;
    if (a.z() < kNear) a = a + (kNear - a.z()) / (b.z() - a.z()) * (b - a);
    if (b.z() < kNear) b = b + (kNear - b.z()) / (a.z() - b.z()) * (a - b);
    const Intrinsics& k = view_.model.intrinsics();
    const Vec2 pa(k.fx * a.x() / a.z() + k.cx, k.fy * a.y() / a.z() + k.cy);
    const Vec2 pb(k.fx * b.x() / b.z() + k.cx, k.fy * b.y() / b.z() + k.cy);
    const Vec2 ab = pb - pa;
    const double len2 = ab.squaredNorm();
    const double reach = 0.5 * width + 1.0;
    const int W = image_.width, H = image_.height;
    // Screen-space bounding box, clipped to the image (segments may extend far beyond it).
    const int xmin = std::max(0, int(std::floor(std::min(pa.x(), pb.x()) - reach)));
    const int xmax = std::min(W - 1, int(std::ceil(std::max(pa.x(), pb.x()) + reach)));
    const int ymin = std::max(0, int(std::floor(std::min(pa.y(), pb.y()) - reach)));
    const int ymax = std::min(H - 1, int(std::ceil(std::max(pa.y(), pb.y()) + reach)));
    if (xmin > xmax || ymin > ymax) return;
    // Clip the screen segment to the image grown by `reach` (Liang-Barsky), so segments that run
    // far outside the image (an end near the eye plane) cost only their visible part.
    double s0 = 0, s1 = 1;
    auto clip = [&](double p, double q) {  // keep p * s <= q
      if (p == 0) return q >= 0;
      const double r = q / p;
      if (p < 0) s0 = std::max(s0, r);
      else s1 = std::min(s1, r);
      return s0 <= s1;
    };
    if (!clip(-ab.x(), pa.x() + reach) || !clip(ab.x(), W - 1 + reach - pa.x()) ||
        !clip(-ab.y(), pa.y() + reach) || !clip(ab.y(), H - 1 + reach - pa.y()))
      return;
    const Vec2 qa = pa + s0 * ab, qb = pa + s1 * ab;
    // Walk the major axis one pixel at a time; cover the pixels within reach across it.
    const bool x_major = std::abs(ab.x()) >= std::abs(ab.y());
    const int major = x_major ? 0 : 1, minor = 1 - major;
    const int r = int(std::ceil(reach));
    const int m0 = int(std::floor(std::min(qa[major], qb[major]))) - r;
    const int m1 = int(std::ceil(std::max(qa[major], qb[major]))) + r;
    const int major_max = x_major ? W - 1 : H - 1, minor_max = x_major ? H - 1 : W - 1;
    for (int m = std::max(0, m0); m <= std::min(major_max, m1); ++m) {
      // Minor coordinate of the line at this major coordinate (clamped to the segment's span).
      const double t = ab[major] != 0 ? std::clamp((m - pa[major]) / ab[major], s0, s1) : s0;
      const int centre = int(std::lround(pa[minor] + t * ab[minor]));
      for (int n = std::max(0, centre - r); n <= std::min(minor_max, centre + r); ++n) {
        const int x = x_major ? m : n, y = x_major ? n : m;
        const Vec2 c(x, y);
        const double sigma = len2 > 0 ? std::clamp((c - pa).dot(ab) / len2, 0.0, 1.0) : 0.0;
        const double dist = (pa + sigma * ab - c).norm();
        double cover = LineCoverage(dist, width);
        if (cover <= 0) continue;
        // Perspective-correct point on the 3D segment, and its distance from the eye.
        const double s = (sigma / b.z()) / ((1.0 - sigma) / a.z() + sigma / b.z());
        const double depth = (a + s * (b - a)).norm();
        const std::size_t p = std::size_t(y) * W + x;
        if (depth > image_.depth[p] * (1.0 + 1e-3)) cover *= 0.3;  // hidden behind the surface: dimmed
        if (cover > alpha_[p]) {
          alpha_[p] = float(cover);
          color_[p] = current_;
        }
      }
    }
  }

  void CompositeInto(Image* image) const {
    for (std::size_t p = 0; p < alpha_.size(); ++p) {
      const double a = alpha_[p];
      if (a <= 0) continue;
      for (int k = 0; k < 3; ++k)
        image->rgb[3 * p + k] =
            float((1.0 - a) * image->rgb[3 * p + k] + a * palette_[color_[p]][k]);
    }
  }

 private:
  const Camera& view_;
  Eigen::Isometry3d cfw_;
  const Image& image_;
  std::vector<float> alpha_;
  std::vector<uint8_t> color_;
  std::vector<Vec3> palette_;
  uint8_t current_ = 0;
};

// Each enabled camera: a small box body behind its centre and its frustum (the distorted image
// border unprojected) as a wireframe out to min(frustum_length, far).
void DrawCameraOverlays(const Rig& rig, const Camera& view, const OverlayOptions& ov,
                        const RenderOptions& options, Image* image) {
  LineOverlay lines(view, *image);
  const double width = std::max(1.0, options.line_width_px);
  for (const Camera& cam : rig.cameras) {
    if (!cam.enabled) continue;
    if (lines.colors() >= 255) break;  // more than 255 cameras: the rest are not drawn
    lines.SetColor(cam.color.cwiseMax(Vec3::Constant(0.15)));
    const Eigen::Isometry3d& T = cam.world_from_camera;
    const double len = std::min(ov.frustum_length, cam.far);
    // Body: a box 8 x 6 x 10 cm behind the centre (camera frame: x right, y down, z forward).
    const double bx = 0.04, by = 0.03, bz = 0.10;
    Vec3 corners[8];
    for (int i = 0; i < 8; ++i)
      corners[i] = T * Vec3((i & 1) ? bx : -bx, (i & 2) ? by : -by, (i & 4) ? 0.0 : -bz);
    static const int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                      {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (const auto& e : kEdges) lines.Segment(corners[e[0]], corners[e[1]], width);
    // Frustum: the image border, 16 points per side, unprojected to distance `len`.
    const double w = cam.model.width() - 0.5, h = cam.model.height() - 0.5;
    std::vector<Vec3> border;
    std::vector<bool> corner;
    const Vec2 c4[5] = {{-0.5, -0.5}, {w, -0.5}, {w, h}, {-0.5, h}, {-0.5, -0.5}};
    for (int side = 0; side < 4; ++side)
      for (int i = 0; i < 16; ++i) {
        const Vec2 px = c4[side] + (i / 16.0) * (c4[side + 1] - c4[side]);
        const auto dir = cam.model.Unproject(px);
        if (!dir) continue;
        border.push_back(T * (len * *dir));
        corner.push_back(i == 0);
      }
    for (std::size_t i = 0; i < border.size(); ++i) {
      lines.Segment(border[i], border[(i + 1) % border.size()], width);
      if (corner[i]) lines.Segment(cam.center(), border[i], width);
    }
  }
  lines.CompositeInto(image);
}

// Colour bar of the slice overlay with its range and the field's name, lower right corner.
void DrawLegend(const std::string& field, double vmin, double vmax, Image* image) {
  const int W = image->width, H = image->height;
  const int scale = H >= 400 ? 2 : 1;
  const int bar_h = std::max(20, H / 3), bar_w = 8 * scale;
  char top[32], bottom[32];
  std::snprintf(top, sizeof top, "%.3g", vmax);
  std::snprintf(bottom, sizeof bottom, "%.3g", vmin);
  const int text_w = std::max({TextWidth(top, scale), TextWidth(bottom, scale), TextWidth(field, scale)});
  const int margin = 6 * scale;
  const int box_w = bar_w + 3 * margin + TextWidth(top, scale) * 0 + text_w;
  const int box_h = bar_h + 2 * margin + 8 * scale;
  const int x0 = W - box_w - margin, y0 = H - box_h - margin;
  if (x0 < 0 || y0 < 0) return;
  for (int y = y0; y < y0 + box_h; ++y)
    for (int x = x0; x < x0 + box_w; ++x)
      for (int k = 0; k < 3; ++k) {
        float& v = image->rgb[3 * (std::size_t(y) * W + x) + k];
        v = 0.25f * v;  // darken what is behind the legend
      }
  const int bx = x0 + margin, by = y0 + margin + 8 * scale;
  for (int y = 0; y < bar_h; ++y) {
    const Vec3 c = ViridisLinear(1.0 - double(y) / (bar_h - 1));
    for (int x = 0; x < bar_w; ++x)
      for (int k = 0; k < 3; ++k) image->rgb[3 * (std::size_t(by + y) * W + bx + x) + k] = float(c[k]);
  }
  const Vec3 white = Vec3::Constant(0.9);
  DrawText(image->rgb.data(), W, H, x0 + margin, y0 + margin, field, white, scale);
  DrawText(image->rgb.data(), W, H, bx + bar_w + margin, by, top, white, scale);
  DrawText(image->rgb.data(), W, H, bx + bar_w + margin, by + bar_h - 5 * scale, bottom, white, scale);
}

// The colour key, upper left corner: a swatch of each enabled camera's light and its id (up to 12
// characters), in as many columns as the image height needs; nothing when it would take more than
// half the width.
void DrawKey(const Rig& rig, Image* image) {
  const int W = image->width, H = image->height;
  std::vector<const Camera*> cams;
  for (const Camera& c : rig.cameras)
    if (c.enabled) cams.push_back(&c);
  if (cams.empty()) return;
  const int scale = H >= 400 ? 2 : 1;
  const int margin = 4 * scale, row = 8 * scale, swatch = 8 * scale;
  std::size_t longest = 1;
  for (const Camera* c : cams) longest = std::max<std::size_t>(longest, std::min<std::size_t>(c->id.size(), 12));
  const int col_w = swatch + 3 * scale + TextWidth(std::string(longest, 'm'), scale) + 2 * margin;
  const int rows_fit = std::max(1, (H - 3 * margin) / row);
  const int cols = (int(cams.size()) + rows_fit - 1) / rows_fit;
  const int rows = (int(cams.size()) + cols - 1) / cols;
  const int box_w = cols * col_w + margin, box_h = rows * row + 2 * margin - 2 * scale;
  if (box_w > W / 2 || box_h > H - margin) return;
  const int x0 = margin, y0 = margin;
  for (int y = y0; y < y0 + box_h; ++y)
    for (int x = x0; x < x0 + box_w; ++x)
      for (int k = 0; k < 3; ++k) {
        float& v = image->rgb[3 * (std::size_t(y) * W + x) + k];
        v = 0.2f * v;  // darken what is behind the key
      }
  const Vec3 text = Vec3::Constant(0.9);
  for (std::size_t i = 0; i < cams.size(); ++i) {
    const int col = int(i) / rows, r = int(i) % rows;
    const int x = x0 + margin + col * col_w, y = y0 + margin + r * row;
    // The swatch shows the light's colour at full strength (clamped as the PNG will be).
    const Vec3 c = cams[i]->color.cwiseMin(Vec3::Ones()).cwiseMax(Vec3::Zero());
    for (int yy = y; yy < y + 5 * scale && yy < H; ++yy)
      for (int xx = x; xx < x + swatch && xx < W; ++xx)
        for (int k = 0; k < 3; ++k) image->rgb[3 * (std::size_t(yy) * W + xx) + k] = float(c[k]);
    DrawText(image->rgb.data(), W, H, x + swatch + 3 * scale, y, cams[i]->id.substr(0, 12), text, scale);
  }
}

// Cheap necessary conditions of VisibilityTester::TestGeometry's kSeen, tested first: the point
// faces the camera, lies within its working range, and (for lenses under 180 degrees) in front of
// it within the normalized-coordinate bounds of the whole (distorted) image. A point failing any of
// them would fail TestGeometry too, so skipping it changes no result, only the time.
struct Cull {
  explicit Cull(const Camera& cam)
      : center(cam.center()), cfw(cam.camera_from_world()), near2(cam.near * cam.near),
        far2(cam.far * cam.far), bounds(cam.model.normalized_bounds()),
        use_bounds(cam.model.max_field_angle() < 0.5 * M_PI) {}
  inline bool MaySee(const Vec3& X, const Vec3& n) const {
    const Vec3 v = center - X;
    if (n.dot(v) <= 0.0) return false;
    const double d2 = v.squaredNorm();
    if (d2 < near2 * (1 - 1e-12) || d2 > far2 * (1 + 1e-12)) return false;
    if (!use_bounds) return true;
    const Vec3 p = cfw.linear() * X + cfw.translation();
    const double z = p.z();
    if (z <= 0.0) return false;
    // x / z within [bounds[0], bounds[1]] and y / z within [bounds[2], bounds[3]], for z > 0.
    return p.x() >= bounds[0] * z && p.x() <= bounds[1] * z && p.y() >= bounds[2] * z &&
           p.y() <= bounds[3] * z;
  }
  Vec3 center;
  Eigen::Isometry3d cfw;
  double near2, far2;
  Eigen::Vector4d bounds;
  bool use_bounds;
};

struct Buffers {
  std::vector<Vec3> normal;  // centre ray's facing normal (contours)
};

}  // namespace

Image RenderWithStats(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const RenderView& view, const RenderOptions& options, const Fields* fields,
                      RenderStats* stats, std::vector<Ray>* primary_out,
                      std::vector<Ray>* shadow_out) {
  const auto start = std::chrono::steady_clock::now();
  if (view.width <= 0 || view.height <= 0)
    throw InputError("--size", "", "the image size must be positive");
  if (view.camera >= int(rig.cameras.size()))
    throw InputError("--camera", "", "no camera " + std::to_string(view.camera) + " in the rig");
  if (view.camera < 0) {
    if (!(view.fov_deg > 0 && view.fov_deg < 180))
      throw InputError("--fov", "", "must be in (0, 180) degrees");
    if (!LookAt(view.from, view.at, view.up))
      throw InputError("--at", "", "'at' equals 'from', or 'up' is parallel to the viewing direction");
  }
  if (rig.cameras.size() > 64)
    throw InputError(scene.path, "$.rigs", "the renderer handles at most 64 cameras per rig");
  const int W = view.width, H = view.height;
  const int samples = std::max(1, options.samples);

  std::vector<int> triangle_object;
  const TriangleMesh mesh = scene.AllTriangles(&triangle_object);
  if (mesh.triangles.size() != caster.triangle_count())
    throw std::invalid_argument("Render: the ray caster was not built from scene.AllTriangles()");
  const std::vector<uint8_t> drawn_edges =
      options.surface == Surface::kHiddenLine ? DrawnEdges(mesh) : std::vector<uint8_t>();
  std::vector<Vec3> object_color(scene.objects.size(), Material().color);
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const int m = scene.objects[o].material;
    if (m >= 0 && m < int(scene.materials.size())) object_color[o] = scene.materials[m].color;
  }
  // Diffuse textures (PNG) of the objects whose mesh has texture coordinates, for kMaterial.
  std::vector<Image> textures;
  std::vector<int> object_texture(scene.objects.size(), -1);
  if (options.surface == Surface::kMaterial && !mesh.corner_uvs.empty())
    object_texture = LoadTextures(scene, &textures);

  const double brightness = std::isnan(options.brightness) ? DefaultBrightness(rig.enabled_count())
                                                          : options.brightness;
  const double scene_scale = std::max(scene.ContentBounds().diagonal(), 1e-9);
  const VisibilityTester tester(rig.cameras, caster, scene_scale);
  // Hit points are lifted off their surface by a tenth of the visibility epsilon along the facing
  // normal, so float round-off in the hit distance cannot make a surface shadow itself.
  const double lift = 0.1 * tester.epsilon();
  const ViewRays rays(view, rig);

  // Overlays from the fields.
  const OverlayOptions& ov = options.overlays;
  SliceImage slice;
  bool have_slice = false;
  std::unique_ptr<RayCaster> iso_caster;
  if (!ov.slice_field.empty() || !ov.iso_field.empty()) {
    if (!fields)
      throw InputError("--fields", "", "the slice and isosurface overlays need a fields file",
                       "run `pandora analyze` and pass its fields.vdb");
  }
  if (!ov.slice_field.empty()) {
    if (ov.slice_axis < 0 || ov.slice_axis > 2)
      throw InputError("--slice-axis", "", "must be x, y or z");
    slice = SampleSlice(*fields, ov.slice_field, ov.slice_axis, ov.slice_position);
    if (std::isfinite(ov.slice_min)) slice.min = ov.slice_min;
    if (std::isfinite(ov.slice_max)) slice.max = ov.slice_max;
    have_slice = true;
  }
  if (!ov.iso_field.empty()) {
    const TriangleMesh iso = ExtractIsosurface(*fields, ov.iso_field, ov.iso_value);
    if (!iso.triangles.empty()) iso_caster = MakeEmbreeRayCaster(iso);
  }
  const Vec3 iso_color = ov.iso_color;

  Image image;
  image.width = W;
  image.height = H;
  const std::size_t pixels = std::size_t(W) * H;
  image.rgb.assign(3 * pixels, 0.0f);
  image.coverage.assign(pixels, 0.0f);
  image.cameras.assign(pixels, 0);
  image.resolution.assign(pixels, 0.0f);
  image.sigma_max.assign(pixels, std::numeric_limits<float>::infinity());
  image.depth.assign(pixels, std::numeric_limits<float>::infinity());
  image.object.assign(pixels, -1);
  Buffers buffers;
  if (options.surface == Surface::kContours) buffers.normal.assign(pixels, Vec3::Zero());

  const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;
  const int tiles = tiles_x * tiles_y;
  const bool record = primary_out || shadow_out;
  std::vector<std::vector<Ray>> tile_primary(record ? tiles : 0), tile_shadow(record ? tiles : 0);
  std::vector<std::size_t> tile_primary_count(tiles, 0), tile_shadow_count(tiles, 0);
  const int camera_count = int(rig.cameras.size());
  std::vector<double> sigma_px(camera_count);
  for (int c = 0; c < camera_count; ++c)
    sigma_px[c] = rig.cameras[c].pixel_sigma > 0 ? rig.cameras[c].pixel_sigma : options.pixel_sigma;

  const bool need_jacobian = options.layers || options.pattern == Pattern::kGrid;
  const bool need_differentials =
      options.pattern == Pattern::kGrid || options.surface == Surface::kHiddenLine;
  const FrustumCuller culler(rig.cameras);
  std::vector<Cull> culls;
  for (const Camera& cam : rig.cameras) culls.emplace_back(cam);
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& r) {
    std::vector<Sample> s;
    std::vector<Ray> segments;
    std::vector<int> owner;
    std::vector<Mat23> jacobians;
    std::vector<uint8_t> occluded;
    std::vector<Ray> primary;
    std::vector<int> primary_owner;
    std::vector<std::optional<RayHit>> primary_hits;
    std::vector<double> resolution;        // per pixel of the tile (layers)
    std::vector<InformationBuilder> info;  // per pixel of the tile (layers)
    for (int tile = r.begin(); tile != r.end(); ++tile) {
      const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
      const int x1 = std::min(W, x0 + kTile), y1 = std::min(H, y0 + kTile);
      const int tw = x1 - x0;
      s.clear();
      if (options.layers) {
        resolution.assign(std::size_t(tw) * (y1 - y0), 0.0);
        info.assign(std::size_t(tw) * (y1 - y0), InformationBuilder());
      }
      // Samples: the centre ray of each pixel (layers; colour too when samples == 1), then the
      // stratified colour samples.
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          Sample c;
          c.pixel = (y - y0) * tw + (x - x0);
          c.px = x;
          c.py = y;
          c.layers = true;
          c.weight = samples == 1 ? 1.0 : 0.0;
          if (!rays.Center(x, y, &c.d, need_differentials ? &c.ddx : nullptr,
                           need_differentials ? &c.ddy : nullptr))
            c.d = Vec3::Zero();
          s.push_back(c);
          if (samples > 1)
            for (int j = 0; j < samples; ++j)
              for (int i = 0; i < samples; ++i) {
                Sample e = c;
                e.layers = false;
                e.weight = 1.0 / (samples * samples);
                e.px = x - 0.5 + (i + 0.5) / samples;
                e.py = y - 0.5 + (j + 0.5) / samples;
                if (c.d.squaredNorm() == 0 || !rays.Direction(e.px, e.py, &e.d)) e.d = Vec3::Zero();
                s.push_back(e);
              }
        }
      // Primary rays, a row of the tile at a time as packets.
      primary.clear();
      primary_owner.clear();
      for (int i = 0; i < int(s.size()); ++i) {
        if (s[i].d.squaredNorm() == 0) continue;
        primary.push_back(Ray{rays.eye(), s[i].d, 0.0, kInf});
        primary_owner.push_back(i);
      }
      primary_hits.resize(primary.size());
      caster.IntersectPacket(primary.data(), primary.size(), primary_hits.data());
      tile_primary_count[tile] += primary.size();
      if (record) tile_primary[tile].insert(tile_primary[tile].end(), primary.begin(), primary.end());
      for (std::size_t k = 0; k < primary.size(); ++k) {
        const auto& hit = primary_hits[k];
        if (!hit) continue;
        Sample& smp = s[primary_owner[k]];
        smp.hit = true;
        smp.t = hit->t;
        smp.triangle = hit->triangle;
        smp.n = hit->normal.dot(smp.d) > 0 ? Vec3(-hit->normal) : hit->normal;
        smp.X = rays.eye() + hit->t * smp.d;
      }
      // Whole tiles outside a camera's frustum or range skip it (FrustumCuller is conservative).
      Aabb tile_box;
      for (const Sample& smp : s)
        if (smp.hit) tile_box.Extend(smp.X);
      if (!tile_box.empty()) {
        tile_box.min.array() -= 2 * lift;
        tile_box.max.array() += 2 * lift;
      }
      // Per camera: the geometric tests, then the occlusion segments of the whole tile as packets.
      for (int c = 0; c < camera_count; ++c) {
        if (!rig.cameras[c].enabled || tile_box.empty()) continue;
        if (!culler.MayIntersect(c, tile_box)) continue;
        const Cull& cull = culls[c];
        segments.clear();
        owner.clear();
        jacobians.clear();
        for (int i = 0; i < int(s.size()); ++i) {
          if (!s[i].hit) continue;
          const Vec3 X = s[i].X + lift * s[i].n;
          if (!cull.MaySee(X, s[i].n)) continue;
          Ray seg;
          Mat23 J;
          if (tester.TestGeometry(c, X, &s[i].n, &seg, need_jacobian ? &J : nullptr) !=
              ViewResult::kSeen)
            continue;
          if (seg.t_far <= seg.t_near) seg.t_far = seg.t_near;  // at the centre: nothing between
          segments.push_back(seg);
          owner.push_back(i);
          jacobians.push_back(J);
        }
        if (segments.empty()) continue;
        occluded.resize(segments.size());
        caster.OccludedPacket(segments.data(), segments.size(), occluded.data());
        tile_shadow_count[tile] += segments.size();
        if (record)
          tile_shadow[tile].insert(tile_shadow[tile].end(), segments.begin(), segments.end());
        const Camera& cam = rig.cameras[c];
        for (std::size_t k = 0; k < segments.size(); ++k) {
          if (occluded[k] && segments[k].t_far > segments[k].t_near) continue;
          Sample& smp = s[owner[k]];
          const Mat23& J = jacobians[k];
          if (smp.layers) {
            smp.seen |= uint64_t(1) << c;
            if (options.layers) {
              resolution[smp.pixel] = std::max(resolution[smp.pixel], PixelDensity(J));
              info[smp.pixel].Add(J, sigma_px[c]);
            }
          }
          if (smp.weight == 0) continue;
          double w = 1.0;
          if (options.pattern == Pattern::kGrid) {
            const auto pixel = cam.Project(smp.X);
            // Derivative of the hit point per output pixel on the hit plane (ray differentials).
            const double nd = smp.n.dot(smp.d);
            const Vec3 dXdx = smp.t * (smp.ddx - (smp.n.dot(smp.ddx) / nd) * smp.d);
            const Vec3 dXdy = smp.t * (smp.ddy - (smp.n.dot(smp.ddy) / nd) * smp.d);
            const double gu = Eigen::Vector2d(J.row(0).dot(dXdx), J.row(0).dot(dXdy)).norm();
            const double gv = Eigen::Vector2d(J.row(1).dot(dXdx), J.row(1).dot(dXdy)).norm();
            const int n = std::max(1, options.grid_pixels);
            const double lu = pixel ? GridLine(pixel->x(), gu, n, options.line_width_px) : 0.0;
            const double lv = pixel ? GridLine(pixel->y(), gv, n, options.line_width_px) : 0.0;
            const double line = 1.0 - (1.0 - lu) * (1.0 - lv);
            w = options.grid_fill + (1.0 - options.grid_fill) * line;
          }
          smp.light += brightness * w * cam.color;
        }
      }
      // Shading and layers.
      for (Sample& smp : s) {
        const int x = x0 + smp.pixel % tw, y = y0 + smp.pixel / tw;
        const std::size_t p = std::size_t(y) * W + x;
        Vec3 color = smp.d.squaredNorm() == 0 ? Vec3::Zero() : options.background;
        if (smp.hit) {
          const int object = triangle_object[smp.triangle];
          switch (options.surface) {
            case Surface::kMaterial: {
              Vec3 albedo = object_color[object];
              if (object_texture[object] >= 0)  // colour times texture (OBJ Kd x map_Kd, glTF)
                albedo = albedo.cwiseProduct(
                    SampleTexture(textures[object_texture[object]], TextureCoordinate(mesh, smp.triangle, smp.X)));
              const double shade = 0.4 + 0.6 * std::abs(smp.n.dot(smp.d));
              color = albedo.cwiseProduct(smp.light) + options.ambient * shade * albedo;
              break;
            }
            default: color = smp.light; break;
          }
          if (options.surface == Surface::kHiddenLine && drawn_edges[smp.triangle]) {
            const auto& tri = mesh.triangles[smp.triangle];
            const Vec3 A = mesh.vertices[tri[0]], B = mesh.vertices[tri[1]], C = mesh.vertices[tri[2]];
            const Vec3 cr = (B - A).cross(C - A);
            const double area2 = cr.norm();
            if (area2 > 0) {
              const Vec3 nt = cr / area2;
              const double nd = smp.n.dot(smp.d);
              const Vec3 dXdx = smp.t * (smp.ddx - (smp.n.dot(smp.ddx) / nd) * smp.d);
              const Vec3 dXdy = smp.t * (smp.ddy - (smp.n.dot(smp.ddy) / nd) * smp.d);
              const Vec3 P[3] = {A, B, C};
              double a = 0;
              for (int i = 0; i < 3; ++i) {
                if (!(drawn_edges[smp.triangle] & (1u << i))) continue;
                const Vec3& E0 = P[(i + 1) % 3];
                const Vec3& E1 = P[(i + 2) % 3];
                const Vec3 grad = nt.cross(E1 - E0) / area2;  // gradient of barycentric i
                const double lambda = grad.dot(smp.X - E0);
                const double g = Eigen::Vector2d(grad.dot(dXdx), grad.dot(dXdy)).norm();
                if (g > 0) a = std::max(a, LineCoverage(std::abs(lambda) / g, options.line_width_px));
              }
              color = (1.0 - a) * color + a * Vec3::Constant(options.line_grey);
            }
          }
        }
        // Slice plane and isosurface in front of the surface, alpha-composited back to front.
        const double t_surface = smp.hit ? smp.t : kInf;
        if (smp.d.squaredNorm() > 0) {
          struct Layer {
            double t;
            Vec3 color;
            double alpha;
          };
          Layer layers[2];
          int nl = 0;
          if (have_slice && smp.d[slice.axis] != 0) {
            const double tp = (slice.position - rays.eye()[slice.axis]) / smp.d[slice.axis];
            if (tp > 0 && tp < t_surface) {
              const double v = slice.Sample(rays.eye() + tp * smp.d);
              if (std::isfinite(v)) {
                const double range = slice.max - slice.min;
                const double u = range > 0 ? (v - slice.min) / range : 0.5;
                layers[nl++] = {tp, ViridisLinear(u), ov.slice_opacity};
              }
            }
          }
          if (iso_caster) {
            const auto ih = iso_caster->Intersect(Ray{rays.eye(), smp.d, 0.0, t_surface});
            if (ih) {
              const double shade = 0.35 + 0.65 * std::abs(ih->normal.dot(smp.d));
              layers[nl++] = {ih->t, shade * iso_color, ov.iso_opacity};
            }
          }
          if (nl == 2 && layers[0].t < layers[1].t) std::swap(layers[0], layers[1]);
          for (int i = 0; i < nl; ++i)
            color = (1.0 - layers[i].alpha) * color + layers[i].alpha * layers[i].color;
        }
        if (smp.weight > 0)
          for (int k = 0; k < 3; ++k) image.rgb[3 * p + k] += float(smp.weight * color[k]);
        if (smp.layers && smp.hit) {
          image.depth[p] = float(smp.t);
          image.object[p] = triangle_object[smp.triangle];
          image.cameras[p] = smp.seen;
          image.coverage[p] = float(__builtin_popcountll(smp.seen));
          if (options.layers) image.resolution[p] = float(resolution[smp.pixel]);
          if (options.layers && info[smp.pixel].cameras() >= 2) {
            const InformationBuilder& b = info[smp.pixel];
            const StaticUncertainty u = StaticFromInformation(b.Decompose(), b.cameras());
            if (u.triangulable) image.sigma_max[p] = float(1e3 * u.sigma_max);
          }
          if (!buffers.normal.empty()) buffers.normal[p] = smp.n;
        }
      }
    }
  });

  // Contours: discontinuities of object, normal or depth between neighbouring centre rays; the
  // line is drawn on the nearer pixel (silhouettes) or on both (creases).
  if (options.surface == Surface::kContours) {
    std::vector<float> a(pixels, 0.0f);
    const double cos_crease = std::cos(30.0 * M_PI / 180.0);
    auto edge = [&](std::size_t p, std::size_t q, const Vec3& dq) {
      const bool hp = std::isfinite(image.depth[p]), hq = std::isfinite(image.depth[q]);
      if (!hp && !hq) return;
      if (hp != hq) {
        a[hp ? p : q] = 1.0f;
        return;
      }
      bool jump = image.object[p] != image.object[q];
      if (!jump) {
        // Depth the neighbour's ray would have on p's plane.
        const Vec3& n = buffers.normal[p];
        const double denom = n.dot(dq);
        if (denom != 0) {
          Vec3 dp;
          const int xp = int(p % W), yp = int(p / W);
          rays.Center(xp, yp, &dp, nullptr, nullptr);
          const double predicted = image.depth[p] * n.dot(dp) / denom;
          jump = !(predicted > 0) || std::abs(predicted - image.depth[q]) > 0.05 * image.depth[p];
        } else {
          jump = true;
        }
      }
      if (jump) {
        a[image.depth[p] <= image.depth[q] ? p : q] = 1.0f;
        return;
      }
      if (buffers.normal[p].dot(buffers.normal[q]) < cos_crease) {
        a[p] = std::max(a[p], 0.5f);
        a[q] = std::max(a[q], 0.5f);
      }
    };
    tbb::parallel_for(0, H, [&](int y) {
      for (int x = 0; x < W; ++x) {
        const std::size_t p = std::size_t(y) * W + x;
        Vec3 d;
        if (x + 1 < W && rays.Center(x + 1, y, &d, nullptr, nullptr)) edge(p, p + 1, d);
      }
    });
    // Vertical pairs write rows y and y + 1: even rows first, then odd ones, so no two tasks ever
    // write the same row at once.
    for (int parity = 0; parity < 2; ++parity)
      tbb::parallel_for(0, H / 2 + 1, [&](int half) {
        const int y = 2 * half + parity;
        if (y + 1 >= H) return;
        for (int x = 0; x < W; ++x) {
          const std::size_t p = std::size_t(y) * W + x;
          Vec3 d;
          if (rays.Center(x, y + 1, &d, nullptr, nullptr)) edge(p, p + W, d);
        }
      });
    for (std::size_t p = 0; p < pixels; ++p)
      for (int k = 0; k < 3; ++k)
        image.rgb[3 * p + k] = float((1.0 - a[p]) * image.rgb[3 * p + k] + a[p] * options.line_grey);
  }

  if (ov.cameras && rays.perspective()) DrawCameraOverlays(rig, rays.pinhole(), ov, options, &image);
  if (have_slice && ov.legend) DrawLegend(FieldUnitLabel(ov.slice_field), slice.min, slice.max, &image);
  if (ov.key) DrawKey(rig, &image);

  if (stats) {
    stats->primary_rays = 0;
    stats->shadow_rays = 0;
    for (int t = 0; t < tiles; ++t) {
      stats->primary_rays += tile_primary_count[t];
      stats->shadow_rays += tile_shadow_count[t];
    }
  }
  if (primary_out) {
    primary_out->clear();
    for (auto& v : tile_primary) primary_out->insert(primary_out->end(), v.begin(), v.end());
  }
  if (shadow_out) {
    shadow_out->clear();
    for (auto& v : tile_shadow) shadow_out->insert(shadow_out->end(), v.begin(), v.end());
  }
  if (stats)
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return image;
}

Image Render(const Scene& scene, const Rig& rig, const RayCaster& caster, const RenderView& view,
             const RenderOptions& options, const Fields* fields) {
  return RenderWithStats(scene, rig, caster, view, options, fields, nullptr);
}

}  // namespace pandora
