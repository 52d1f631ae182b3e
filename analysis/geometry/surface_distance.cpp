// Point-to-mesh distance and cone certificates (analysis/geometry/surface_distance.h).
#include "analysis/geometry/surface_distance.h"

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

// Whether the segment origin + t e, t in [0, 1], meets the box grown by `pad` on every side.
bool SegmentMeetsBox(const Vec3& origin, const Vec3& e, const Aabb& box, double pad) {
  double t0 = 0.0, t1 = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = box.min[a] - pad, hi = box.max[a] + pad;
    if (e[a] == 0.0) {
      if (origin[a] < lo || origin[a] > hi) return false;
      continue;
    }
    double ta = (lo - origin[a]) / e[a], tb = (hi - origin[a]) / e[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

// Whether triangle (a, b, c) crosses every segment from a point of the ball B(C, r) to X, more than
// `trim` from both ends: X more than trim before the plane, the ball more than r + trim beyond it,
// and the ball more than r + trim inside each of the three planes through X and an edge (the
// pyramid of X's view of the triangle). A segment from Y in the ball to X then runs from beyond the
// plane to X inside the pyramid, and crosses the plane inside the pyramid: in the triangle.
bool BlocksCone(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& C, double r, const Vec3& X,
                double trim) {
  const Vec3 n = (b - a).cross(c - a);
  const double length = n.norm();
  if (!(length > 0)) return false;
  const Vec3 u = n / length;
  double dX = u.dot(X - a), dC = u.dot(C - a);
  if (dX < 0) dX = -dX, dC = -dC;
  if (!(dX > trim) || !(-dC > r + trim)) return false;
  const std::array<const Vec3*, 3> v{&a, &b, &c};
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = *v[k];
    const Vec3& q = *v[(k + 1) % 3];
    const Vec3& o = *v[(k + 2) % 3];
    Vec3 m = (p - X).cross(q - X);
    const double m_length = m.norm();
    if (!(m_length > 0)) return false;
    m /= m_length;
    const double side = m.dot(o - X);
    if (side < 0)
      m = -m;
    else if (!(side > 0))
      return false;
    if (!(m.dot(C - X) > r + trim)) return false;
  }
  return true;
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
  // Depth-first, nearer child first; boxes no nearer than the best so far are skipped. The
  // hierarchy halves its triangles per level, so a stack of 64 holds any mesh that fits an int.
  std::array<int, 64> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (BoxDistance(n.box, p) >= best) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i)
        best = std::min(
            best, PointTriangleDistance(p, triangles_[i][0], triangles_[i][1], triangles_[i][2]));
      continue;
    }
    const double dl = BoxDistance(nodes_[n.left].box, p), dr = BoxDistance(nodes_[n.right].box, p);
    if (dl < dr) {
      stack[top++] = n.right;
      stack[top++] = n.left;
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
  return best;
}

bool SurfaceDistance::ConeClear(const Vec3& C, double r, const Vec3& X, double trim,
                                int max_steps) const {
  if (nodes_.empty()) return true;
  const Vec3 e = X - C;
  const double D = e.norm();
  if (!(r >= 0) || !(trim >= 0) || !(D - trim > r)) return false;
  // A segment from Y (|Y - C| <= r) keeps the fractions [trim / |X - Y|, 1 - trim / |X - Y|] of its
  // way, |X - Y| <= D + r; its point at fraction s is (1 - s)(Y - C) from C + s e.
  const double s0 = trim / (D + r), s1 = 1.0 - s0;
  double s = s0;
  for (int step = 0; step < max_steps; ++step) {
    // Plus `trim`: every segment keeps that much off every triangle, so rounding cannot carry the
    // march through a surface it approaches (it would stall there and run out of steps instead).
    const double need = (1.0 - s) * r + trim;
    // Far enough to cover the rest: the distance drops at most D per unit of s, the need by r.
    const double enough = need + (s1 - s) * (D - r);
    const double d = Distance(C + s * e, enough);
    if (d >= enough) return true;
    if (!(d > need)) return false;
    s += (d - need) / (D - r);
    if (s >= s1) return true;
  }
  return false;
}

bool SurfaceDistance::ConeBlocked(const Vec3& C, double r, const Vec3& X, double trim) const {
  if (nodes_.empty()) return false;
  const Vec3 e = X - C;
  // Boxes grown by a relative 1e-12 so rounding in the slab test cannot drop a crossed triangle.
  const double pad = 1e-12 * (C.cwiseAbs().maxCoeff() + X.cwiseAbs().maxCoeff() + e.norm());
  std::array<int, 64> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (!SegmentMeetsBox(C, e, n.box, pad)) continue;
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i)
        if (BlocksCone(triangles_[i][0], triangles_[i][1], triangles_[i][2], C, r, X, trim))
          return true;
      continue;
    }
    stack[top++] = n.left;
    stack[top++] = n.right;
  }
  return false;
}

}  // namespace pandora
