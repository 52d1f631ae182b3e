#include "analysis/geometry/ray_caster.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace pandora {

void RayCaster::OccludedBatch(const std::vector<Ray>& rays, std::vector<uint8_t>* occluded) const {
  occluded->assign(rays.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        (*occluded)[i] = Occluded(rays[i]) ? 1 : 0;
                    });
}

void RayCaster::OccludedPacket(const Ray* rays, std::size_t count, uint8_t* occluded) const {
  for (std::size_t i = 0; i < count; ++i) occluded[i] = Occluded(rays[i]) ? 1 : 0;
}

void RayCaster::OccludedFan(const Fan& fan, std::size_t count, uint8_t* occluded) const {
  Ray rays[256];
  for (std::size_t start = 0; start < count; start += 256) {
    const std::size_t n = std::min<std::size_t>(256, count - start);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k = fan.at(start + i);
      rays[i].origin = fan.origin;
      rays[i].direction = Vec3(fan.dx[k], fan.dy[k], fan.dz[k]);
      rays[i].t_near = fan.t_near[k];
      rays[i].t_far = fan.t_far[k];
    }
    OccludedPacket(rays, n, occluded + start);
  }
}

void RayCaster::IntersectPacket(const Ray* rays, std::size_t count,
                                std::optional<RayHit>* hits) const {
  for (std::size_t i = 0; i < count; ++i) hits[i] = Intersect(rays[i]);
}

namespace {

class BruteForceRayCaster final : public RayCaster {
 public:
  explicit BruteForceRayCaster(const TriangleMesh& mesh) : mesh_(mesh), bounds_(mesh.Bounds()) {}
  const Aabb& bounds() const override { return bounds_; }

  bool Occluded(const Ray& ray) const override {
    for (std::size_t i = 0; i < mesh_.triangles.size(); ++i)
      if (HitTriangle(ray, static_cast<int>(i), ray.t_far)) return true;
    return false;
  }

  std::optional<RayHit> Intersect(const Ray& ray) const override {
    std::optional<RayHit> best;
    double t_max = ray.t_far;
    for (std::size_t i = 0; i < mesh_.triangles.size(); ++i) {
      if (auto t = HitTriangle(ray, static_cast<int>(i), t_max)) {
        t_max = *t;
        const Eigen::Vector3i& tri = mesh_.triangles[i];
        const Vec3 n = (mesh_.vertices[tri[1]] - mesh_.vertices[tri[0]])
                           .cross(mesh_.vertices[tri[2]] - mesh_.vertices[tri[0]]);
        best = RayHit{*t, static_cast<int>(i), n.normalized()};
      }
    }
    return best;
  }

  const char* name() const override { return "brute-force"; }
  std::size_t triangle_count() const override { return mesh_.triangles.size(); }

 private:
  // Moller-Trumbore in double precision. Returns t when the ray hits triangle `index` (closed
  // triangle, either side) with t_near < t < t_max.
  std::optional<double> HitTriangle(const Ray& ray, int index, double t_max) const {
    const Eigen::Vector3i& tri = mesh_.triangles[index];
    const Vec3& a = mesh_.vertices[tri[0]];
    const Vec3 e1 = mesh_.vertices[tri[1]] - a;
    const Vec3 e2 = mesh_.vertices[tri[2]] - a;
    const Vec3 p = ray.direction.cross(e2);
    const double det = e1.dot(p);
    if (det == 0.0 || !std::isfinite(det)) return std::nullopt;
    const double inv = 1.0 / det;
    const Vec3 s = ray.origin - a;
    const double u = s.dot(p) * inv;
    if (u < 0.0 || u > 1.0) return std::nullopt;
    const Vec3 q = s.cross(e1);
    const double v = ray.direction.dot(q) * inv;
    if (v < 0.0 || u + v > 1.0) return std::nullopt;
    const double t = e2.dot(q) * inv;
    if (t > ray.t_near && t < t_max) return t;
    return std::nullopt;
  }

  TriangleMesh mesh_;
  Aabb bounds_;
};

}  // namespace

std::unique_ptr<RayCaster> MakeBruteForceRayCaster(const TriangleMesh& mesh) {
  return std::make_unique<BruteForceRayCaster>(mesh);
}

}  // namespace pandora
