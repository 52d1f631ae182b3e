#pragma once
/// \file solid_trees.h
/// The search trees of a scene's solids and region mesh (InsideMesh: CGAL AABB trees), built on
/// first use and kept: an acceleration structure of the static scene, like the ray caster's BVH. A
/// study (app/session/study.h) owns one, so a session, `pandora bench` or `pandora accuracy` that
/// evaluates the fields many times builds each tree once; an evaluation without one builds the
/// trees it needs itself (FieldOptions::solid_trees).

#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/scene/scene.h"

namespace pandora {

struct RigCheckOptions;

class SolidTrees {
 public:
  /// Builds nothing. `scene` must outlive this object (the study owns both).
  explicit SolidTrees(const Scene& scene);
  ~SolidTrees();

  /// The tree of scene.objects[index] when `scene` (possibly a copy with another voxel size or
  /// region) has the same mesh at that index as the scene this was made for, built at the first
  /// call (thread-safe); nullptr otherwise (the caller builds its own).
  const InsideMesh* Object(const Scene& scene, std::size_t index) const;
  /// The tree of the region's mesh, under the same condition.
  const InsideMesh* RegionMesh(const Scene& scene) const;
  /// Lends these trees to the plausibility checks (RigCheckOptions::object_tree and region_tree,
  /// analysis/rig/rig_check.h) over `scene`, which must outlive `check` as this object must.
  void LendTo(const Scene& scene, RigCheckOptions* check) const;
  /// Trees built so far and the seconds spent building them (all threads' wall time summed).
  int built() const;
  double build_seconds() const;

 private:
  const Scene& scene_;
  mutable std::vector<std::once_flag> once_;  // objects, then the region
  mutable std::vector<std::unique_ptr<InsideMesh>> trees_;
  mutable std::mutex mutex_;
  mutable int built_ = 0;
  mutable double seconds_ = 0;
  const InsideMesh* Get(std::size_t slot, const TriangleMesh& mesh) const;
};

}  // namespace pandora
