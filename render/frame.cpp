// The per-frame engine of the projective-light renderer (render/frame.h) and the prepared scene and
// overlays it reads (render/prepared_scene.h): primary rays through the ray caster, the visibility
// rules per camera (VisibilityTester), occlusion segments in packets per tile and pixel level, the
// light rule (render/light.h), shading and the image-space passes.
#include "render/frame.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <unordered_map>

#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/ptz.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "render/colormap.h"
#include "render/image_overlays.h"
#include "volume/active_set.h"

namespace pandora {
namespace internal {
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

constexpr double kInf = std::numeric_limits<double>::infinity();

// Primary rays of the view: a pinhole eye, or a rig camera's own lens (unprojected).
class ViewRays {
 public:
  // `table`: for a camera's-eye view, unproject every pixel's centre ray once up front (a frame);
  // otherwise each query unprojects (a single pick). Both give the same rays bit for bit.
  // `camera_t_near`: for a camera's-eye view, where its primary rays start, the fields' rule for
  // the same camera (VisibilityTester::Tolerance(camera, 0)): a surface through the camera centre
  // (a camera mounted on a wall's face) is behind it for the image as for the fields.
  ViewRays(const RenderView& view, const Rig& rig, bool table, double camera_t_near = 0.0)
      : width_(view.OutputWidth()), height_(view.OutputHeight()) {
    if (view.camera >= 0) {
      cam_ = &rig.cameras[view.camera];
      camera_t_near_ = camera_t_near;
      eye_ = cam_->center();
      R_ = cam_->world_from_camera.linear();
      sx_ = double(cam_->model.width()) / view.width;
      sy_ = double(cam_->model.height()) / view.height;
      if (!view.window.empty()) {
        ox_ = view.window.x;
        oy_ = view.window.y;
      }
      if (table) {
        const std::size_t n = std::size_t(width_) * height_;
        table_.resize(n);
        tbb::parallel_for(0, height_, [&](int y) {
          for (int x = 0; x < width_; ++x) table_[std::size_t(y) * width_ + x] = CameraEntry(x, y);
        });
      }
    } else {
      const auto pose = LookAt(view.from, view.at, view.up);
      eye_ = view.from;
      clip_near_ = view.clip_near;
      R_ = pose->linear();
      f_ = 0.5 * width_ / std::tan(0.5 * view.fov_deg * kPi / 180.0);
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
  // Where the primary ray along unit `d` starts: RenderView::clip_near along the optical axis.
  double NearT(const Vec3& d) const {
    if (cam_) return camera_t_near_;
    if (!(clip_near_ > 0)) return 0.0;
    const double c = d.dot(R_.col(2));
    return c > 0 ? clip_near_ / c : 0.0;
  }
  bool perspective() const { return cam_ == nullptr; }
  const Camera& pinhole() const { return pinhole_; }

  // Unit direction through output pixel coordinates (px, py); false outside the lens's domain.
  bool Direction(double px, double py, Vec3* d) const {
    if (!cam_) {
      *d = (R_ * Vec3((px - cx_) / f_, (py - cy_) / f_, 1.0)).normalized();
      return true;
    }
    const Vec2 pixel((px + ox_ + 0.5) * sx_ - 0.5, (py + oy_ + 0.5) * sy_ - 0.5);
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
    const Entry e = table_.empty() ? CameraEntry(x, y) : table_[std::size_t(y) * width_ + x];
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
  // Camera's-eye view: the centre ray of pixel (x, y) (one unprojection) and its exact per-pixel
  // differentials: the projection's Jacobian J at the unit direction has the ray in its null
  // space, so M = J^T (J J^T)^-1 is d(direction)/d(pixel), perpendicular to the direction.
  Entry CameraEntry(int x, int y) const {
    Entry e;
    const Vec2 pixel((x + ox_ + 0.5) * sx_ - 0.5, (y + oy_ + 0.5) * sy_ - 0.5);
    const auto dir = cam_->model.Unproject(pixel);
    if (!dir) return e;
    Mat23 J;
    if (!cam_->model.Project(*dir, &J)) return e;
    const Eigen::Matrix2d JJt = J * J.transpose();
    if (!(std::abs(JJt.determinant()) > 0)) return e;
    const Eigen::Matrix<double, 3, 2> M = J.transpose() * JJt.inverse();
    e.ok = true;
    e.d = R_ * *dir;
    e.dx = R_ * M.col(0) * sx_;
    e.dy = R_ * M.col(1) * sy_;
    return e;
  }

  int width_, height_;
  const Camera* cam_ = nullptr;
  Vec3 eye_;
  Mat3 R_;
  double clip_near_ = 0;
  double camera_t_near_ = 0;
  double f_ = 1, cx_ = 0, cy_ = 0;
  double sx_ = 1, sy_ = 1;
  int ox_ = 0, oy_ = 0;  // RenderView::window's corner
  std::vector<Entry> table_;
  Camera pinhole_;
};

// Cheap necessary conditions of VisibilityTester::TestGeometry's kSeen, tested first: the point
// faces the camera, lies within its working range, and (for lenses under 180 degrees) in front of
// it within the normalized-coordinate bounds of the whole (distorted) image. A point failing any of
// them would fail TestGeometry too, so skipping it changes no result, only the time.
struct Cull {
  explicit Cull(const Camera& cam)
      : center(cam.center()),
        cfw(cam.camera_from_world()),
        near2(cam.near * cam.near),
        far2(cam.far * cam.far),
        bounds(cam.model.normalized_bounds()),
        use_bounds(cam.model.max_field_angle() < 0.5 * kPi) {}
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

// What one sample (a ray through the pixel) found.
struct Sample {
  int pixel = 0;          // index in the tile
  int slot = -1;          // centre samples: index among the group's centre samples (layers)
  double px = 0, py = 0;  // output pixel coordinates
  bool layers = false;    // the pixel's centre ray: fills the layers
  double weight = 0;      // share of the pixel's colour
  bool hit = false;
  double t = kInf;
  int triangle = -1;
  Vec3 d, ddx, ddy;  // direction and its per-pixel derivatives
  Vec3 X, n;         // hit point and geometric normal facing the eye
  Vec3 light = Vec3::Zero();
  int seen = 0;       // cameras that see the point (centre samples)
  uint64_t mask = 0;  // bit c: camera c sees it (rigs of at most 64 cameras)
};

// A pixel of a tile, relative to its corner.
struct TilePixel {
  uint8_t x, y;
};
// The pixels of a kTile x kTile tile in Morton (Z) order: all of them, and those of each level.
// Consecutive entries form compact clusters (2 x 2, 4 x 2, 4 x 4, ...), so the rays that share a
// packet are coherent at every level.
struct TileOrderTables {
  std::vector<TilePixel> all;
  std::vector<TilePixel> level[kLevels];
};
const TileOrderTables& TileOrder() {
  static const TileOrderTables tables = [] {
    static_assert(kTile == 16, "the Morton order below covers 16 x 16 tiles");
    TileOrderTables t;
    for (int m = 0; m < kTile * kTile; ++m) {
      int x = 0, y = 0;
      for (int bit = 0; bit < 4; ++bit) {
        x |= ((m >> (2 * bit)) & 1) << bit;
        y |= ((m >> (2 * bit + 1)) & 1) << bit;
      }
      const TilePixel p{uint8_t(x), uint8_t(y)};
      t.all.push_back(p);
      t.level[PixelLevel(x, y)].push_back(p);
    }
    return t;
  }();
  return tables;
}

// The hit of ray (eye, d): the point and the geometric normal turned towards the eye.
inline void SetHit(const Vec3& eye, const RayHit& hit, const TriangleMesh& mesh, Sample* smp) {
  smp->hit = true;
  // The distance again in double from the hit triangle's plane: the caster's float distance errs
  // by about 2^-24 of it, which a far eye (a plan's, 500 scene sizes away) would turn into points
  // off their surface that shadow themselves.
  double t = hit.t;
  const double dn = hit.normal.dot(smp->d);
  if (hit.triangle >= 0 && std::size_t(hit.triangle) < mesh.triangles.size() &&
      std::abs(dn) > 1e-9) {
    const double plane_t =
        hit.normal.dot(mesh.vertices[mesh.triangles[hit.triangle][0]] - eye) / dn;
    if (std::abs(plane_t - t) <= 1e-5 * std::max(1.0, t)) t = plane_t;
  }
  smp->t = t;
  smp->triangle = hit.triangle;
  smp->n = hit.normal.dot(smp->d) > 0 ? Vec3(-hit.normal) : hit.normal;
  smp->X = eye + t * smp->d;
}

}  // namespace

void CheckView(const RenderView& view, const Rig& rig) {
  if (view.width <= 0 || view.height <= 0)
    throw InputError("{size}", "", "the image size must be positive");
  if (view.camera >= int(rig.cameras.size()))
    throw InputError("{camera}", "", "no camera " + std::to_string(view.camera) + " in the rig");
  if (!view.window.empty()) {  // set by code (pandora synth), never by a user: a caller's bug
    const RenderView::Window& w = view.window;
    if (view.camera < 0)
      throw std::invalid_argument("Render: a window is for a camera's-eye view only");
    if (w.x < 0 || w.y < 0 || w.x + w.width > view.width || w.y + w.height > view.height)
      throw std::invalid_argument("Render: the window must lie inside the image");
  }
  if (view.camera < 0) {
    if (!(view.fov_deg > 0 && view.fov_deg < 180))
      throw InputError("{fov_deg}", "", "must be in (0, 180) degrees");
    if (!LookAt(view.from, view.at, view.up))
      throw InputError("{at}", "",
                       "'at' equals 'from', or 'up' is parallel to the viewing direction");
  }
}

// ---------------------------------------------------------------------------------------------
// Prepared scene and overlays.

const std::vector<int>& PreparedSceneData::ObjectTextures() const {
  std::call_once(textures_once, [this] {
    object_texture.assign(object_material.size(), -1);
    if (!has_uvs) return;
    // Each textured material's PNG once. A texture that cannot be read (missing file, not a PNG)
    // leaves its objects their plain colour, with one warning line on stderr.
    std::vector<int> of_material(material_texture.size(), -1);
    for (std::size_t m = 0; m < material_texture.size(); ++m) {
      if (m < material_printed.size() && material_printed[m]) {  // reflectance, 255 = paper
        const PrintedPattern& print = *material_printed[m];
        Image tex;
        tex.width = print.width;
        tex.height = print.height;
        tex.rgb.resize(3 * print.grey.size());
        for (std::size_t i = 0; i < print.grey.size(); ++i)
          tex.rgb[3 * i] = tex.rgb[3 * i + 1] = tex.rgb[3 * i + 2] = print.grey[i] / 255.0f;
        textures.push_back(std::move(tex));
        of_material[m] = static_cast<int>(textures.size()) - 1;
        continue;
      }
      const std::string& path = material_texture[m];
      if (path.empty()) continue;
      std::string ext = std::filesystem::path(path).extension().string();
      for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      try {
        if (ext != ".png") throw std::runtime_error("only PNG textures are read");
        textures.push_back(ReadPng(path));
        of_material[m] = static_cast<int>(textures.size()) - 1;
      } catch (const std::exception& e) {
        std::fprintf(stderr,
                     "pandora: warning: texture %s not used (%s); the material colour stands in\n",
                     path.c_str(), e.what());
      }
    }
    for (std::size_t o = 0; o < object_material.size(); ++o) {
      const int m = object_material[o];
      if (m >= 0 && m < int(of_material.size()) && object_has_uvs[o])
        object_texture[o] = of_material[m];
    }
  });
  return object_texture;
}

const std::vector<uint8_t>& PreparedSceneData::DrawnEdges() const {
  std::call_once(edges_once, [this] { drawn_edges = pandora::ComputeDrawnEdges(mesh); });
  return drawn_edges;
}

namespace {

std::unique_ptr<PreparedSceneData> Prepare(const Scene& scene,
                                           std::shared_ptr<const RayCaster> owned,
                                           const RayCaster* caster) {
  auto d = std::make_unique<PreparedSceneData>();
  d->path = scene.path;
  d->mesh = scene.AllTriangles(&d->triangle_object);
  if (!caster) {
    owned = MakeEmbreeRayCaster(d->mesh);
    caster = owned.get();
  }
  if (d->mesh.triangles.size() != caster->triangle_count())
    throw std::invalid_argument(
        "PreparedScene: the ray caster was not built from scene.AllTriangles() (" +
        std::to_string(caster->triangle_count()) + " triangles, the scene has " +
        std::to_string(d->mesh.triangles.size()) + ")");
  d->owned = std::move(owned);
  d->caster = caster;
  d->object_color.assign(scene.objects.size(), Material().color);
  d->object_material.assign(scene.objects.size(), -1);
  d->object_has_uvs.assign(scene.objects.size(), false);
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const int m = scene.objects[o].material;
    d->object_material[o] = m;
    d->object_has_uvs[o] = !scene.objects[o].mesh.corner_uvs.empty();
    if (m >= 0 && m < int(scene.materials.size())) d->object_color[o] = scene.materials[m].color;
  }
  for (const Material& m : scene.materials) {
    d->material_texture.push_back(m.texture);
    d->material_printed.push_back(m.printed);
  }
  d->has_uvs = !d->mesh.corner_uvs.empty();
  d->scene_scale = std::max(scene.ContentBounds().diagonal(), 1e-9);
  return d;
}

}  // namespace
}  // namespace internal

PreparedScene::PreparedScene(const Scene& scene)
    : data_(internal::Prepare(scene, nullptr, nullptr)) {}
PreparedScene::PreparedScene(const Scene& scene, const RayCaster& caster)
    : data_(internal::Prepare(scene, nullptr, &caster)) {}
PreparedScene::PreparedScene(const Scene& scene, std::shared_ptr<const RayCaster> caster)
    : data_(internal::Prepare(
          scene, caster,
          caster ? caster.get() : throw std::invalid_argument("PreparedScene: null ray caster"))) {}
PreparedScene::~PreparedScene() = default;
PreparedScene::PreparedScene(PreparedScene&&) noexcept = default;
PreparedScene& PreparedScene::operator=(PreparedScene&&) noexcept = default;
const RayCaster& PreparedScene::caster() const { return *data_->caster; }

const std::vector<Image>& PreparedScene::Textures() const {
  data_->ObjectTextures();
  return data_->textures;
}

const std::vector<int>& PreparedScene::ObjectTextures() const { return data_->ObjectTextures(); }
std::size_t PreparedScene::triangle_count() const { return data_->mesh.triangles.size(); }
void PreparedScene::PrepareAll() const {
  data_->ObjectTextures();
  data_->DrawnEdges();
}

PreparedOverlays::PreparedOverlays(const Fields& fields, const OverlayOptions& ov)
    : data_(std::make_unique<internal::PreparedOverlaysData>()) {
  internal::PreparedOverlaysData& d = *data_;
  d.slice_field = ov.slice_field;
  d.slice_axis = ov.slice_axis;
  d.slice_position = ov.slice_position;
  d.iso_field = ov.iso_field;
  d.iso_value = ov.iso_value;
  if (!ov.slice_field.empty()) {
    if (ov.slice_axis < 0 || ov.slice_axis > 2)
      throw InputError("{slice_axis}", "", "must be x, y or z");
    d.slice = SampleSlice(fields, ov.slice_field, ov.slice_axis, ov.slice_position, &d.slice_plane);
    d.have_slice = true;
  }
  if (!ov.iso_field.empty()) {
    const TriangleMesh iso = ExtractIsosurface(fields, ov.iso_field, ov.iso_value);
    if (!iso.triangles.empty()) d.iso_caster = MakeEmbreeRayCaster(iso);
  }
}
PreparedOverlays::~PreparedOverlays() = default;
PreparedOverlays::PreparedOverlays(PreparedOverlays&&) noexcept = default;
PreparedOverlays& PreparedOverlays::operator=(PreparedOverlays&&) noexcept = default;

bool PreparedOverlays::Matches(const OverlayOptions& ov) const {
  const internal::PreparedOverlaysData& d = *data_;
  if (ov.slice_field != d.slice_field || ov.iso_field != d.iso_field) return false;
  if (!ov.slice_field.empty()) {
    if (ov.slice_axis != d.slice_axis) return false;
    const bool same_position = (std::isnan(ov.slice_position) && std::isnan(d.slice_position)) ||
                               ov.slice_position == d.slice_position;
    if (!same_position) return false;
  }
  if (!ov.iso_field.empty() && ov.iso_value != d.iso_value) return false;
  return true;
}

namespace internal {

// ---------------------------------------------------------------------------------------------
// The frame.

struct GroupScratch {
  std::vector<Sample> s;
  std::vector<Ray> segments;
  std::vector<int> owner;
  std::vector<Mat23> jacobians;
  std::vector<uint8_t> occluded;
  std::vector<double> shade;  // per segment: the light's factor (PTZ traces: later seconds darker)
  std::vector<Ray> primary;
  std::vector<int> primary_owner;
  std::vector<std::optional<RayHit>> primary_hits;
  std::vector<double> resolution;        // per centre sample (layers)
  std::vector<InformationBuilder> info;  // per centre sample (layers)
};
void DeleteScratch(GroupScratch* scratch) { delete scratch; }
std::unique_ptr<GroupScratch, ScratchDeleter> MakeScratch() {
  return std::unique_ptr<GroupScratch, ScratchDeleter>(new GroupScratch());
}

struct FrameRenderer::Impl {
  Impl(const PreparedSceneData& scene, const Rig& rig, const RenderView& view,
       const RenderOptions& options, const PreparedOverlaysData* overlays, bool table)
      : scene(scene),
        rig(rig),
        options(options),
        overlays(overlays),
        tester(rig.cameras, *scene.caster, scene.scene_scale),
        rays(view, rig, table, view.camera >= 0 ? tester.Tolerance(view.camera, 0.0) : 0.0),
        culler(rig.cameras) {}

  const PreparedSceneData& scene;
  const Rig& rig;
  const RenderOptions options;
  const PreparedOverlaysData* overlays;  // null when no overlay
  const VisibilityTester tester;
  const ViewRays rays;
  const FrustumCuller culler;
  std::vector<Cull> culls;
  std::vector<double> sigma_px;
  LightRule rule;
  int samples = 1;
  double lift = 0;
  bool need_jacobian = false, need_differentials = false;
  bool mask = true;  // fill Image::cameras (rigs of at most 64 cameras)
  bool have_slice = false;
  double slice_min = 0, slice_max = 0;
  const RayCaster* iso_caster = nullptr;
  // PTZ "all" traces: per rig camera its reach (null for an ordinary light) and budget.
  std::vector<std::unique_ptr<PtzReach>> reach;
  std::vector<double> reach_budget;
  const std::vector<int>* object_texture = nullptr;
  const std::vector<uint8_t>* drawn_edges = nullptr;

  // The steps of RenderGroup (frame.h).
  int GroupSamples(int level, int x0, int y0, int x1, int y1, GroupScratch* scratch) const;
  void TracePrimary(GroupScratch* scratch, TileRecord* record, bool record_rays) const;
  void CameraSegments(int c, const PtzReach* reach, GroupScratch* scratch) const;
  void ApplyCameraLight(int c, const PtzReach* reach, GroupScratch* scratch) const;
  Vec3 SurfaceColor(const Sample& smp, Vec3 color) const;
  Vec3 OverlayColor(const Sample& smp, const FieldSlice* slice, double slice_plane,
                    Vec3 color) const;
  void StoreLayers(const Sample& smp, std::size_t p, const GroupScratch& scratch,
                   FrameBuffers* out) const;
};

FrameRenderer::FrameRenderer(const PreparedScene& prepared, const Rig& rig, const RenderView& view,
                             const RenderOptions& options, const PreparedOverlays* overlays) {
  CheckView(view, rig);
  options.Check();
  const OverlayOptions& ov = options.overlays;
  const bool want_overlays = !ov.slice_field.empty() || !ov.iso_field.empty();
  if (want_overlays && !overlays)
    throw InputError("{fields}", "", "the slice and isosurface overlays need a fields file",
                     "run `pandora analyze` and pass its fields.vdb");
  if (want_overlays && !overlays->Matches(ov))
    throw std::invalid_argument(
        "Render: the prepared overlays were made for another slice or isosurface than "
        "options.overlays asks for; prepare them again (PreparedOverlays)");
  width_ = view.OutputWidth();
  height_ = view.OutputHeight();
  tiles_x_ = (width_ + kTile - 1) / kTile;
  tiles_y_ = (height_ + kTile - 1) / kTile;
  const PreparedSceneData& scene = prepared.data();
  impl_ =
      std::make_unique<Impl>(scene, rig, view, options, want_overlays ? &overlays->data() : nullptr,
                             /*table=*/true);
  Impl& m = *impl_;
  m.samples = std::max(1, options.samples);
  m.rule.pattern = options.pattern;
  m.rule.brightness =
      std::isnan(options.brightness) ? DefaultBrightness(rig.enabled_count()) : options.brightness;
  m.rule.grid_pixels = options.grid_pixels;
  m.rule.grid_fill = options.grid_fill;
  m.rule.line_width_px = options.line_width_px;
  // Hit points are lifted off their surface by a tenth of the visibility epsilon along the facing
  // normal, so float round-off in the hit distance cannot make a surface shadow itself.
  m.lift = 0.1 * m.tester.epsilon();
  m.need_jacobian = options.layers || options.pattern == Pattern::kGrid;
  m.need_differentials =
      options.pattern == Pattern::kGrid || options.surface == Surface::kHiddenLine;
  m.mask = int(rig.cameras.size()) <= Image::kMaxMaskCameras;
  const int camera_count = int(rig.cameras.size());
  m.sigma_px.resize(camera_count);
  for (int c = 0; c < camera_count; ++c)
    m.sigma_px[c] =
        rig.cameras[c].pixel_sigma > 0 ? rig.cameras[c].pixel_sigma : options.pixel_sigma;
  m.culls.reserve(camera_count);
  for (const Camera& cam : rig.cameras) m.culls.emplace_back(cam);
  m.reach.resize(camera_count);
  m.reach_budget.assign(camera_count, 0.0);
  for (const RenderOptions::PtzTrace& t : options.ptz_all) {
    if (t.camera < 0 || t.camera >= camera_count || !rig.cameras[t.camera].ptz)
      throw std::invalid_argument("Render: a PTZ trace names a camera without a PTZ head");
    const Camera& cam = rig.cameras[t.camera];
    m.reach[t.camera] = std::make_unique<PtzReach>(cam, *cam.ptz, cam.ptz->Home());
    m.reach_budget[t.camera] = std::max(0.0, t.budget_s);
  }
  if (m.overlays) {
    m.have_slice = m.overlays->have_slice;
    m.slice_min = std::isfinite(ov.slice_min) ? ov.slice_min : m.overlays->slice.min;
    m.slice_max = std::isfinite(ov.slice_max) ? ov.slice_max : m.overlays->slice.max;
    m.iso_caster = m.overlays->iso_caster.get();
  }
  // Diffuse textures (PNG) of the objects whose mesh has texture coordinates, for kMaterial.
  if (options.surface == Surface::kMaterial) m.object_texture = &scene.ObjectTextures();
  if (options.surface == Surface::kHiddenLine) m.drawn_edges = &scene.DrawnEdges();
}

FrameRenderer::~FrameRenderer() = default;

int FrameRenderer::GroupPixels(int tile, int level) const {
  const int x0 = (tile % tiles_x_) * kTile, y0 = (tile / tiles_x_) * kTile;
  const int x1 = std::min(width_, x0 + kTile), y1 = std::min(height_, y0 + kTile);
  // Pixels of the tile whose x and y are multiples of b, for b = 8 >> level.
  auto lattice = [&](int b) {
    return ((x1 + b - 1) / b - (x0 + b - 1) / b) * ((y1 + b - 1) / b - (y0 + b - 1) / b);
  };
  // Level l holds the pixels of lattice 8 >> l that are not on the coarser lattice 16 >> l.
  return lattice(8 >> level) - (level == 0 ? 0 : lattice(16 >> level));
}

FrameBuffers FrameRenderer::Allocate() const {
  FrameBuffers b;
  Reset(&b);
  return b;
}

void FrameRenderer::Reset(FrameBuffers* b) const {
  Image& image = b->image;
  image.width = width_;
  image.height = height_;
  const std::size_t pixels = std::size_t(width_) * height_;
  // Every group writes every value of its pixels, so buffers of the right size need no clearing.
  const bool same = image.rgb.size() == 3 * pixels &&
                    image.cameras.size() == (impl_->mask ? pixels : 0) &&
                    b->normal.size() == (impl_->options.surface == Surface::kContours ? pixels : 0);
  if (same) return;
  image.rgb.assign(3 * pixels, 0.0f);
  image.coverage.assign(pixels, 0.0f);
  if (impl_->mask)
    image.cameras.assign(pixels, 0);
  else
    image.cameras.clear();
  image.resolution.assign(pixels, 0.0f);
  image.sigma_max.assign(pixels, std::numeric_limits<float>::infinity());
  image.depth.assign(pixels, std::numeric_limits<float>::infinity());
  image.object.assign(pixels, -1);
  if (impl_->options.surface == Surface::kContours)
    b->normal.assign(pixels, Vec3::Zero());
  else
    b->normal.clear();
}

// The samples of group `level` of the tile with pixels [x0, x1) x [y0, y1), in tile order, into
// scratch->s; returns the number of centre samples.
int FrameRenderer::Impl::GroupSamples(int level, int x0, int y0, int x1, int y1,
                                      GroupScratch* scratch) const {
  const Impl& m = *this;
  const int tw = x1 - x0;
  // At the last level with several samples per pixel, the stratified colour samples of every
  // pixel of the tile are traced; the coarser levels' centre samples give a preview colour.
  const bool last = level == kLevels - 1;
  const bool stratified = samples > 1 && last;
  std::vector<Sample>& s = scratch->s;
  s.clear();
  int centres = 0;
  for (const TilePixel& t : stratified ? TileOrder().all : TileOrder().level[level]) {
    const int x = x0 + t.x, y = y0 + t.y;
    if (x >= x1 || y >= y1) continue;  // a partial tile at the image's edge
    const bool centre = !stratified || PixelLevel(x, y) == level;
    Sample c;
    c.pixel = (y - y0) * tw + (x - x0);
    c.px = x;
    c.py = y;
    c.layers = true;
    c.weight = samples == 1 || !last ? 1.0 : 0.0;
    if (!rays.Center(x, y, &c.d, m.need_differentials ? &c.ddx : nullptr,
                     m.need_differentials ? &c.ddy : nullptr))
      c.d = Vec3::Zero();
    if (centre) {
      c.slot = centres++;
      s.push_back(c);
    }
    if (stratified)
      for (int j = 0; j < samples; ++j)
        for (int i = 0; i < samples; ++i) {
          Sample e = c;
          e.layers = false;
          e.slot = -1;
          e.weight = 1.0 / (samples * samples);
          e.px = x - 0.5 + (i + 0.5) / samples;
          e.py = y - 0.5 + (j + 0.5) / samples;
          if (c.d.squaredNorm() == 0 || !rays.Direction(e.px, e.py, &e.d)) e.d = Vec3::Zero();
          s.push_back(e);
        }
  }
  return centres;
}

// Traces the group's primary rays and sets the samples' hits.
void FrameRenderer::Impl::TracePrimary(GroupScratch* scratch, TileRecord* record,
                                       bool record_rays) const {
  std::vector<Sample>& s = scratch->s;
  const RayCaster& caster = *scene.caster;
  // Primary rays, in sample order (Morton order: compact clusters per packet).
  std::vector<Ray>& primary = scratch->primary;
  std::vector<int>& primary_owner = scratch->primary_owner;
  std::vector<std::optional<RayHit>>& primary_hits = scratch->primary_hits;
  primary.clear();
  primary_owner.clear();
  for (int i = 0; i < int(s.size()); ++i) {
    if (s[i].d.squaredNorm() == 0) continue;
    // A cut view's ray starts on the cut plane itself (origin moved there in double), not at the
    // eye with tnear: Embree's float origin and t at an eye kilometres away (a plan's) would pick
    // the wrong one of two triangles a fraction of a millimetre apart. SetHit recomputes the hit
    // from the eye in double either way.
    const double t0 = rays.NearT(s[i].d);
    primary.push_back(Ray{Vec3(rays.eye() + t0 * s[i].d), s[i].d, 0.0, kInf});
    primary_owner.push_back(i);
  }
  primary_hits.resize(primary.size());
  caster.IntersectPacket(primary.data(), primary.size(), primary_hits.data());
  if (record) {
    record->primary += primary.size();
    if (record_rays)
      record->primary_rays.insert(record->primary_rays.end(), primary.begin(), primary.end());
  }
  for (std::size_t k = 0; k < primary.size(); ++k)
    if (primary_hits[k]) {
      RayHit h = *primary_hits[k];
      h.t += rays.NearT(s[primary_owner[k]].d);  // from the eye
      SetHit(rays.eye(), h, scene.mesh, &s[primary_owner[k]]);
    }
}

// Camera c's occlusion segments to the group's hit points that pass its geometric tests, with
// their samples (owner), projection Jacobians and light factors (shade).
void FrameRenderer::Impl::CameraSegments(int c, const PtzReach* reach,
                                         GroupScratch* scratch) const {
  const Impl& m = *this;
  std::vector<Sample>& s = scratch->s;
  std::vector<Ray>& segments = scratch->segments;
  std::vector<int>& owner = scratch->owner;
  std::vector<Mat23>& jacobians = scratch->jacobians;
  std::vector<double>& shade = scratch->shade;
  const Cull& cull = m.culls[c];
  segments.clear();
  owner.clear();
  jacobians.clear();
  shade.clear();
  for (int i = 0; i < int(s.size()); ++i) {
    if (!s[i].hit) continue;
    const Vec3 X = s[i].X + m.lift * s[i].n;
    Ray seg;
    Mat23 J;
    if (reach) {
      // The first whole second (0 = from home) from which a reachable setting sees X.
      const double budget = m.reach_budget[c];
      const int seconds = std::max(1, static_cast<int>(std::ceil(budget - 1e-9)));
      int k = 0;
      while (k <= seconds && !reach->Reachable(X, std::min<double>(k, budget), &s[i].n, &seg)) ++k;
      if (k > seconds) continue;  // not reachable within the budget
      const double tol = m.tester.Tolerance(c, seg.t_far);
      seg.t_near = tol;
      seg.t_far = std::max(tol, seg.t_far - tol);
      if (m.need_jacobian) {
        const std::optional<PtzState> pose = reach->BestPose(X, std::min<double>(k, budget));
        const Camera at = rig.cameras[c].ptz->CameraAt(rig.cameras[c], *pose);
        if (!at.Project(X, &J)) J.setZero();
      }
      shade.push_back(1.0 - 0.6 * k / seconds);
    } else {
      if (!cull.MaySee(X, s[i].n)) continue;
      if (m.tester.TestGeometry(c, X, &s[i].n, &seg, m.need_jacobian ? &J : nullptr) !=
          ViewResult::kSeen)
        continue;
      shade.push_back(1.0);
    }
    if (seg.t_far <= seg.t_near) seg.t_far = seg.t_near;  // at the centre: nothing between
    segments.push_back(seg);
    owner.push_back(i);
    jacobians.push_back(J);
  }
}

// Camera c's light rule term (and layers) for each sample whose segment is not occluded.
void FrameRenderer::Impl::ApplyCameraLight(int c, const PtzReach* reach,
                                           GroupScratch* scratch) const {
  const Impl& m = *this;
  std::vector<Sample>& s = scratch->s;
  const std::vector<Ray>& segments = scratch->segments;
  const std::vector<int>& owner = scratch->owner;
  const std::vector<Mat23>& jacobians = scratch->jacobians;
  const std::vector<uint8_t>& occluded = scratch->occluded;
  const std::vector<double>& shade = scratch->shade;
  std::vector<double>& resolution = scratch->resolution;
  std::vector<InformationBuilder>& info = scratch->info;
  const Camera& cam = rig.cameras[c];
  for (std::size_t k = 0; k < segments.size(); ++k) {
    if (occluded[k] && segments[k].t_far > segments[k].t_near) continue;
    Sample& smp = s[owner[k]];
    const Mat23& J = jacobians[k];
    if (smp.layers) {
      ++smp.seen;
      if (m.mask) smp.mask |= uint64_t(1) << c;
      if (options.layers) {
        resolution[smp.slot] = std::max(resolution[smp.slot], PixelDensity(J));
        info[smp.slot].Add(J, m.sigma_px[c]);
      }
    }
    if (smp.weight == 0) continue;
    CameraAtPoint at;
    at.sees = true;
    at.color = shade[k] * cam.color;
    if (options.pattern == Pattern::kGrid && !reach) {
      const auto pixel = cam.Project(smp.X);
      // Derivative of the hit point per output pixel on the hit plane (ray differentials), and
      // of the camera's pixel coordinates through the projection Jacobian.
      const double nd = smp.n.dot(smp.d);
      const Vec3 dXdx = smp.t * (smp.ddx - (smp.n.dot(smp.ddx) / nd) * smp.d);
      const Vec3 dXdy = smp.t * (smp.ddy - (smp.n.dot(smp.ddy) / nd) * smp.d);
      at.du = Eigen::Vector2d(J.row(0).dot(dXdx), J.row(0).dot(dXdy)).norm();
      at.dv = Eigen::Vector2d(J.row(1).dot(dXdx), J.row(1).dot(dXdy)).norm();
      at.projects = pixel.has_value();
      if (pixel) {
        at.u = pixel->x();
        at.v = pixel->y();
      }
    }
    smp.light += CameraLight(m.rule, at);
  }
}

// The colour of a sample's hit surface (`color`: the background), with the drawn edges of
// Surface::kHiddenLine over it.
Vec3 FrameRenderer::Impl::SurfaceColor(const Sample& smp, Vec3 color) const {
  const Impl& m = *this;
  const int object = scene.triangle_object[smp.triangle];
  switch (options.surface) {
    case Surface::kMaterial: {
      Vec3 albedo = scene.object_color[object];
      const std::vector<int>& object_texture = *m.object_texture;
      if (object_texture[object] >= 0)  // colour times texture (OBJ Kd x map_Kd, glTF)
        albedo =
            albedo.cwiseProduct(SampleTexture(scene.textures[object_texture[object]],
                                              TextureCoordinate(scene.mesh, smp.triangle, smp.X)));
      color = MaterialColor(albedo, smp.light, options.ambient, smp.n.dot(smp.d));
      break;
    }
    default:
      color = smp.light;
      break;
  }
  if (m.drawn_edges && (*m.drawn_edges)[smp.triangle]) {
    const uint8_t drawn = (*m.drawn_edges)[smp.triangle];
    const auto& tri = scene.mesh.triangles[smp.triangle];
    const Vec3 A = scene.mesh.vertices[tri[0]], B = scene.mesh.vertices[tri[1]],
               C = scene.mesh.vertices[tri[2]];
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
        if (!(drawn & (1u << i))) continue;
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
  return color;
}

// `color` with the slice plane and isosurface in front of the surface, alpha-composited back to
// front.
Vec3 FrameRenderer::Impl::OverlayColor(const Sample& smp, const FieldSlice* slice,
                                       double slice_plane, Vec3 color) const {
  const Impl& m = *this;
  const OverlayOptions& ov = options.overlays;
  const double t_surface = smp.hit ? smp.t : kInf;
  if (smp.d.squaredNorm() > 0) {
    struct Layer {
      double t;
      Vec3 color;
      double alpha;
    };
    Layer layers[2];
    int nl = 0;
    if (slice && smp.d[slice->axis] != 0) {
      const double tp = (slice_plane - rays.eye()[slice->axis]) / smp.d[slice->axis];
      if (tp > 0 && tp < t_surface) {
        const double v = slice->Sample(rays.eye() + tp * smp.d);
        if (std::isfinite(v)) {
          const double range = m.slice_max - m.slice_min;
          const double u = range > 0 ? (v - m.slice_min) / range : 0.5;
          layers[nl++] = {tp, ViridisLinear(u), ov.slice_opacity};
        }
      }
    }
    if (m.iso_caster) {
      const auto ih = m.iso_caster->Intersect(Ray{rays.eye(), smp.d, 0.0, t_surface});
      if (ih) {
        const double shade = 0.35 + 0.65 * std::abs(ih->normal.dot(smp.d));
        layers[nl++] = {ih->t, shade * ov.iso_color, ov.iso_opacity};
      }
    }
    if (nl == 2 && layers[0].t < layers[1].t) std::swap(layers[0], layers[1]);
    for (int i = 0; i < nl; ++i)
      color = (1.0 - layers[i].alpha) * color + layers[i].alpha * layers[i].color;
  }
  return color;
}

// Every layer of a centre sample's pixel `p`, also where nothing is hit.
void FrameRenderer::Impl::StoreLayers(const Sample& smp, std::size_t p, const GroupScratch& scratch,
                                      FrameBuffers* out) const {
  const Impl& m = *this;
  Image& image = out->image;
  const std::vector<double>& resolution = scratch.resolution;
  const std::vector<InformationBuilder>& info = scratch.info;
  image.depth[p] = smp.hit ? float(smp.t) : std::numeric_limits<float>::infinity();
  image.object[p] = smp.hit ? scene.triangle_object[smp.triangle] : -1;
  if (m.mask) image.cameras[p] = smp.mask;
  image.coverage[p] = float(smp.seen);
  image.resolution[p] = options.layers ? float(resolution[smp.slot]) : 0.0f;
  float sigma = std::numeric_limits<float>::infinity();
  if (options.layers && info[smp.slot].cameras() >= 2) {
    const InformationBuilder& b = info[smp.slot];
    const StaticUncertainty u = StaticFromInformation(b.Decompose(), b.cameras());
    if (u.triangulable) sigma = float(1e3 * u.sigma_max);
  }
  image.sigma_max[p] = sigma;
  if (!out->normal.empty()) out->normal[p] = smp.hit ? smp.n : Vec3::Zero();
}

void FrameRenderer::RenderGroup(int tile, int level, FrameBuffers* out, GroupScratch* scratch,
                                TileRecord* record, bool record_rays) const {
  const Impl& m = *impl_;
  const RenderOptions& options = m.options;
  const Rig& rig = m.rig;
  const PreparedSceneData& scene = m.scene;
  const RayCaster& caster = *scene.caster;
  const int W = width_;
  const int x0 = (tile % tiles_x_) * kTile, y0 = (tile / tiles_x_) * kTile;
  const int x1 = std::min(W, x0 + kTile), y1 = std::min(height_, y0 + kTile);
  const int tw = x1 - x0;
  const int centres = m.GroupSamples(level, x0, y0, x1, y1, scratch);
  std::vector<Sample>& s = scratch->s;
  if (s.empty()) return;
  std::vector<double>& resolution = scratch->resolution;
  std::vector<InformationBuilder>& info = scratch->info;
  if (options.layers) {
    resolution.assign(centres, 0.0);
    info.assign(centres, InformationBuilder());
  }
  // Primary rays, in sample order (Morton order: compact clusters per packet).
  m.TracePrimary(scratch, record, record_rays);
  // Cameras that cannot see any of the group's hit points skip it (FrustumCuller is conservative).
  Aabb box;
  for (const Sample& smp : s)
    if (smp.hit) box.Extend(smp.X);
  if (!box.empty()) {
    box.min.array() -= 2 * m.lift;
    box.max.array() += 2 * m.lift;
  }
  // Per camera, in rig order: the geometric tests, then the occlusion segments of the whole group
  // as packets, then the light rule's term for each sample that camera sees.
  std::vector<Ray>& segments = scratch->segments;
  std::vector<uint8_t>& occluded = scratch->occluded;
  const int camera_count = int(rig.cameras.size());
  for (int c = 0; c < camera_count && !box.empty(); ++c) {
    if (!rig.cameras[c].enabled) continue;
    const PtzReach* reach = m.reach[c].get();
    if (!reach && !m.culler.MayIntersect(c, box)) continue;
    m.CameraSegments(c, reach, scratch);
    if (segments.empty()) continue;
    occluded.resize(segments.size());
    caster.OccludedPacket(segments.data(), segments.size(), occluded.data());
    if (record) {
      record->shadow += segments.size();
      if (record_rays)
        record->shadow_rays.insert(record->shadow_rays.end(), segments.begin(), segments.end());
    }
    m.ApplyCameraLight(c, reach, scratch);
  }
  // Shading, overlays in front of the surface, and the layers.
  // A pixel's samples are consecutive: its colour is summed in `sum` and stored when the next
  // pixel's samples begin.
  Image& image = out->image;
  int summing = -1;  // tile pixel being summed
  float sum[3] = {0, 0, 0};
  auto store = [&] {
    if (summing < 0) return;
    const std::size_t q = std::size_t(y0 + summing / tw) * W + (x0 + summing % tw);
    for (int k = 0; k < 3; ++k) image.rgb[3 * q + k] = sum[k];
  };
  const FieldSlice* slice = m.have_slice ? &m.overlays->slice : nullptr;
  const double slice_plane = m.have_slice ? m.overlays->slice_plane : 0.0;
  for (Sample& smp : s) {
    const int x = x0 + smp.pixel % tw, y = y0 + smp.pixel / tw;
    const std::size_t p = std::size_t(y) * W + x;
    Vec3 color = smp.d.squaredNorm() == 0 ? Vec3::Zero() : options.background;
    if (smp.hit) color = m.SurfaceColor(smp, color);
    // Slice plane and isosurface in front of the surface, alpha-composited back to front.
    color = m.OverlayColor(smp, slice, slice_plane, color);
    if (smp.weight > 0) {
      if (smp.pixel != summing) {
        store();
        summing = smp.pixel;
        sum[0] = sum[1] = sum[2] = 0.0f;
      }
      for (int k = 0; k < 3; ++k) sum[k] += float(smp.weight * color[k]);
    }
    // Every layer of the pixel, also where nothing is hit.
    if (smp.layers) m.StoreLayers(smp, p, *scratch, out);
  }
  store();
}

void FrameRenderer::Finish(FrameBuffers* frame) const {
  const Impl& m = *impl_;
  const RenderOptions& options = m.options;
  const ViewRays& rays = m.rays;
  Image& image = frame->image;
  const int W = width_, H = height_;
  const std::size_t pixels = std::size_t(W) * H;
  // Contours: discontinuities of object, normal or depth between neighbouring centre rays; the
  // line is drawn on the nearer pixel (silhouettes) or on both (creases).
  if (options.surface == Surface::kContours) {
    const std::vector<Vec3>& normal = frame->normal;
    std::vector<float> a(pixels, 0.0f);
    const double cos_crease = std::cos(30.0 * kPi / 180.0);
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
        const Vec3& n = normal[p];
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
      if (normal[p].dot(normal[q]) < cos_crease) {
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
        image.rgb[3 * p + k] =
            float((1.0 - a[p]) * image.rgb[3 * p + k] + a[p] * options.line_grey);
  }
  const OverlayOptions& ov = options.overlays;
  if (ov.cameras && rays.perspective())
    DrawCameraOverlays(m.rig, rays.pinhole(), ov, options, &image);
  if (m.have_slice && ov.legend)
    DrawLegend(FieldUnitLabel(ov.slice_field), m.slice_min, m.slice_max, &image);
  if (ov.key) DrawKey(m.rig, &image);
}

}  // namespace internal

struct PixelPicker::Impl {
  Impl(const internal::PreparedSceneData& scene, const Rig& rig, const RenderView& view)
      : scene(scene),
        rig(rig),
        width(view.OutputWidth()),
        height(view.OutputHeight()),
        tester(rig.cameras, *scene.caster, scene.scene_scale),
        rays(view, rig, /*table=*/false,
             view.camera >= 0 ? tester.Tolerance(view.camera, 0.0) : 0.0) {}
  const internal::PreparedSceneData& scene;
  const Rig& rig;
  int width, height;
  const VisibilityTester tester;  // before rays: their camera start comes from it
  const internal::ViewRays rays;
};

PixelPicker::PixelPicker(const PreparedScene& scene, const Rig& rig, const RenderView& view) {
  internal::CheckView(view, rig);
  impl_ = std::make_unique<Impl>(scene.data(), rig, view);
}
PixelPicker::~PixelPicker() = default;

std::optional<PixelPick> PixelPicker::Pick(int x, int y) const {
  const Impl& m = *impl_;
  if (x < 0 || y < 0 || x >= m.width || y >= m.height)
    throw std::out_of_range("PixelPicker: pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                            ") outside the " + std::to_string(m.width) + " x " +
                            std::to_string(m.height) + " image");
  internal::Sample smp;
  if (!m.rays.Center(x, y, &smp.d, nullptr, nullptr)) return std::nullopt;
  const double t0 = m.rays.NearT(smp.d);  // from the cut plane, as the frame's rays
  const auto hit =
      m.scene.caster->Intersect(Ray{Vec3(m.rays.eye() + t0 * smp.d), smp.d, 0.0, internal::kInf});
  if (!hit) return std::nullopt;
  RayHit h = *hit;
  h.t += t0;  // from the eye
  internal::SetHit(m.rays.eye(), h, m.scene.mesh, &smp);
  const double lift = 0.1 * m.tester.epsilon();  // as FrameRenderer
  PixelPick pick;
  pick.point = smp.X;
  pick.normal = smp.n;
  pick.lit_point = smp.X + lift * smp.n;
  pick.depth = smp.t;
  pick.triangle = smp.triangle;
  pick.object = m.scene.triangle_object[smp.triangle];
  for (int c = 0; c < int(m.rig.cameras.size()); ++c)
    if (m.tester.Test(c, pick.lit_point, &pick.normal) == ViewResult::kSeen)
      pick.cameras.push_back(c);
  return pick;
}

std::optional<Ray> PixelRay(const Rig& rig, const RenderView& view, double x, double y) {
  internal::CheckView(view, rig);
  const internal::ViewRays rays(view, rig, /*table=*/false);
  Vec3 d;
  if (!rays.Direction(x, y, &d)) return std::nullopt;
  return Ray{rays.eye(), d, rays.NearT(d), internal::kInf};
}

std::optional<PixelPick> PickPixel(const PreparedScene& scene, const Rig& rig,
                                   const RenderView& view, int x, int y) {
  return PixelPicker(scene, rig, view).Pick(x, y);
}

std::vector<uint8_t> ComputeDrawnEdges(const TriangleMesh& mesh) {
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
      if (std::lexicographical_compare(b.data(), b.data() + 3, a.data(), a.data() + 3))
        std::swap(a, b);
      edges[Key{{a.x(), a.y(), a.z(), b.x(), b.y(), b.z()}}].push_back({uint32_t(t), uint8_t(i)});
    }
  const double cos_crease = std::cos(1.0 * kPi / 180.0);
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

void RenderOptions::Check() const {
  const auto in = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
  if (!std::isnan(brightness) && !(brightness > 0 && brightness <= 1e6))
    throw InputError("{brightness}", "", "must be in (0, 1e6] times one camera's light",
                     "leave it unset for the default min(1, 3 / enabled cameras)");
  if (!in(ambient, 0, 1)) throw InputError("{ambient}", "", "must be in [0, 1]");
  if (!in(grid_pixels, 1, 100000))
    throw InputError("{grid_pixels}", "", "must be a whole number of camera pixels in [1, 100000]");
  if (!in(grid_fill, 0, 1)) throw InputError("{grid_fill}", "", "must be in [0, 1]");
  if (!(line_width_px > 0 && line_width_px <= 1000))
    throw InputError("{line_width_px}", "", "must be in (0, 1000] output pixels");
  if (!in(line_grey, 0, 1)) throw InputError("{line_grey}", "", "must be in [0, 1]");
  if (!in(samples, 1, 16)) throw InputError("{samples}", "", "must be 1 to 16 (per axis)");
  if (!background.allFinite() || (background.array() < 0).any())
    throw InputError("{background}", "", "must be a finite linear RGB colour >= 0");
  if (!(pixel_sigma > 0 && std::isfinite(pixel_sigma)))
    throw InputError("{pixel_sigma}", "", "must be a finite number of pixels > 0");
  for (const PtzTrace& t : ptz_all)
    if (!(t.budget_s >= 0 && std::isfinite(t.budget_s)))
      throw InputError("{budget_s}", "", "must be a finite number of seconds >= 0");
}

}  // namespace pandora
