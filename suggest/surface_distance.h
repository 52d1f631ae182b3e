#pragma once
/// \file surface_distance.h
/// Exact distance from a point to the nearest triangle of a mesh (double precision), for the
/// clearance `pandora suggest` keeps between a camera centre and every scene surface. A bounding
/// volume hierarchy (median splits, up to 4 triangles per leaf) prunes the search.

#include <array>
#include <limits>
#include <vector>

#include "analysis/geometry.h"

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

  std::size_t triangle_count() const { return triangles_.size(); }

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
