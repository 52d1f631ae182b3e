#pragma once
/// \file geometry.h
/// Small geometric value types shared by every library. Double precision; metres; world frame is
/// right-handed with Z up.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <limits>
#include <vector>

namespace pandora {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Mat23 = Eigen::Matrix<double, 2, 3>;

/// Axis-aligned box. Empty when min > max on any axis (the default).
struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const { return (min.array() > max.array()).any(); }
  void Extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void Extend(const Aabb& b) {
    if (b.empty()) return;
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  bool Contains(const Vec3& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  Vec3 center() const { return 0.5 * (min + max); }
  Vec3 size() const { return empty() ? Vec3::Zero() : Vec3(max - min); }
  double diagonal() const { return size().norm(); }
};

/// Indexed triangle mesh in world coordinates (after the instance transform).
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< Counter-clockwise seen from outside.
  /// Texture coordinates of each triangle's three corners (per corner, so seams survive welding),
  /// parallel to `triangles`; empty when the mesh has none.
  std::vector<std::array<Eigen::Vector2d, 3>> corner_uvs;

  Aabb Bounds() const {
    Aabb b;
    for (const Vec3& v : vertices) b.Extend(v);
    return b;
  }
  /// Appends `other`, offsetting its indices.
  void Append(const TriangleMesh& other) {
    const int offset = static_cast<int>(vertices.size());
    vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
    const std::size_t before = triangles.size();
    for (const Eigen::Vector3i& t : other.triangles)
      triangles.push_back(t + Eigen::Vector3i::Constant(offset));
    if (!corner_uvs.empty() || !other.corner_uvs.empty()) {  // keep both parallel to triangles
      corner_uvs.resize(before);
      if (other.corner_uvs.empty())
        corner_uvs.resize(triangles.size());
      else
        corner_uvs.insert(corner_uvs.end(), other.corner_uvs.begin(), other.corner_uvs.end());
    }
  }
};

}  // namespace pandora
