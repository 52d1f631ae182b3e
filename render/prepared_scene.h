#pragma once
/// \file prepared_scene.h
/// What the renderer needs from a scene and from the fields, prepared once and reused for every
/// frame: PreparedScene (triangles and their objects, material colours, decoded textures, the
/// hidden-line edges, the ray caster) and PreparedOverlays (the slice plane sampled from the fields
/// and the isosurface with its own BVH). A frame then does only per-frame work:
/// Render(prepared, rig, view, options) in render/render.h, or ProgressiveRender
/// (render/progressive.h) for interactive use. Light header: no Embree, OpenVDB or image library.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"

namespace pandora {

class Fields;
struct OverlayOptions;
struct Image;  // render/render.h

namespace internal {
struct PreparedSceneData;
struct PreparedOverlaysData;
}  // namespace internal

/// Which of each triangle's edges the hidden-line mode draws (Surface::kHiddenLine): edges between
/// triangles more than 1 degree from coplanar, and boundary edges, matched by their exact end
/// points. Bit i of entry t: the edge of triangle t opposite its vertex i. PreparedScene computes
/// it once per scene; the GPU renderer of the viewer draws the same set.
std::vector<uint8_t> ComputeDrawnEdges(const TriangleMesh& mesh);

/// A scene prepared for rendering. Holds a copy of everything it derives from the Scene (the
/// Scene itself may go away), and either borrows, shares or owns the ray caster. The parts only
/// some surface modes need are prepared at first use, once, thread-safely: the decoded PNG
/// textures (Surface::kMaterial on meshes with texture coordinates; a texture that cannot be read
/// prints one warning line then, and its material colour stands in) and the drawn-edge table
/// (Surface::kHiddenLine). Immutable otherwise; safe to render from many threads at once. Rigs are
/// not part of it: every frame takes its rig, so camera edits need no new preparation.
class PreparedScene {
 public:
  /// Prepares `scene` with a BVH of its own (MakeEmbreeRayCaster(scene.AllTriangles())).
  /// Throws std::runtime_error when Embree fails.
  explicit PreparedScene(const Scene& scene);
  /// Prepares `scene` over an existing ray caster, e.g. the one a session holds for the scene and
  /// shares with the fields and suggest: no BVH is built. `caster` must have been built from
  /// scene.AllTriangles() and must outlive this object. Throws std::invalid_argument when its
  /// triangle count differs from the scene's.
  PreparedScene(const Scene& scene, const RayCaster& caster);
  /// The same, sharing ownership of the caster.
  PreparedScene(const Scene& scene, std::shared_ptr<const RayCaster> caster);
  ~PreparedScene();
  PreparedScene(PreparedScene&&) noexcept;
  PreparedScene& operator=(PreparedScene&&) noexcept;

  /// The ray caster every frame traces against.
  const RayCaster& caster() const;
  /// Triangles of scene.AllTriangles() (the caster's).
  std::size_t triangle_count() const;
  /// Prepares now what would otherwise be prepared at first use (textures, hidden-line edges), e.g.
  /// on a loading thread so that the first frame of each mode does not pay for it.
  void PrepareAll() const;
  /// The decoded diffuse textures (linear RGB, row 0 at the top, render/render.h's Image), decoded
  /// at the first call (as Surface::kMaterial's first frame does), and per object of the scene the
  /// index of its texture, or -1 (no texture, no texture coordinates, or a texture that could not
  /// be read). What the GPU renderer of the viewer uploads.
  const std::vector<Image>& Textures() const;
  const std::vector<int>& ObjectTextures() const;

  /// Internal to render/.
  const internal::PreparedSceneData& data() const { return *data_; }

 private:
  std::unique_ptr<internal::PreparedSceneData> data_;
};

/// The field overlays of OverlayOptions (slice plane, isosurface) prepared from a Fields: the slice
/// sampled on its plane (SampleSlice) and the isosurface extracted (OpenVDB volumeToMesh) and put
/// in its own Embree BVH. Build once per (fields, overlay choice) and pass to every frame until the
/// fields or the choice change; what a frame may still vary (slice range, opacities, colours, the
/// legend) stays in RenderOptions. Immutable; the fields may go away after construction.
class PreparedOverlays {
 public:
  /// Prepares what `overlays` asks for (its slice_field, slice_axis, slice_position, iso_field,
  /// iso_value); nothing when both field names are empty. Throws InputError like Render does: file
  /// "{slice_axis}" for a bad axis, "{slice_field}" / "{iso_field}" when the fields lack the grid
  /// (the hint lists the grids present).
  PreparedOverlays(const Fields& fields, const OverlayOptions& overlays);
  ~PreparedOverlays();
  PreparedOverlays(PreparedOverlays&&) noexcept;
  PreparedOverlays& operator=(PreparedOverlays&&) noexcept;

  /// True when `overlays` asks for the same slice and isosurface as this was prepared for (the
  /// fields named above equal; slice_position equal or both NaN).
  bool Matches(const OverlayOptions& overlays) const;

  /// Internal to render/.
  const internal::PreparedOverlaysData& data() const { return *data_; }

 private:
  std::unique_ptr<internal::PreparedOverlaysData> data_;
};

}  // namespace pandora
