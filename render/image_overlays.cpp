// Image-space overlays of the renderer (render/image_overlays.h): camera bodies and frusta as
// antialiased, depth-tested wireframes, the slice legend and the colour key.
#include "render/image_overlays.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "render/colormap.h"

namespace pandora::internal {
namespace {

// Antialiased 3D line segments with hidden parts dimmed, composited so that each pixel shows the
// strongest line over it (the first drawn among equals). The lines touch few pixels, so they are
// kept as a list of (pixel, coverage, colour) rather than image-sized buffers.
class LineOverlay {
 public:
  LineOverlay(const Camera& view, const Image& image)
      : view_(view), cfw_(view.camera_from_world()), image_(image) {}

  // Segments drawn after this call use `color` (up to 65535 colours per overlay).
  std::size_t colors() const { return palette_.size(); }
  void SetColor(const Vec3& color) {
    palette_.push_back(color);
    current_ = uint16_t(palette_.size() - 1);
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
      if (p < 0)
        s0 = std::max(s0, r);
      else
        s1 = std::min(s1, r);
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
        if (depth > image_.depth[p] * (1.0 + 1e-3))
          cover *= 0.3;  // hidden behind the surface: dimmed
        touches_.push_back({p, cover, current_});
      }
    }
  }

  void CompositeInto(Image* image) {
    // Per pixel, in drawing order: a touch replaces the pixel's line when it covers more.
    std::stable_sort(touches_.begin(), touches_.end(),
                     [](const Touch& a, const Touch& b) { return a.pixel < b.pixel; });
    for (std::size_t i = 0; i < touches_.size();) {
      const std::size_t p = touches_[i].pixel;
      float alpha = 0.0f;
      uint16_t color = 0;
      for (; i < touches_.size() && touches_[i].pixel == p; ++i)
        if (touches_[i].cover > alpha) {
          alpha = float(touches_[i].cover);
          color = touches_[i].color;
        }
      const double a = alpha;
      if (a <= 0) continue;
      for (int k = 0; k < 3; ++k)
        image->rgb[3 * p + k] = float((1.0 - a) * image->rgb[3 * p + k] + a * palette_[color][k]);
    }
  }

 private:
  const Camera& view_;
  Eigen::Isometry3d cfw_;
  const Image& image_;
  struct Touch {
    std::size_t pixel;
    double cover;
    uint16_t color;
  };
  std::vector<Touch> touches_;
  std::vector<Vec3> palette_;
  uint16_t current_ = 0;
};

}  // namespace

// Each enabled camera: a small box body behind its centre and its frustum (the distorted image
// border unprojected) as a wireframe out to min(frustum_length, far).
void DrawCameraOverlays(const Rig& rig, const Camera& view, const OverlayOptions& ov,
                        const RenderOptions& options, Image* image) {
  LineOverlay lines(view, *image);
  const double width = std::max(1.0, options.line_width_px);
  for (const Camera& cam : rig.cameras) {
    if (!cam.enabled) continue;
    if (lines.colors() >= 65535) break;  // beyond 65535 cameras the rest are not drawn
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
  if (!ov.labels) return;
  // Ids beside the centres, over a dark backing (drawn last: always readable).
  const int scale = image->height >= 400 ? 2 : 1;
  const Eigen::Isometry3d cfw = view.camera_from_world();
  const Intrinsics& k = view.model.intrinsics();
  for (const Camera& cam : rig.cameras) {
    if (!cam.enabled) continue;
    const Vec3 c = cfw * cam.center();
    if (!(c.z() > 1e-3)) continue;
    const int px = int(std::lround(k.fx * c.x() / c.z() + k.cx));
    const int y = int(std::lround(k.fy * c.y() / c.z() + k.cy)) - 2 * scale;
    const std::string id = cam.id.substr(0, 16);
    const int w = TextWidth(id, scale);
    // Right of the centre, or left of it when that would leave the image.
    const int x = px + 4 * scale + w + scale <= image->width ? px + 4 * scale : px - 4 * scale - w;
    for (int yy = std::max(0, y - scale); yy < std::min(image->height, y + 6 * scale); ++yy)
      for (int xx = std::max(0, x - scale); xx < std::min(image->width, x + w + scale); ++xx)
        for (int ch = 0; ch < 3; ++ch)
          image->rgb[3 * (std::size_t(yy) * image->width + xx) + ch] *= 0.3f;
    DrawText(image->rgb.data(), image->width, image->height, x, y, id,
             cam.color.cwiseMax(Vec3::Constant(0.35)), scale);
  }
}

// Colour bar of the slice overlay with its range and the field's name, lower right corner.
void DrawLegend(const std::string& field, double vmin, double vmax, Image* image) {
  const int W = image->width, H = image->height;
  const int scale = H >= 400 ? 2 : 1;
  const int bar_h = std::max(20, H / 3), bar_w = 8 * scale;
  char top[32], bottom[32];
  std::snprintf(top, sizeof top, "%.3g", vmax);
  std::snprintf(bottom, sizeof bottom, "%.3g", vmin);
  const int text_w =
      std::max({TextWidth(top, scale), TextWidth(bottom, scale), TextWidth(field, scale)});
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
      for (int k = 0; k < 3; ++k)
        image->rgb[3 * (std::size_t(by + y) * W + bx + x) + k] = float(c[k]);
  }
  const Vec3 white = Vec3::Constant(0.9);
  DrawText(image->rgb.data(), W, H, x0 + margin, y0 + margin, field, white, scale);
  DrawText(image->rgb.data(), W, H, bx + bar_w + margin, by, top, white, scale);
  DrawText(image->rgb.data(), W, H, bx + bar_w + margin, by + bar_h - 5 * scale, bottom, white,
           scale);
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
  for (const Camera* c : cams)
    longest = std::max<std::size_t>(longest, std::min<std::size_t>(c->id.size(), 12));
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
    DrawText(image->rgb.data(), W, H, x + swatch + 3 * scale, y, cams[i]->id.substr(0, 12), text,
             scale);
  }
}

}  // namespace pandora::internal
