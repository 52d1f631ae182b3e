#pragma once
/// \file surface_distance.h
/// Exact distance from a point to the nearest triangle of a mesh (double precision), for the
/// clearance `pandora suggest` and the rig generators keep between a camera centre and every scene
/// surface, and certificates that a whole cone of segments misses or crosses the mesh, for the
/// occlusion of a PTZ head whose centre moves along a move (analysis/scene/ptz.h). A bounding
/// volume hierarchy (median splits, up to 4 triangles per leaf) prunes the search.

#include <array>
#include <limits>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

/// Distance queries against a fixed triangle mesh. Immutable after construction; safe for
/// concurrent const use.
class SurfaceDistance {
 public:
  explicit SurfaceDistance(const TriangleMesh& mesh);

  /// Euclidean distance (metres) from `p` to the closest point of any triangle (faces, edges and
  /// corners; both sides), or `limit` when no triangle is closer than `limit` (infinity: the mesh
  /// has no triangle).
  double Distance(const Vec3& p, double limit = std::numeric_limits<double>::infinity()) const;

  /// The segments from every point Y within `r` of `C` to `X`, each less `trim` at both ends: true
  /// when every one keeps more than `trim` off every triangle. Certified by sphere tracing along
  /// C -> X: a point at fraction s of the way is within (1 - s) r of the matching point of every
  /// segment, so a distance above (1 - s) r + trim everywhere clears them all (at most `max_steps`
  /// distance queries; false when they run out or r >= |X - C| - trim). False says nothing: some
  /// segment may or may not meet a triangle.
  bool ConeClear(const Vec3& C, double r, const Vec3& X, double trim, int max_steps = 256) const;

  /// The same segments: true when one triangle crosses every one of them, each crossing more than
  /// `trim` from both ends of its segment: the ball B(C, r) lies, by more than r + trim, inside the
  /// pyramid that X's view of the triangle spans and beyond the triangle's plane, X more than
  /// `trim` before it. Candidates are the triangles whose boxes meet the segment C -> X. False says
  /// nothing (several triangles together may block every segment).
  bool ConeBlocked(const Vec3& C, double r, const Vec3& X, double trim) const;

  std::size_t triangle_count() const { return triangles_.size(); }
  /// Bytes held (triangles and hierarchy), for the memory budget.
  std::size_t bytes() const {
    return triangles_.capacity() * sizeof(triangles_[0]) + nodes_.capacity() * sizeof(Node);
  }

 private:
  struct Node {
    Aabb box;
    int left = -1, right = -1;  // children, or -1 for a leaf
    int first = 0, count = 0;   // leaf: triangles_[first, first + count)
  };
  int Build(int first, int count);

  std::vector<std::array<Vec3, 3>> triangles_;
  std::vector<Node> nodes_;
};

/// Distance from `p` to the triangle (a, b, c), closest point on the face, an edge or a corner
/// (Ericson, Real-Time Collision Detection, 5.1.5). Degenerate triangles are handled as segments.
double PointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace pandora
