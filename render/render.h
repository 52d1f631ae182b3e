#pragma once
/// \file render.h
/// Projective-light rendering (paper Fig. 2 and 4): the scene seen from a viewpoint, lit by every
/// enabled camera of a rig as a projector of its own colour. A surface point seen by camera c under
/// the visibility rules (analysis/geometry/visibility.h: working range, image bounds with
/// distortion, facing the camera, not occluded) receives c's colour; contributions add; points no
/// camera sees stay unlit. The renderer is the exact CPU reference: one primary ray per sample
/// through Embree, then one occlusion segment per (sample, camera), traced in packets.
///
/// Two forms: the one-shot Render(scene, rig, caster, view, options, fields), which prepares the
/// scene for that call, and Render(prepared, rig, view, options, overlays) over a PreparedScene
/// (render/prepared_scene.h) that holds the per-scene work (triangles, edges, textures, the ray
/// caster) across frames. Both give the same image bit for bit. ProgressiveRender
/// (render/progressive.h) gives a coarse image first and refines it, for interactive use. The light
/// rule itself is render/light.h.
///
/// This header is light (no Embree, OpenVDB, OpenEXR or libpng). Overlays from fields come in as a
/// `Fields` (volume/fields.h), e.g. from ReadFieldsVdb (volume/vdb_io.h).

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "render/light.h"

namespace pandora {

class Fields;
class PreparedScene;
class PreparedOverlays;

/// Where the image is seen from.
struct RenderView {
  /// Main view: a pinhole eye at `from` looking at `at`, `up` up, horizontal field of view
  /// `fov_deg`.
  Vec3 from = Vec3::Zero();
  Vec3 at = Vec3::UnitX();
  Vec3 up = Vec3::UnitZ();
  double fov_deg = 60.0;
  /// Output size in pixels.
  int width = 1280;
  int height = 720;
  /// Camera's-eye view: >= 0 renders what rig.cameras[camera] images (its pose and lens model,
  /// distortion included: each output pixel is unprojected through the camera model, the camera's
  /// image scaled to width x height). from/at/up/fov_deg are then ignored.
  int camera = -1;
  /// Main view: nothing nearer than this distance along the optical axis is drawn (a plan's cut
  /// through the ceiling, an elevation's section); 0: none. Primary rays start on that plane (the
  /// origin moved there in double, so a far eye costs no float precision); the GPU renderer
  /// discards fragments nearer than it.
  double clip_near = 0;
  /// Camera's-eye views only: render just the rectangle [x, x + width) x [y, y + height) of the
  /// width x height image; the Image is then window.width x window.height, its pixel (i, j) the
  /// full image's (x + i, y + j), every ray and value as in the full image. Empty (width or height
  /// 0): the whole image. `pandora synth` renders only where a fiducial may show.
  struct Window {
    int x = 0, y = 0, width = 0, height = 0;
    bool empty() const { return width <= 0 || height <= 0; }
  };
  Window window;
  int OutputWidth() const { return window.empty() ? width : window.width; }
  int OutputHeight() const { return window.empty() ? height : window.height; }
};

/// A RenderView from a named scene view (View::fov_deg unset: `default_fov_deg`).
RenderView ViewFromScene(const View& view, int width, int height, double default_fov_deg = 60.0);

/// A plan or elevation of `bounds` for proposals: `side` "plan" (from above, north up) or
/// "north", "south", "east", "west" (from that side, +z up). The eye stands kPlanDistance times the
/// bounds' diagonal away with the field of view that frames them (5 % margin), so the picture is
/// orthographic to a relative scale error of depth / distance (at most 1 / kPlanDistance, 0.2 %).
/// `metres_per_pixel` (if given) receives the scale at the bounds' centre. The view is cut at
/// `cut` (a plan: the height; an elevation: the coordinate along its axis), nothing on the eye's
/// side of it drawn (a ceiling, the near wall); NaN: no cut. An unknown side: nullopt.
inline constexpr double kPlanDistance = 500.0;
std::optional<RenderView> PlanView(const Aabb& bounds, const std::string& side, int width,
                                   int height, double cut, double* metres_per_pixel = nullptr);
/// The default cut of a plan or elevation of a study region `region` (`pandora render --plan`, the
/// viewer's Plan and Elevation views): a plan at the region's top, an elevation at the region's
/// face on its side (north: max y, south: min y, east: max x, west: min x). NaN for an unknown
/// side.
double PlanDefaultCut(const Aabb& region, const std::string& side);

/// How the surfaces themselves look under the projected light.
enum class Surface {
  kMaterial,    ///< Intrinsic material colour (Scene::materials), with a dim ambient term.
  kBlack,       ///< Black: only the projected light shows (analytic tests use this).
  kHiddenLine,  ///< Black with grey mesh edges, hidden lines removed (coplanar diagonals skipped).
  kContours,  ///< Black with grey contours only: silhouette/crease/object boundaries in the image.
};

/// Surface's names in its order ("material", "black", "hidden-line", "contours"): `render
/// --surface`, a script's "light", the viewer's panel.
inline const std::vector<std::string>& SurfaceNames() {
  static const std::vector<std::string> kNames{"material", "black", "hidden-line", "contours"};
  return kNames;
}
inline const std::string& SurfaceName(Surface surface) {
  return SurfaceNames()[static_cast<std::size_t>(surface)];
}
/// The surface mode SurfaceName calls `name`; nullopt for any other text.
inline std::optional<Surface> SurfaceFromName(const std::string& name) {
  for (std::size_t i = 0; i < SurfaceNames().size(); ++i)
    if (SurfaceNames()[i] == name) return static_cast<Surface>(i);
  return std::nullopt;
}

/// Overlays drawn in the main view.
struct OverlayOptions {
  bool cameras = true;          ///< Each enabled camera as a small body plus its frustum wireframe.
  bool labels = false;          ///< With `cameras`: each camera's id beside its centre (plans).
  double frustum_length = 0.6;  ///< Metres along the axis (clipped to the camera's far distance).
  /// Slice plane through the fields (needs `fields`): empty = none, else the field name, e.g.
  /// "coverage", "resolution", "sigma_max". Coloured with viridis between slice_min and slice_max
  /// (NaN: the field's range on the slice); a legend is drawn in the lower right corner.
  std::string slice_field;
  int slice_axis = 2;  ///< 0 x, 1 y, 2 z: the plane is perpendicular to this axis.
  /// Plane position along slice_axis (m); NaN: the middle voxel layer of the field's active voxels.
  double slice_position = std::numeric_limits<double>::quiet_NaN();
  double slice_min = std::numeric_limits<double>::quiet_NaN();
  double slice_max = std::numeric_limits<double>::quiet_NaN();
  double slice_opacity = 0.75;
  /// Draw the slice's colour bar with its range and the field's name and unit (FieldUnitLabel).
  bool legend = true;
  /// Draw the colour key: each enabled camera's id beside a swatch of its light's colour, in the
  /// upper left corner (in columns when the cameras do not fit one; left out when the key would
  /// take more than half the image's width).
  bool key = true;
  /// Isosurface (needs `fields`): empty = none, else a field name and an iso value; e.g.
  /// "coverage" at 1.5 is the boundary of coverage >= 2, "sigma_max" at 2.0 the 2 mm boundary.
  /// Extracted with OpenVDB's volumeToMesh, ray traced with the scene, alpha-composited.
  std::string iso_field;
  double iso_value = 1.5;
  Vec3 iso_color{1.0, 0.55, 0.1};
  double iso_opacity = 0.45;
};

/// The label of a field with its unit, for legends: "coverage [cameras]", "resolution [px/m]",
/// "sigma_max [mm]", "sigma_mean [mm]", "triangulation_angle [deg]", "condition [1]", and the
/// steady-state fields like their static ones; other names unchanged.
std::string FieldUnitLabel(const std::string& field);

struct RenderOptions {
  Pattern pattern = Pattern::kUniform;
  Surface surface = Surface::kMaterial;
  /// Multiplies every camera's light, so many overlaps do not saturate to white (paper Fig. 4).
  /// NaN (the default): DefaultBrightness of the rig's enabled cameras.
  double brightness = std::numeric_limits<double>::quiet_NaN();
  /// Dim ambient light in kMaterial mode (fraction of the material colour shown unlit).
  double ambient = 0.15;
  int grid_pixels = 32;        ///< kGrid: a line every this many camera pixels.
  double grid_fill = 0.15;     ///< kGrid: light between the lines, as a fraction of the lines'.
  double line_width_px = 1.2;  ///< Grid lines, mesh edges and contours, in output pixels.
  double line_grey = 0.25;     ///< Linear grey of mesh edges and contours.
  int samples = 1;             ///< Samples per pixel per axis (samples^2 per pixel, stratified).
  Vec3 background{0.02, 0.02, 0.03};  ///< Linear RGB where no surface is hit.
  OverlayOptions overlays;
  /// Compute the resolution and sigma_max layers (projection Jacobians and a 3x3 decomposition per
  /// pixel); when false they stay 0 and +inf. `pandora render` computes them for EXR output only.
  /// coverage, cameras, depth and object are always filled.
  bool layers = true;
  /// Study pixel sigma for the sigma_max layer, for cameras without their own (Study::pixel_sigma).
  double pixel_sigma = 0.5;
  /// PTZ traces in the "all" mode (docs/ptz.md): rig camera `camera` (which must have a PTZ head)
  /// lights every point some setting reachable from home within `budget_s` seconds sees (image,
  /// range, facing, occlusion from that setting's centre), darker for later seconds: the colour
  /// times 1 - 0.6 k / ceil(budget_s) for a point first reached in second k (0: seen from home).
  struct PtzTrace {
    int camera = -1;
    double budget_s = 3;
  };
  std::vector<PtzTrace> ptz_all;

  /// Checks every value (Render does before it draws): brightness NaN or in (0, 1e6], ambient,
  /// grid_fill and line_grey in [0, 1], grid_pixels in [1, 100000], line_width_px in (0, 1000],
  /// samples in [1, 16], a finite background >= 0, pixel_sigma > 0, PTZ budgets >= 0. InputError
  /// naming the field ({samples}), which each front end writes its own way.
  void Check() const;
};

/// The rendered image and its per-pixel layers (row-major, y down, index y * width + x). The layers
/// are taken at the first surface hit of the pixel centre's ray (overlays do not change them).
struct Image {
  /// Rigs up to this many cameras get the per-pixel camera set as a bitmask (`cameras`).
  static constexpr int kMaxMaskCameras = 64;

  int width = 0, height = 0;
  std::vector<float> rgb;  ///< Linear RGB, 3 per pixel, unclamped (>= 0).
  /// Number of enabled cameras that see the surface point: exact for any number of cameras.
  std::vector<float> coverage;
  /// Bit c set when rig camera c sees the surface point, for rigs of at most kMaxMaskCameras
  /// cameras. Empty for larger rigs: a per-pixel set of up to 1000 cameras would not fit a mask,
  /// and a mask of the first 64 would read as the whole set. There, `coverage` still counts every
  /// camera and PickPixel lists the cameras that see the point a pixel shows.
  std::vector<uint64_t> cameras;
  std::vector<float> resolution;  ///< Best pixel density (px/m) among those cameras; 0 if none.
  /// Worst-direction 1-sigma of the static triangulation (mm), as the sigma_max field;
  /// +inf where fewer than two cameras see the point or a direction is unobservable.
  std::vector<float> sigma_max;
  std::vector<float> depth;     ///< Distance from the eye along the ray (m); +inf: no surface.
  std::vector<int32_t> object;  ///< Scene object index hit, -1 for none.

  Vec3 Rgb(int x, int y) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
    return Vec3(rgb[i], rgb[i + 1], rgb[i + 2]);
  }
};

/// A float layer of Image as files carry it: its name (the EXR channel), the member that holds
/// it and what its values mean (the EXR header's pandora_layers).
struct ImageLayer {
  const char* name;
  std::vector<float> Image::*values;
  const char* meaning;
};

/// Image's float layers beside rgb, in file order: the one table WriteExr and ReadExr use.
inline const std::vector<ImageLayer>& ImageFloatLayers() {
  static const std::vector<ImageLayer> kLayers{
      {"coverage", &Image::coverage, "cameras seeing the surface point"},
      {"resolution", &Image::resolution, "px/m"},
      {"sigma_max", &Image::sigma_max, "mm, inf = not triangulable"},
      {"depth", &Image::depth, "m along the eye ray, inf = no surface"},
  };
  return kLayers;
}

/// Renders one frame of a prepared scene lit by the enabled cameras of `rig`: only per-frame work
/// (the view's rays, the rig's visibility tests, shading, overlays). `overlays` (may be null) holds
/// the prepared slice and isosurface that options.overlays asks for. Any number of cameras.
/// Throws InputError for a bad view ("{size}", "{fov_deg}", "{at}", "{camera}") and when an overlay
/// needs fields and `overlays` is null (file "{fields}"); std::invalid_argument when `overlays` was
/// prepared for another slice or isosurface (PreparedOverlays::Matches). Parallel over image tiles
/// (TBB); safe to call from several threads at once on the same PreparedScene.
Image Render(const PreparedScene& scene, const Rig& rig, const RenderView& view,
             const RenderOptions& options, const PreparedOverlays* overlays = nullptr);

/// The one-shot convenience form: prepares `scene` over `caster` (no BVH is built) and, when
/// options.overlays asks for them, the overlays from `fields`, then renders as above; the same
/// image bit for bit. `caster` must be built from scene.AllTriangles(). `fields` may be null when
/// no overlay needs it. Throws as above, and InputError when the fields lack the grid
/// ("{slice_field}",
/// "{iso_field}"; the hint lists the grids present).
Image Render(const Scene& scene, const Rig& rig, const RayCaster& caster, const RenderView& view,
             const RenderOptions& options, const Fields* fields = nullptr);

/// Timing of Render's parts and the ray counts, for `pandora bench --render`.
struct RenderStats {
  double seconds = 0;  ///< Whole Render call (with the preparation in the one-shot form).
  std::size_t primary_rays = 0;
  std::size_t shadow_rays = 0;  ///< Occlusion segments cast (after the geometric tests).
};
/// Render that also reports stats (may be null) and, when `primary` / `shadow` are given, records
/// every primary ray and every occlusion segment it traced, tile by tile, so a benchmark can replay
/// them through raw Embree.
Image RenderWithStats(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const RenderView& view, const RenderOptions& options, const Fields* fields,
                      RenderStats* stats, std::vector<Ray>* primary = nullptr,
                      std::vector<Ray>* shadow = nullptr);
/// The same over a prepared scene (stats->seconds: the frame only).
Image RenderWithStats(const PreparedScene& scene, const Rig& rig, const RenderView& view,
                      const RenderOptions& options, const PreparedOverlays* overlays,
                      RenderStats* stats, std::vector<Ray>* primary = nullptr,
                      std::vector<Ray>* shadow = nullptr);

/// What the centre of output pixel (x, y) shows: the surface point and the cameras that see it.
struct PixelPick {
  Vec3 point;   ///< First surface hit of the pixel's centre ray (world, m).
  Vec3 normal;  ///< Geometric unit normal there, turned towards the eye.
  /// The point the cameras are tested at: `point` lifted off the surface along `normal` by a
  /// tenth of the visibility epsilon, as the renderer does, so float round-off in the hit cannot
  /// make a surface shadow itself.
  Vec3 lit_point;
  double depth = 0;   ///< Distance from the eye along the ray, m.
  int object = -1;    ///< Scene object index.
  int triangle = -1;  ///< Index into scene.AllTriangles().
  /// Indices (rig order) of the enabled cameras that see lit_point (VisibilityTester::Test with the
  /// normal): the per-pixel camera set for rigs of any size; its size is the `coverage` layer.
  std::vector<int> cameras;
};
/// Answers "what does output pixel (x, y) show, and which cameras light it" for one frame's rig and
/// view (a viewer's hover or click; the per-pixel camera set of rigs over 64 cameras). The pixel's
/// centre ray is the one Render traces, and the point and camera tests are the renderer's; the ray
/// is cast alone here (RayCaster::Intersect), so with Embree a ray through a shared triangle edge
/// may, rarely, resolve to the neighbouring triangle of the image's. Keeps references to `scene`
/// and `rig`, which must outlive it. Immutable; Pick is safe to call from many threads.
class PixelPicker {
 public:
  /// Throws as Render does for a bad view.
  PixelPicker(const PreparedScene& scene, const Rig& rig, const RenderView& view);
  ~PixelPicker();
  /// nullopt when the centre ray hits nothing or lies outside the lens's domain (camera's-eye
  /// view). Throws std::out_of_range for a pixel outside the image.
  std::optional<PixelPick> Pick(int x, int y) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The ray through output pixel coordinates (x, y) of `view` (pixel centres at integers; any real
/// coordinates, e.g. a mouse position), as Render traces it: origin at the eye, unit direction,
/// t from 0 to infinity. nullopt outside the lens's domain (a camera's-eye view). Throws as Render
/// does for a bad view. What a viewer's picking and gizmo drags use.
std::optional<Ray> PixelRay(const Rig& rig, const RenderView& view, double x, double y);

/// PixelPicker(scene, rig, view).Pick(x, y), for a single pick.
std::optional<PixelPick> PickPixel(const PreparedScene& scene, const Rig& rig,
                                   const RenderView& view, int x, int y);

/// 8-bit sRGB PNG of image.rgb (clamped to [0, 1], sRGB transfer curve), encoded in memory: the
/// bytes of the file WritePng writes (the report embeds them).
std::string EncodePng(const Image& image);
/// A PNG of 8-bit sRGB triples (row-major, y down) as they are, encoded in memory.
std::string EncodePngSrgb8(int width, int height, const std::vector<std::uint8_t>& rgb);

/// EncodePng written to a temporary name and renamed; throws InputError (file = path) when it
/// cannot be written.
void WritePng(const Image& image, const std::string& path);

/// Single-part, multi-layer scanline OpenEXR (ZIP): float R, G, B (linear) and float layers
/// `coverage`, `resolution`, `sigma_max`, `depth`, and uint `cameras` (bits 0-31; `cameras_hi`
/// holds bits 32-63 when the rig has more than 32 cameras). For rigs of more than
/// Image::kMaxMaskCameras cameras (image.cameras empty) neither is written and the header's
/// `pandora_layers` attribute says why. Temporary name, then renamed. Throws std::invalid_argument
/// for an inconsistent image (a layer's size, or `cameras` empty for a rig of at most 64 cameras).
void WriteExr(const Image& image, const std::string& path, int rig_cameras);

/// Reads back an EXR written by WriteExr (tests, tools); `cameras` stays empty when the file has no
/// `cameras` channel. Throws InputError when unreadable.
Image ReadExr(const std::string& path);

/// Reads a PNG (8-bit RGB or RGBA) into linear RGB (tests, reference images).
Image ReadPng(const std::string& path);

}  // namespace pandora
