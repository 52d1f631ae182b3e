#pragma once
/// \file renderer.h
/// The GPU projective-light renderer of the viewer: the same picture as the exact CPU renderer
/// (render/render.h) drawn with OpenGL 3.3 core into offscreen framebuffers, with shadow maps in
/// place of the occlusion rays. Every enabled camera is a projector of its colour; lights add in
/// rig order with the brightness and pattern of render/light.h, whose formulas the shaders follow
/// (docs/rendering.md, "The light rule"). Per camera, a fragment's surface point is tested as
/// VisibilityTester does: working range, projection through the camera's lens model in the
/// fragment shader (pinhole, Brown-Conrady k1 k2 p1 p2 k3 with its monotonic domain and Jacobian
/// test, fisheye k1..k4: the formulas of analysis/geometry/camera.cpp), the image bounds, facing,
/// and, in place of the occlusion segment, one distance map per camera (docs/viewer.md).
///
/// Light header: no GL. Every call needs a current GL 3.3 context (viewer/gl/context.h) on the
/// calling thread, the one the renderer was created on.

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/scene/scene.h"
#include "render/light.h"
#include "render/prepared_scene.h"
#include "render/render.h"

namespace pandora {

struct RenderView;

/// How a GPU frame is drawn: the CPU renderer's RenderOptions that apply, and the shadow maps.
struct GlRenderOptions {
  Pattern pattern = Pattern::kUniform;
  /// What a surface shows, as render's RenderOptions::surface: kMaterial, albedo * light plus the
  /// ambient term of MaterialColor (textured when the renderer was given a PreparedScene); kBlack,
  /// the light only; kHiddenLine, the light with grey mesh edges (the drawn-edge set of
  /// render/frame.cpp: edges between triangles more than 1 degree apart and boundary edges) where
  /// the surface next to them is visible; kContours, the light with grey contours found in the
  /// G-buffer by the CPU renderer's rules (object, depth and 30-degree normal discontinuities
  /// between neighbouring pixels).
  Surface surface = Surface::kMaterial;
  /// NaN (the default): DefaultBrightness of the rig's enabled cameras.
  double brightness = std::numeric_limits<double>::quiet_NaN();
  double ambient = 0.15;
  int grid_pixels = 32;
  double grid_fill = 0.15;
  double line_width_px = 1.2;  ///< Grid lines and mesh edges, output pixels.
  double line_grey = 0.25;     ///< Linear grey of mesh edges and contours.
  Vec3 background{0.02, 0.02, 0.03};
  /// Texels per side of each camera's distance map, 256 .. 4096 (std::invalid_argument outside;
  /// the window's frames while cameras move use 256, what users choose is 512 .. 4096).
  /// A camera whose field reaches 75 degrees off its axis or more (wide fisheyes) gets a cube of
  /// six maps of map_size / 2 texels around its centre instead of one.
  int shadow_map_size = 2048;
  /// Multiplies the shadow test's tolerance (docs/viewer.md, "Shadows"); 1 is what was measured.
  double shadow_bias_scale = 1.0;
  /// Which test decides that a point is lit (docs/viewer.md, "Shadows"). kBoth, the default, is
  /// what the thresholds were measured with; the others are there to measure each alone.
  enum class ShadowTest {
    kDistance = 0,  ///< Distance to the camera within the stored one plus a texel-size bias.
    kReceiverPlane =
        1,      ///< The stored distance not nearer than the point's plane on the texel ray.
    kBoth = 2,  ///< Either.
  };
  ShadowTest shadow_test = ShadowTest::kBoth;
  /// Keep each camera's maps for the next frame and draw them again only for cameras whose
  /// geometry changed (SameCameraGeometry): a frame that moves only the eye draws no maps. Only
  /// when the whole rig fits one light pass (see map_memory_mib).
  bool reuse_maps = true;
  /// Draw every map a frame needs in one instanced, layered draw per texture array (a geometry
  /// shader routes each map to its layer; the nearest distance kept by MIN blending, so no depth
  /// range and no per-map CPU work). false: one draw per map with a depth test and a depth range
  /// from the triangle tree (DepthRangeInPyramid), as before; both give the same maps (tested).
  bool one_pass_maps = true;
  /// Memory for the maps of one light pass, MiB. All maps of a pass are bound at once; a rig whose
  /// maps need more is lit in several passes (and its maps are drawn every frame). A map takes
  /// 4 map_size^2 bytes (16 MiB at 2048, 64 MiB at 4096), a cube 1.5 times that.
  double map_memory_mib = 1024;
};

/// A GPU frame read back to the CPU. Row-major, y down, index y * width + x, as render's Image.
struct GlImage {
  int width = 0, height = 0;
  std::vector<float> rgb;  ///< Linear RGB, 3 per pixel, unclamped.
  /// The per-pixel camera sets, camera_words 64-bit words per pixel (pixel p's word w at
  /// p * camera_words + w): bit c % 64 of word c / 64 set when rig camera c lights the pixel's
  /// surface point. camera_words = max(1, ceil(rig cameras / 64)): for rigs of up to 64 cameras,
  /// one word per pixel, render's Image::cameras layout.
  int camera_words = 0;
  std::vector<uint64_t> cameras;
  /// Whether rig camera c lights pixel p.
  bool Lights(std::size_t p, int c) const {
    return (cameras[p * std::size_t(camera_words) + std::size_t(c / 64)] >> (c % 64)) & 1u;
  }
  /// true where the pixel shows a surface.
  std::vector<uint8_t> hit;
};

/// Timing of a frame, seconds. With stats requested (and per_part) the renderer waits for the GPU
/// (glFinish) after each part, so the parts do not overlap.
struct GlFrameStats {
  /// Wait for the GPU after each part so that the times below are the parts' own (a bench); false
  /// (a window) fills only what costs nothing to count: the bytes, maps and the CPU time of maps.
  bool per_part = true;
  double shadow_seconds = 0;  ///< Distance maps of every enabled camera.
  /// CPU time (of the calling thread) spent preparing the maps: each map's depth range from the
  /// triangle tree, seconds.
  double map_cpu_seconds = 0;
  double light_seconds = 0;         ///< The per-camera light passes over the G-buffer.
  double total_seconds = 0;         ///< The whole frame up to the read-back (not included).
  double readback_seconds = 0;      ///< Render: the read-back; DrawToTexture: the encode pass.
  std::int64_t readback_bytes = 0;  ///< Bytes read from the GPU to the CPU (0: DrawToTexture).
  int shadow_maps = 0;   ///< Maps drawn (a cube counts 6, fewer where a face is not needed).
  int light_passes = 0;  ///< Passes over the G-buffer (batches of cameras).
};

/// The scene's triangles on the GPU and the programs; renders frames of any rig and view.
class GlRenderer {
 public:
  /// Uploads scene.AllTriangles() (positions relative to the centre of Scene::ContentBounds(), in
  /// float), each triangle's geometric normal and its object's material colour, and compiles the
  /// shaders. With `prepared` (the same scene's), the objects' diffuse textures too (the decoded
  /// images of PreparedScene::Textures(), drawn in Surface::kMaterial as the CPU renderer does:
  /// colour times the bilinear, repeating texel); without it, material colours only. Throws
  /// std::runtime_error with the GL info log when a shader does not compile.
  explicit GlRenderer(const Scene& scene, const PreparedScene* prepared = nullptr);
  ~GlRenderer();
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  /// Renders `rig` lit scene seen from `view` and reads it back: a main view (from/at/up/fov_deg,
  /// width x height), or a camera's-eye view (view.camera >= 0: what that rig camera images, its
  /// lens and distortion included, the camera's image scaled to width x height, as the CPU draws
  /// it). A camera's-eye view takes the lens's rays from a table the CPU unprojects once per lens
  /// and size (with their exact differentials for the grid), draws a pinhole G-buffer of the
  /// camera twice as fine as the output over the lens's field, and per output pixel keeps the
  /// nearest of the triangles there that the pixel's own ray hits (an exact ray-triangle test);
  /// primary rays start where the CPU's do (a camera on a wall does not see the wall). Throws
  /// std::invalid_argument for a camera index outside the rig, a camera's-eye view of a lens
  /// reaching 75 degrees off its axis (wide fisheyes: the CPU's), a bad size, fov or look-at, or a
  /// map size outside 256 .. 4096 or beyond this GL's GL_MAX_TEXTURE_SIZE; std::runtime_error for
  /// a GL error in the frame.
  GlImage Render(const Rig& rig, const RenderView& view, const GlRenderOptions& options,
                 GlFrameStats* stats = nullptr);
  /// The same frame, kept on the GPU for a window to show: its colour encoded as 8-bit sRGB RGBA
  /// (opaque; per channel what the CPU path's 8-bit sRGB of Render's rgb gives, within one level)
  /// in a GL_TEXTURE_2D this renderer owns, row 0 the image's top row, linear filtering. Returns
  /// the texture's name, valid until the next call with another size or the renderer's end.
  /// Nothing is read back (stats->readback_bytes = 0). Throws as Render.
  unsigned DrawToTexture(const Rig& rig, const RenderView& view, const GlRenderOptions& options,
                         GlFrameStats* stats = nullptr);

  std::size_t triangle_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The RGBA8 texels of `texture` (a GL_TEXTURE_2D of width x height, e.g. DrawToTexture's), row 0
/// first: what a screenshot or a test reads back of a frame kept on the GPU.
std::vector<unsigned char> GlReadRgba8(unsigned texture, int width, int height);

/// Copies `from` into `to` (both GL_TEXTURE_2D RGBA8 of width x height) on the GPU: a window keeps
/// a DrawToTexture frame of its own (the renderer's texture is its size's, drawn again next time).
void GlCopyTexture(unsigned from, unsigned to, int width, int height);

/// Whether GlRenderer draws `cam`'s camera's-eye view (lenses reaching 75 degrees off their axis,
/// wide fisheyes, are the CPU renderer's).
bool GlDrawsCameraEye(const Camera& cam);

/// The tightest [near, far] of camera-frame depth z that the scene's triangles reach inside the
/// pyramid {|x| / z, |y| / z within `bounds`} (x_min, x_max, y_min, y_max of normalized image
/// coordinates) of the frame `camera_from_world`: each triangle is clipped to the pyramid's four
/// side planes (double precision). Empty (near > far) when no triangle enters it. The shadow
/// maps' near and far planes (the Pandora paper's trick), exposed for tests.
std::pair<double, double> DepthRangeInPyramid(const TriangleMesh& mesh,
                                              const Eigen::Isometry3d& camera_from_world,
                                              const Eigen::Vector4d& bounds);

/// A bounding-box hierarchy over a mesh's triangles (leaves of at most 4), for the depth range.
struct TriangleBoxTree {
  struct Node {
    Aabb box;
    int left = -1, right = -1;  // children (both or neither)
    int first = 0, count = 0;   // a leaf's triangles: order[first .. first + count)
  };
  std::vector<Node> nodes;  // nodes[0] is the root (none for an empty mesh)
  std::vector<int> order;   // triangle indices, grouped by leaf
};
TriangleBoxTree BuildTriangleBoxTree(const TriangleMesh& mesh);

/// DepthRangeInPyramid with `tree` (BuildTriangleBoxTree(mesh)): the same two numbers, bit for
/// bit, from only the triangles that can widen the range found so far: a node is skipped when its
/// box lies outside one of the pyramid's planes or within the current [near, far] (both tested
/// with a margin over the boxes' rounding). What each shadow map and the G-buffer use: a map of the
/// trauma room's 10k triangles visits a few hundred. `visited`, when set, receives the triangles
/// clipped.
std::pair<double, double> DepthRangeInPyramid(const TriangleMesh& mesh, const TriangleBoxTree& tree,
                                              const Eigen::Isometry3d& camera_from_world,
                                              const Eigen::Vector4d& bounds,
                                              std::int64_t* visited = nullptr);

/// The light rule's weight as the renderer's GLSL computes it (render/light.h CameraLightWeight
/// for `rule`'s pattern, grid spacing, fill and line width; brightness and colour aside), one
/// fragment per input, on the current context: what the tests compare with the CPU rule at the
/// inputs of render/light_test.cpp. Inputs are rounded to float.
std::vector<double> GlCameraLightWeights(const LightRule& rule,
                                         const std::vector<CameraAtPoint>& points);

}  // namespace pandora
