#pragma once
/// \file frame.h
/// Internal to render/: the data behind PreparedScene and PreparedOverlays, and FrameRenderer, the
/// per-frame engine that Render and ProgressiveRender share.
///
/// A frame is cut into 16 x 16 pixel tiles, and every tile into four groups of pixels by level:
/// level 0 holds the pixels whose x and y are multiples of 8, level 1 those of 4 not in level 0,
/// level 2 those of 2 not in the earlier ones, level 3 the rest (and, with several samples per
/// pixel, the stratified colour samples of every pixel of the tile). A group's rays are traced
/// together (primary rays as one packet stream, each camera's occlusion segments as another), and
/// nothing a group computes depends on any other group. Render runs every group of a tile in level
/// order; ProgressiveRender runs level 0 of every tile, then level 1, and so on. Both make the same
/// ray caster calls with the same rays for every group, so their images are equal bit for bit.

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "render/overlay_fields.h"
#include "render/prepared_scene.h"
#include "render/render.h"

namespace pandora::internal {

constexpr int kTile = 16;   // tile edge in pixels: 256 centre samples share a packet per camera
constexpr int kLevels = 4;  // pixel levels per tile: blocks of 8, 4, 2, 1

/// The level of pixel (x, y): 0 when x and y are multiples of 8, 1 of 4, 2 of 2, else 3.
inline int PixelLevel(int x, int y) {
  const int m = x | y;
  return (m & 7) == 0 ? 0 : (m & 3) == 0 ? 1 : (m & 1) == 0 ? 2 : 3;
}

struct PreparedSceneData {
  std::string path;                        // the scene file (error messages)
  std::shared_ptr<const RayCaster> owned;  // when the caster is owned or shared
  const RayCaster* caster = nullptr;
  TriangleMesh mesh;                 // scene.AllTriangles()
  std::vector<int> triangle_object;  // object index of each triangle
  std::vector<Vec3> object_color;    // material colour per object
  double scene_scale = 1.0;          // diagonal of Scene::ContentBounds() (visibility epsilon)
  std::vector<std::string> material_texture;  // texture path per material ("" none)
  // A fiducial's print per material (null: none), used in place of the texture path.
  std::vector<std::shared_ptr<const PrintedPattern>> material_printed;
  std::vector<int> object_material;  // material per object
  std::vector<bool> object_has_uvs;  // per object: its mesh has texture coordinates
  bool has_uvs = false;

  // Prepared at first use.
  mutable std::once_flag textures_once;
  mutable std::vector<Image> textures;
  mutable std::vector<int> object_texture;  // per object: index into textures, or -1
  mutable std::once_flag edges_once;
  mutable std::vector<uint8_t> drawn_edges;  // per triangle: bit i = edge opposite vertex i drawn

  const std::vector<int>& ObjectTextures() const;
  const std::vector<uint8_t>& DrawnEdges() const;
};

struct PreparedOverlaysData {
  std::string slice_field, iso_field;
  int slice_axis = 2;
  double slice_position = 0, iso_value = 0;
  bool have_slice = false;
  FieldSlice slice;                       // auto range in slice.min / slice.max
  double slice_plane = 0;                 // coordinate along slice_axis the plane is drawn at
  std::unique_ptr<RayCaster> iso_caster;  // null when no isosurface (or an empty one)
};

/// Checks what a frame needs of the view: InputError naming "{size}", "{camera}", "{fov_deg}" or
/// "{at}".
void CheckView(const RenderView& view, const Rig& rig);

/// The per-pixel outputs of the groups: the image and the centre rays' facing normals (contours).
struct FrameBuffers {
  Image image;
  std::vector<Vec3> normal;  // empty unless Surface::kContours
};

/// Scratch vectors of one thread, reused across groups.
struct GroupScratch;
void DeleteScratch(GroupScratch* scratch);
struct ScratchDeleter {
  void operator()(GroupScratch* s) const { DeleteScratch(s); }
};
std::unique_ptr<GroupScratch, ScratchDeleter> MakeScratch();

/// Rays traced per tile (for RenderStats), optionally the rays themselves.
struct TileRecord {
  std::size_t primary = 0, shadow = 0;
  std::vector<Ray> primary_rays, shadow_rays;
};

/// One frame: the checked view, the rig's visibility tests and the resolved options. Immutable
/// after construction; groups may run concurrently on different tiles.
class FrameRenderer {
 public:
  /// Checks the view and overlays (throws as Render documents).
  FrameRenderer(const PreparedScene& scene, const Rig& rig, const RenderView& view,
                const RenderOptions& options, const PreparedOverlays* overlays);
  ~FrameRenderer();

  int width() const { return width_; }
  int height() const { return height_; }
  int tiles() const { return tiles_x_ * tiles_y_; }
  /// Centre pixels of `level` in `tile`.
  int GroupPixels(int tile, int level) const;

  /// The buffers at their initial values (black, no hit, +inf depth and sigma).
  FrameBuffers Allocate() const;
  /// The same into existing buffers (their memory is reused when the size is unchanged).
  void Reset(FrameBuffers* buffers) const;
  /// Traces group (tile, level) into `out`: the layers of its centre pixels and their colour (at
  /// levels 0-2 with several samples per pixel: the centre sample's colour, replaced at level 3 by
  /// the stratified average). `record` (may be null) receives the counts and, when record_rays,
  /// the rays.
  void RenderGroup(int tile, int level, FrameBuffers* out, GroupScratch* scratch,
                   TileRecord* record, bool record_rays) const;
  /// The image-space passes after the groups: contours, camera wireframes, legend, key.
  void Finish(FrameBuffers* frame) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int width_ = 0, height_ = 0, tiles_x_ = 0, tiles_y_ = 0;
};

}  // namespace pandora::internal
