#pragma once
/// \file inside_mesh.h
/// Point-in-closed-mesh tests (vertical columns' crossing parity with CGAL's exact predicates, and
/// CGAL's Side_of_triangle_mesh over an AABB tree where a column is degenerate), used for solid
/// objects and mesh regions. The only translation unit that includes CGAL is inside_mesh.cpp.

#include <memory>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

/// Classifies points and boxes against a closed, consistently oriented triangle mesh. Immutable
/// after construction; safe for concurrent const use (each thread gets its own CGAL query object).
class InsideMesh {
 public:
  /// The mesh must be closed (the scene loader checks it). Builds the column grid (the faces
  /// bucketed by their (x, y) bounds); CGAL's mesh and AABB tree only when a query needs them
  /// (Inside(), a column through an edge or a vertex, Classify() over most of a large mesh).
  explicit InsideMesh(const TriangleMesh& closed_mesh);
  ~InsideMesh();
  InsideMesh(const InsideMesh&) = delete;
  InsideMesh& operator=(const InsideMesh&) = delete;

  /// True when `p` is inside or on the boundary.
  bool Inside(const Vec3& p) const;

  /// The mesh along one vertical line (x, y): where it crosses the surface, for Inside() at many
  /// heights (InsideOnColumn) after one search of the tree.
  struct Column {
    double x = 0, y = 0;
    /// Outside the mesh's bounds in x or y: no point of the line is inside.
    bool outside = true;
    /// The line meets a face's edge or vertex (in projection): InsideOnColumn asks Inside().
    bool degenerate = false;
    struct Crossing {
      Vec3 a, b, c;  ///< the face
      double z = 0;  ///< where the line crosses it (rounded; exact predicates decide near it)
      int up = 1;    ///< +1 when the face's normal points up
    };
    std::vector<Crossing> crossings;  ///< ascending z
  };
  Column ColumnAt(double x, double y) const;
  /// Inside() for `count` points (column.x, column.y, z[i]) into `inside` (1 or 0): the parity of
  /// the crossings below each point, decided by CGAL's exact predicates where a point lies within
  /// round-off of a crossing, so the answers equal Inside()'s.
  void InsideOnColumn(const Column& column, const double* z, int count,
                      unsigned char* inside) const;

  enum class BoxClass { kOutside, kInside, kCrossing };
  /// Whether the closed box lies entirely outside, entirely inside, or may cross the surface.
  /// Conservative: kCrossing whenever a triangle's bounding box meets the box; otherwise the
  /// centre's column parity (as InsideOnColumn) decides.
  BoxClass Classify(const Aabb& box) const;

  const Aabb& bounds() const { return bounds_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Aabb bounds_;
};

}  // namespace pandora
