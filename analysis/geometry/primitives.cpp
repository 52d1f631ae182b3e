#include "analysis/geometry/primitives.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "analysis/util/units.h"

namespace pandora {
namespace {

// A point of a surface of revolution's profile: distance from the z axis and height.
struct ProfilePoint {
  double r;
  double z;
};

// Revolves `profile` (listed from top to bottom; first and last points on the axis, r == 0, and
// only those) around the z axis in `segments` slices. Each interior profile point becomes a ring of
// `segments` vertices, the end points become single pole vertices, and consecutive rings are joined
// by quads split in two triangles, counter-clockwise seen from outside.
TriangleMesh Revolve(const std::vector<ProfilePoint>& profile, int segments) {
  TriangleMesh mesh;
  const int rings = static_cast<int>(profile.size()) - 2;
  mesh.vertices.reserve(2 + static_cast<size_t>(rings) * segments);
  mesh.vertices.emplace_back(0.0, 0.0, profile.front().z);
  std::vector<double> cos_phi(segments), sin_phi(segments);
  for (int j = 0; j < segments; ++j) {
    const double phi = 2.0 * kPi * j / segments;
    cos_phi[j] = std::cos(phi);
    sin_phi[j] = std::sin(phi);
  }
  for (int i = 1; i <= rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      mesh.vertices.emplace_back(profile[i].r * cos_phi[j], profile[i].r * sin_phi[j],
                                 profile[i].z);
    }
  }
  const int top = 0;
  const int bottom = static_cast<int>(mesh.vertices.size());
  mesh.vertices.emplace_back(0.0, 0.0, profile.back().z);

  auto ring_vertex = [segments](int ring, int j) {
    return 1 + (ring - 1) * segments + j % segments;
  };
  // Seen from outside at azimuth phi, "down" the profile and "forward" in phi: the quad
  // a = (upper, j), b = (upper, j+1), c = (lower, j+1), d = (lower, j) is split into (a, d, c) and
  // (a, c, b), both with outward normals.
  for (int j = 0; j < segments; ++j) {
    mesh.triangles.emplace_back(top, ring_vertex(1, j), ring_vertex(1, j + 1));
  }
  for (int i = 1; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const int a = ring_vertex(i, j), b = ring_vertex(i, j + 1);
      const int c = ring_vertex(i + 1, j + 1), d = ring_vertex(i + 1, j);
      mesh.triangles.emplace_back(a, d, c);
      mesh.triangles.emplace_back(a, c, b);
    }
  }
  for (int j = 0; j < segments; ++j) {
    mesh.triangles.emplace_back(ring_vertex(rings, j), bottom, ring_vertex(rings, j + 1));
  }
  return mesh;
}

// Profile of a sphere of `radius` centred at height `z0`, colatitudes from `theta0` to `theta1`
// (radians, 0 = north pole) in `stacks` equal steps; end points included. Poles and the equator get
// exact coordinates.
void AppendSphereProfile(double radius, double z0, double theta0, double theta1, int stacks,
                         std::vector<ProfilePoint>* profile) {
  for (int k = 0; k <= stacks; ++k) {
    const double theta = theta0 + (theta1 - theta0) * k / stacks;
    double r = radius * std::sin(theta), z = radius * std::cos(theta);
    if (theta == 0.0 || theta == kPi) r = 0.0;
    if (theta == 0.5 * kPi) {
      r = radius;
      z = 0.0;
    }
    if (theta == 0.0) z = radius;
    if (theta == kPi) z = -radius;
    profile->push_back({r, z0 + z});
  }
}

std::vector<ProfilePoint> SphereProfile(double radius, int segments) {
  std::vector<ProfilePoint> profile;
  const int stacks = std::max(2, segments / 2);
  // Two halves so the equator is exact whenever `stacks` is even.
  if (stacks % 2 == 0) {
    AppendSphereProfile(radius, 0.0, 0.0, 0.5 * kPi, stacks / 2, &profile);
    profile.pop_back();
    AppendSphereProfile(radius, 0.0, 0.5 * kPi, kPi, stacks / 2, &profile);
  } else {
    AppendSphereProfile(radius, 0.0, 0.0, kPi, stacks, &profile);
  }
  return profile;
}

// Volume of the solid Revolve(profile, segments) encloses: a stack of frustums whose parallel faces
// are regular polygons of circumradius r (area segments/2 r^2 sin(2 pi / segments)).
double RevolvedVolume(const std::vector<ProfilePoint>& profile, int segments) {
  const double polygon_factor = 0.5 * segments * std::sin(2.0 * kPi / segments);
  double volume = 0;
  for (size_t i = 0; i + 1 < profile.size(); ++i) {
    const double a1 = polygon_factor * profile[i].r * profile[i].r;
    const double a2 = polygon_factor * profile[i + 1].r * profile[i + 1].r;
    const double h = profile[i].z - profile[i + 1].z;
    volume += h / 3.0 * (a1 + a2 + std::sqrt(a1 * a2));
  }
  return volume;
}

}  // namespace

TriangleMesh MakeBox(const Vec3& size) {
  const Vec3 h = 0.5 * size;
  TriangleMesh mesh;
  // Vertex i has x = +h.x when bit 0 is set, y = +h.y for bit 1, z = +h.z for bit 2.
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.emplace_back((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(),
                               (i & 4) ? h.z() : -h.z());
  }
  // Each face as a counter-clockwise quad seen from outside, split along its first diagonal.
  const int faces[6][4] = {
      {0, 2, 3, 1},  // -z
      {4, 5, 7, 6},  // +z
      {0, 1, 5, 4},  // -y
      {2, 6, 7, 3},  // +y
      {0, 4, 6, 2},  // -x
      {1, 3, 7, 5},  // +x
  };
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(f[0], f[1], f[2]);
    mesh.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return mesh;
}

TriangleMesh MakeSphere(double radius, int segments) {
  return Revolve(SphereProfile(radius, segments), segments);
}

double TessellatedSphereVolume(double radius, int segments) {
  return RevolvedVolume(SphereProfile(radius, segments), segments);
}

TriangleMesh MakeCylinder(double radius, double height, int segments) {
  const double h = 0.5 * height;
  return Revolve({{0.0, h}, {radius, h}, {radius, -h}, {0.0, -h}}, segments);
}

TriangleMesh MakeCapsule(double radius, double length, int segments) {
  const int stacks = std::max(1, segments / 4);
  const double h = 0.5 * length;
  std::vector<ProfilePoint> profile;
  AppendSphereProfile(radius, h, 0.0, 0.5 * kPi, stacks, &profile);
  std::vector<ProfilePoint> lower;
  AppendSphereProfile(radius, -h, 0.5 * kPi, kPi, stacks, &lower);
  // Without a straight part the two equators coincide: keep one.
  profile.insert(profile.end(), lower.begin() + (length > 0 ? 0 : 1), lower.end());
  return Revolve(profile, segments);
}

TriangleMesh MakePlane(const Vec2& size) {
  const double hx = 0.5 * size.x(), hy = 0.5 * size.y();
  TriangleMesh mesh;
  mesh.vertices = {Vec3(-hx, -hy, 0), Vec3(hx, -hy, 0), Vec3(hx, hy, 0), Vec3(-hx, hy, 0)};
  mesh.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  return mesh;
}

double SignedVolume(const TriangleMesh& mesh) {
  // Sum of signed tetrahedra against a reference point near the mesh, which keeps the rounding
  // error proportional to the mesh's size rather than its distance from the origin.
  if (mesh.vertices.empty()) return 0.0;
  const Vec3 origin = mesh.vertices.front();
  double six_volume = 0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Vec3 a = mesh.vertices[t[0]] - origin;
    const Vec3 b = mesh.vertices[t[1]] - origin;
    const Vec3 c = mesh.vertices[t[2]] - origin;
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

ClosedCheck CheckClosed(const TriangleMesh& mesh) {
  ClosedCheck result;
  if (mesh.triangles.empty()) {
    result.closed = false;
    result.description = "it has no triangles";
    return result;
  }
  auto key = [](int a, int b) { return (uint64_t{static_cast<uint32_t>(a)} << 32) | uint32_t(b); };
  std::unordered_map<uint64_t, int> directed;
  directed.reserve(mesh.triangles.size() * 3);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) {
      if (result.closed) {
        result.closed = false;
        result.example_a = mesh.vertices[tri[0]];
        result.example_b = mesh.vertices[tri[1]];
        result.description = "triangle " + std::to_string(t) + " is degenerate (repeats a vertex)";
      }
      ++result.bad_edges;
      continue;
    }
    for (int e = 0; e < 3; ++e) ++directed[key(tri[e], tri[(e + 1) % 3])];
  }
  for (const auto& [k, forward] : directed) {
    const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    const auto it = directed.find(key(b, a));
    const int backward = it == directed.end() ? 0 : it->second;
    if (forward == 1 && backward == 1) continue;
    // Count each undirected edge once: from its smaller end, or from the only direction present.
    if (backward > 0 && a > b) continue;
    ++result.bad_edges;
    if (!result.closed) continue;
    result.closed = false;
    result.example_a = mesh.vertices[a];
    result.example_b = mesh.vertices[b];
    const int uses = forward + backward;
    if (uses == 1) {
      result.description = "it has open boundary edges (an edge used by only one triangle)";
    } else if (uses > 2) {
      result.description =
          "it has non-manifold edges (an edge shared by " + std::to_string(uses) + " triangles)";
    } else {
      result.description =
          "its triangles are not consistently oriented (two triangles traverse an edge in the "
          "same direction)";
    }
  }
  return result;
}

TriangleMesh WeldVertices(const TriangleMesh& mesh) {
  TriangleMesh welded;
  // Ordered by exact coordinates; -0.0 and 0.0 compare equal, as they should.
  std::map<std::array<double, 3>, int> index_of;
  std::vector<int> remap(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& v = mesh.vertices[i];
    const auto [it, inserted] =
        index_of.emplace(std::array<double, 3>{v.x(), v.y(), v.z()}, int(welded.vertices.size()));
    if (inserted) welded.vertices.push_back(v);
    remap[i] = it->second;
  }
  welded.triangles.reserve(mesh.triangles.size());
  const bool uvs = mesh.corner_uvs.size() == mesh.triangles.size() && !mesh.corner_uvs.empty();
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    const Eigen::Vector3i r(remap[t[0]], remap[t[1]], remap[t[2]]);
    if (r[0] == r[1] || r[1] == r[2] || r[2] == r[0]) continue;
    welded.triangles.push_back(r);
    if (uvs) welded.corner_uvs.push_back(mesh.corner_uvs[i]);
  }
  return welded;
}

}  // namespace pandora
