#pragma once
/// \file primitives.h
/// Tessellated primitive shapes in their own object frame (metres, centred on the origin), and
/// checks on triangle meshes (closedness, signed volume, welding).
///
/// Every primitive is an indexed mesh with shared vertices and counter-clockwise triangles seen
/// from outside. Box, sphere, cylinder and capsule are closed (watertight); the plane is an open
/// sheet.

#include <string>

#include "analysis/geometry/geometry.h"

namespace pandora {

/// Axis-aligned box of edge lengths `size` (all > 0), centred on the origin: 8 vertices, 12
/// triangles.
TriangleMesh MakeBox(const Vec3& size);

/// UV sphere of `radius` centred on the origin. `segments` (>= 3) slices around the z axis and
/// max(2, segments / 2) stacks from pole to pole, so faces span about 360/segments degrees both
/// ways. All vertices lie on the sphere (the mesh is inscribed).
TriangleMesh MakeSphere(double radius, int segments = 32);

/// Cylinder of `radius` and `height` whose axis is the z axis, centred on the origin, with flat
/// caps (fans around a centre vertex). `segments` (>= 3) slices around; vertices lie on the
/// circles.
TriangleMesh MakeCylinder(double radius, double height, int segments = 32);

/// Capsule: a cylinder of `radius` whose straight part has length `length` (>= 0) along z, closed
/// by two hemispheres; centred on the origin, total extent along z is length + 2 radius. `segments`
/// (>= 3) slices around, max(1, segments / 4) stacks per hemisphere.
TriangleMesh MakeCapsule(double radius, double length, int segments = 32);

/// Square sheet of `size` (x, y) in the object's xy plane, centred on the origin, normal +z:
/// 4 vertices, 2 triangles. Single sided and open.
TriangleMesh MakePlane(const Vec2& size);

/// Exact volume enclosed by the tessellation MakeSphere(radius, segments) produces (a stack of
/// frustums of regular polygons), for tests and tolerances. Always below (4/3) pi radius^3.
double TessellatedSphereVolume(double radius, int segments);

/// Signed volume enclosed by the mesh (divergence theorem); positive for a closed mesh whose
/// triangles are counter-clockwise seen from outside. Meaningless for open meshes.
double SignedVolume(const TriangleMesh& mesh);

/// Result of CheckClosed.
struct ClosedCheck {
  bool closed = true;
  /// Number of undirected edges not shared by exactly two triangles of opposite orientation.
  int bad_edges = 0;
  /// One offending edge's end points, when not closed.
  Vec3 example_a = Vec3::Zero(), example_b = Vec3::Zero();
  /// One line describing the first problem found ("" when closed).
  std::string description;
};

/// Whether every edge is shared by exactly two triangles that traverse it in opposite directions
/// (closed, consistently oriented, edge-manifold). Works on vertex indices: weld first
/// (WeldVertices) when the mesh may repeat positions. An empty mesh is not closed.
ClosedCheck CheckClosed(const TriangleMesh& mesh);

/// Merges vertices whose positions are exactly equal, remaps the triangles and drops triangles that
/// become degenerate (two equal indices). Keeps the first occurrence's order.
TriangleMesh WeldVertices(const TriangleMesh& mesh);

}  // namespace pandora
