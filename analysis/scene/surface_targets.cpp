#include "analysis/scene/surface_targets.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/seeded.h"

namespace pandora {
void SampleSurface(const TriangleMesh& mesh, int count, std::uint64_t seed,
                   std::vector<Vec3>* points, std::vector<Vec3>* normals,
                   std::vector<int>* triangles, std::vector<Eigen::Vector2d>* barycentric) {
  points->clear();
  normals->clear();
  if (triangles) triangles->clear();
  if (barycentric) barycentric->clear();
  std::vector<double> cumulative;
  cumulative.reserve(mesh.triangles.size());
  double total = 0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative.push_back(total);
  }
  if (!(total > 0) || count <= 0) return;
  for (int i = 0; i < count; ++i) {
    const double pick = SeededUniform(seed, std::uint64_t(i), 0) * total;
    const std::size_t k = std::min<std::size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(),
        cumulative.size() - 1);
    const Eigen::Vector3i& t = mesh.triangles[k];
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    // Uniform on the triangle: (1 - sqrt(r1)) a + sqrt(r1) (1 - r2) b + sqrt(r1) r2 c.
    const double r1 = std::sqrt(SeededUniform(seed, std::uint64_t(i), 1)),
                 r2 = SeededUniform(seed, std::uint64_t(i), 2);
    points->push_back((1 - r1) * a + r1 * (1 - r2) * b + r1 * r2 * c);
    normals->push_back((b - a).cross(c - a).normalized());
    if (triangles) triangles->push_back(int(k));
    if (barycentric) barycentric->emplace_back(r1 * (1 - r2), r1 * r2);
  }
}

namespace {

// True when `p`, on the surface of object `own`, lies inside another part's capsule.
bool InsideAnotherPart(const TargetSurface& surface, const Vec3& p, std::size_t own) {
  for (std::size_t o = 0; o < surface.capsules.size(); ++o) {
    if (o == own || !surface.capsules[o]) continue;
    const SceneObject::CapsuleAxis& c = *surface.capsules[o];
    const Vec3 ab = c.b - c.a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - c.a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    if ((c.a + t * ab - p).norm() < c.radius) return true;
  }
  return false;
}

}  // namespace

SurfacePoints SampleTargetPoints(const TargetSurface& surface, int count, std::uint64_t seed) {
  SurfacePoints out;
  const bool capsules = std::any_of(surface.capsules.begin(), surface.capsules.end(),
                                    [](const auto& c) { return c.has_value(); });
  if (!capsules) {
    SampleSurface(surface.mesh, count, seed, &out.points, &out.normals, &out.triangles,
                  &out.barycentric);
    return out;
  }
  // A person's parts overlap at the joints: keep the first `count` draws that are not inside
  // another part (draw i is the same whatever the count, so drawing more keeps the first ones).
  for (int drawn = 2 * count; drawn <= 64 * count; drawn *= 2) {
    SurfacePoints all;
    SampleSurface(surface.mesh, drawn, seed, &all.points, &all.normals, &all.triangles,
                  &all.barycentric);
    out = SurfacePoints();
    for (std::size_t i = 0; i < all.points.size() && int(out.points.size()) < count; ++i) {
      const std::size_t own =
          std::size_t(std::upper_bound(surface.first_triangle.begin(), surface.first_triangle.end(),
                                       all.triangles[i]) -
                      surface.first_triangle.begin() - 1);
      if (InsideAnotherPart(surface, all.points[i], own)) continue;
      out.points.push_back(all.points[i]);
      out.normals.push_back(all.normals[i]);
      out.triangles.push_back(all.triangles[i]);
      out.barycentric.push_back(all.barycentric[i]);
    }
    if (int(out.points.size()) == count) break;
  }
  return out;
}

void PlaceTargetPoints(const Scene& scene, const TargetSurface& surface, const SurfacePoints& rest,
                       const TimeSample& sample, std::vector<Vec3>* points,
                       std::vector<Vec3>* normals) {
  points->resize(rest.points.size());
  normals->resize(rest.points.size());
  if (!surface.skinned) {
    const Eigen::Isometry3d T = MotionTransform(scene, surface.motion, sample);
    for (std::size_t i = 0; i < rest.points.size(); ++i) {
      (*points)[i] = T * rest.points[i];
      (*normals)[i] = T.linear() * rest.normals[i];
    }
    return;
  }
  std::vector<Vec3> posed;
  posed.reserve(surface.mesh.vertices.size());
  for (int o : surface.objects) {
    const std::vector<Vec3> v = ObjectVerticesAt(scene, o, sample);
    posed.insert(posed.end(), v.begin(), v.end());
  }
  for (std::size_t i = 0; i < rest.points.size(); ++i) {
    const Eigen::Vector3i& t = surface.mesh.triangles[rest.triangles[i]];
    const Vec3 &a = posed[t[0]], &b = posed[t[1]], &c = posed[t[2]];
    const Eigen::Vector2d& w = rest.barycentric[i];
    (*points)[i] = (1 - w[0] - w[1]) * a + w[0] * b + w[1] * c;
    const Vec3 n = (b - a).cross(c - a);
    (*normals)[i] = n.norm() > 0 ? Vec3(n.normalized()) : rest.normals[i];
  }
}

TargetSurface FindTargetSurface(const Scene& scene, const std::string& name) {
  TargetSurface t;
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    if (!scene.objects[o].InGroup(name)) continue;
    if (t.mesh.triangles.empty() && t.motion < 0)
      for (std::size_t k = 0; k < scene.motions.size(); ++k)
        for (int member : scene.motions[k].objects)
          if (member == int(o)) t.motion = int(k);
    t.first_triangle.push_back(int(t.mesh.triangles.size()));
    t.capsules.push_back(scene.objects[o].capsule);
    t.mesh.Append(scene.objects[o].mesh);
    t.objects.push_back(int(o));
    t.skinned |= scene.objects[o].skin >= 0;
  }
  return t;
}

std::vector<SurfaceTargetResult> EvaluateSurfaceTargets(const Scene& scene, const Rig& rig,
                                                        const RigidPartsRayCaster& parts,
                                                        const std::vector<TimeSample>& samples_in,
                                                        int min_cameras) {
  std::vector<SurfaceTargetResult> out;
  if (!scene.study.targets) return out;
  const SurfaceTargets& spec = *scene.study.targets;
  const std::vector<TimeSample> samples = SamplesOrAsPlaced(samples_in);
  const int kmax = std::max(3, min_cameras);
  // Each sample's caster and tester, built once for all targets.
  std::vector<std::unique_ptr<RayCaster>> casters;
  std::vector<std::unique_ptr<VisibilityTester>> testers;
  for (const TimeSample& s : samples) {
    casters.push_back(CasterAtSample(parts, scene, s));
    testers.push_back(std::make_unique<VisibilityTester>(rig.cameras, *casters.back(),
                                                         scene.ContentBounds().diagonal()));
  }
  for (std::size_t g = 0; g < spec.names.size(); ++g) {
    const std::string& name = spec.names[g];
    const TargetSurface surface = FindTargetSurface(scene, name);
    const auto t0 = std::chrono::steady_clock::now();
    SurfaceTargetResult r;
    r.name = name;
    const SurfacePoints rest = SampleTargetPoints(surface, spec.points, spec.seed + g);
    const std::vector<Vec3>& points = rest.points;
    std::vector<Vec3> placed, placed_normals;
    r.points = int(points.size());
    r.samples = int(samples.size());
    r.cameras.assign(std::size_t(r.samples) * r.points, 0);
    std::vector<std::vector<std::int64_t>> seen_by(
        samples.size(), std::vector<std::int64_t>(rig.cameras.size(), 0));
    const std::size_t pixel_count = scene.study.pixel_targets.size();
    std::vector<std::int64_t> pixel_pairs(pixel_count, 0);
    std::vector<std::uint16_t> pixel_cameras(pixel_count * points.size());
    for (std::size_t s = 0; s < samples.size(); ++s) {
      PlaceTargetPoints(scene, surface, rest, samples[s], &placed, &placed_normals);
      std::vector<std::vector<std::uint8_t>> sees(rig.cameras.size(),
                                                  std::vector<std::uint8_t>(points.size(), 0));
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, points.size(), 64), [&](const auto& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i) {
              const Vec3 &X = placed[i], &n = placed_normals[i];
              int count = 0;
              for (std::size_t p = 0; p < pixel_count; ++p)
                pixel_cameras[p * points.size() + i] = 0;
              for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
                if (!rig.cameras[c].enabled) continue;
                Mat23 J;
                if (testers[s]->Test(int(c), X, &n, &J) == ViewResult::kSeen) {
                  ++count;
                  sees[c][i] = 1;
                  const double density = PixelDensity(J);
                  for (std::size_t p = 0; p < pixel_count; ++p)
                    if (density >= scene.study.pixel_targets[p].px_per_m())
                      ++pixel_cameras[p * points.size() + i];
                }
              }
              r.cameras[s * points.size() + i] = std::uint16_t(std::min(count, 65535));
            }
          });
      for (std::size_t c = 0; c < rig.cameras.size(); ++c)
        for (std::uint8_t v : sees[c]) seen_by[s][c] += v;
      for (std::size_t p = 0; p < pixel_count; ++p)
        for (std::size_t i = 0; i < points.size(); ++i)
          pixel_pairs[p] += pixel_cameras[p * points.size() + i] >= min_cameras;
    }
    const double pairs = double(r.points) * r.samples;
    r.share_ge.assign(kmax, 0.0);
    r.sample_share.assign(samples.size(), 0.0);
    std::vector<std::uint8_t> always(points.size(), 1);
    for (std::size_t s = 0; s < samples.size(); ++s)
      for (std::size_t i = 0; i < points.size(); ++i) {
        const int n = r.cameras[s * points.size() + i];
        for (int k = 1; k <= std::min(n, kmax); ++k) r.share_ge[k - 1] += 1;
        if (n >= min_cameras)
          r.sample_share[s] += 1;
        else
          always[i] = 0;
      }
    for (double& v : r.share_ge) v = pairs > 0 ? v / pairs : 0.0;
    for (double& v : r.sample_share) v = r.points > 0 ? v / r.points : 0.0;
    double a = 0;
    for (std::uint8_t v : always) a += v;
    r.always = r.points > 0 ? a / r.points : 0.0;
    r.worst_sample = int(std::min_element(r.sample_share.begin(), r.sample_share.end()) -
                         r.sample_share.begin());
    for (std::size_t p = 0; p < pixel_count; ++p)
      r.pixel_share.push_back(pairs > 0 ? double(pixel_pairs[p]) / pairs : 0.0);
    r.per_camera.assign(rig.cameras.size(), 0.0);
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
      double n = 0;
      for (std::size_t s = 0; s < samples.size(); ++s) n += double(seen_by[s][c]);
      r.per_camera[c] = pairs > 0 ? n / pairs : 0.0;
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace pandora
