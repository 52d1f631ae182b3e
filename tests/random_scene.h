#pragma once
// Randomized scenes and a grazing classifier shared by the ray-caster and visibility tests.

#include <algorithm>
#include <cmath>
#include <random>

#include "analysis/geometry/geometry.h"

namespace pandora::testing {

/// Random rotated boxes and loose triangles inside [offset, offset + scale]^3.
inline TriangleMesh RandomScene(std::mt19937_64& rng, double scale, const Vec3& offset, int boxes,
                                int loose_triangles) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TriangleMesh mesh;
  auto random_point = [&]() -> Vec3 { return offset + scale * Vec3(u(rng), u(rng), u(rng)); };
  for (int b = 0; b < boxes; ++b) {
    const Vec3 c = random_point();
    const Vec3 half =
        scale * Vec3(0.02 + 0.08 * u(rng), 0.02 + 0.08 * u(rng), 0.02 + 0.08 * u(rng));
    const Mat3 r =
        Eigen::Quaterniond(
            Eigen::Vector4d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized())
            .toRotationMatrix();
    const int base = static_cast<int>(mesh.vertices.size());
    for (int i = 0; i < 8; ++i) {
      const Vec3 s((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
      mesh.vertices.push_back(c + r * s.cwiseProduct(half));
    }
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
      mesh.triangles.emplace_back(base + q[0], base + q[1], base + q[2]);
      mesh.triangles.emplace_back(base + q[0], base + q[2], base + q[3]);
    }
  }
  for (int t = 0; t < loose_triangles; ++t) {
    const Vec3 a = random_point();
    const Vec3 e1 = scale * 0.2 * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    const Vec3 e2 = scale * 0.2 * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    const int base = static_cast<int>(mesh.vertices.size());
    mesh.vertices.push_back(a);
    mesh.vertices.push_back(a + e1);
    mesh.vertices.push_back(a + e2);
    mesh.triangles.emplace_back(base, base + 1, base + 2);
  }
  return mesh;
}

/// Distance between segments [p0, p1] and [q0, q1].
inline double SegmentSegmentDistance(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                     const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 1e-300 && e <= 1e-300) return r.norm();
  if (a <= 1e-300) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-300) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

/// Distance from point p to triangle abc.
inline double PointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double nn = n.squaredNorm();
  if (nn > 0) {
    const Vec3 q = p - n * (n.dot(p - a) / nn);  // projection on the plane
    const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                        (a - c).cross(q - c).dot(n) >= 0;
    if (inside) return (p - q).norm();
  }
  return std::min({SegmentSegmentDistance(p, p, a, b), SegmentSegmentDistance(p, p, b, c),
                   SegmentSegmentDistance(p, p, c, a)});
}

/// True when the segment [p0, p1] comes within `tol` of any triangle edge, or either end lies
/// within `tol` of any triangle (except `own_triangle`, the one a surface point lies on): the cases
/// where single- and double-precision casters may legitimately disagree (grazing). Anything else
/// has one right answer.
inline bool IsGrazing(const TriangleMesh& mesh, const Vec3& p0, const Vec3& p1, double tol,
                      int own_triangle = -1) {
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    const Vec3& a = mesh.vertices[t[0]];
    const Vec3& b = mesh.vertices[t[1]];
    const Vec3& c = mesh.vertices[t[2]];
    if (SegmentSegmentDistance(p0, p1, a, b) < tol || SegmentSegmentDistance(p0, p1, b, c) < tol ||
        SegmentSegmentDistance(p0, p1, c, a) < tol)
      return true;
    if (static_cast<int>(i) == own_triangle) continue;
    if (PointTriangleDistance(p0, a, b, c) < tol || PointTriangleDistance(p1, a, b, c) < tol)
      return true;
  }
  return false;
}

}  // namespace pandora::testing
