// Point-to-mesh distance for the suggestion's clearance (suggest/surface_distance.h).
#include "suggest/surface_distance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace pandora {
namespace {

double SegmentDistance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

// Distance from p to the box (0 inside).
double BoxDistance(const Aabb& box, const Vec3& p) {
  const Vec3 d = (box.min - p).cwiseMax(p - box.max).cwiseMax(Vec3::Zero());
  return d.norm();
}

}  // namespace

double PointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a;
  if (!(ab.cross(ac).squaredNorm() > 1e-30 * std::max(ab.squaredNorm(), ac.squaredNorm()) *
                                         std::max(ab.squaredNorm(), ac.squaredNorm())))
    return std::min({SegmentDistance(p, a, b), SegmentDistance(p, b, c), SegmentDistance(p, c, a)});
  // Voronoi regions of the corners, edges and face (Ericson 5.1.5).
  const Vec3 ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return (p - (a + v * ab + w * ac)).norm();
}

SurfaceDistance::SurfaceDistance(const TriangleMesh& mesh) {
  triangles_.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles)
    triangles_.push_back({mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]});
  if (!triangles_.empty()) Build(0, static_cast<int>(triangles_.size()));
}

int SurfaceDistance::Build(int first, int count) {
  Node node;
  node.first = first;
  node.count = count;
  for (int i = first; i < first + count; ++i)
    for (const Vec3& v : triangles_[i]) node.box.Extend(v);
  const int index = static_cast<int>(nodes_.size());
  nodes_.push_back(node);
  if (count <= 4) return index;
  // Split at the median centroid along the longest axis of the box.
  const Vec3 size = node.box.size();
  int axis = 0;
  if (size.y() > size[axis]) axis = 1;
  if (size.z() > size[axis]) axis = 2;
  auto centroid = [&](const std::array<Vec3, 3>& t) {
    return t[0][axis] + t[1][axis] + t[2][axis];
  };
  const int mid = first + count / 2;
  std::nth_element(triangles_.begin() + first, triangles_.begin() + mid,
                   triangles_.begin() + first + count,
                   [&](const auto& x, const auto& y) { return centroid(x) < centroid(y); });
  const int left = Build(first, mid - first);
  const int right = Build(mid, first + count - mid);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

double SurfaceDistance::Distance(const Vec3& p, double limit) const {
  double best = limit;
  if (nodes_.empty()) return best;
  // Depth-first, nearer child first; boxes no nearer than the best so far are skipped.
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const Node& n = nodes_[stack.back()];
    stack.pop_back();
    if (BoxDistance(n.box, p) >= best) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i)
        best = std::min(
            best, PointTriangleDistance(p, triangles_[i][0], triangles_[i][1], triangles_[i][2]));
      continue;
    }
    const double dl = BoxDistance(nodes_[n.left].box, p), dr = BoxDistance(nodes_[n.right].box, p);
    if (dl < dr) {
      stack.push_back(n.right);
      stack.push_back(n.left);
    } else {
      stack.push_back(n.left);
      stack.push_back(n.right);
    }
  }
  return best;
}

}  // namespace pandora
