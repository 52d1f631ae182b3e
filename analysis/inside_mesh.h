#pragma once
/// \file inside_mesh.h
/// Point-in-closed-mesh tests (CGAL's Side_of_triangle_mesh over an AABB tree), used for solid objects
/// and mesh regions. The only translation unit that includes CGAL is inside_mesh.cpp.

#include <memory>

#include "analysis/geometry.h"

namespace pandora {

/// Classifies points and boxes against a closed, consistently oriented triangle mesh. Immutable after
/// construction; safe for concurrent const use (each thread gets its own CGAL query object).
class InsideMesh {
 public:
  /// The mesh must be closed (the scene loader checks it). Builds the AABB tree eagerly.
  explicit InsideMesh(const TriangleMesh& closed_mesh);
  ~InsideMesh();
  InsideMesh(const InsideMesh&) = delete;
  InsideMesh& operator=(const InsideMesh&) = delete;

  /// True when `p` is inside or on the boundary.
  bool Inside(const Vec3& p) const;

  enum class BoxClass { kOutside, kInside, kCrossing };
  /// Whether the closed box lies entirely outside, entirely inside, or may cross the surface.
  /// Conservative: kCrossing whenever a triangle's bounding box meets the box.
  BoxClass Classify(const Aabb& box) const;

  const Aabb& bounds() const { return bounds_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Aabb bounds_;
};

}  // namespace pandora
