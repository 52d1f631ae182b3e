// Suggest (issue 5), the parts without Ceres: target points, the exact evaluation, objectives, the
// pose chart of a selected camera, snapping, and the random-perturbation baseline.
#include "suggest/suggest.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <string>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/surface_targets.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "suggest/suggest_internal.h"

namespace pandora {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

double WrapDeg(double a) {
  a = std::fmod(a + 180.0, 360.0);
  if (a < 0) a += 360.0;
  return a - 180.0;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Objectives

std::optional<Objective> ParseObjective(const std::string& name) {
  Objective o;
  if (name == "coverage") {
    o.kind = ObjectiveKind::kCoverage;
    return o;
  }
  auto number = [](const std::string& s, double* v) {
    if (s.empty() || s.size() > 8) return false;
    char* end = nullptr;
    *v = std::strtod(s.c_str(), &end);
    return end && *end == '\0' && std::isfinite(*v);
  };
  double v = 0;
  if (name.rfind("coverage", 0) == 0 && number(name.substr(8), &v)) {
    if (v < 1 || v > 64 || v != std::floor(v)) return std::nullopt;
    o.kind = ObjectiveKind::kCoverage;
    o.k = static_cast<int>(v);
    return o;
  }
  if (name == "sigma-mean") {
    o.kind = ObjectiveKind::kSigmaMean;
    return o;
  }
  if (name.rfind("sigma-p", 0) == 0 && number(name.substr(7), &v)) {
    if (!(v > 0 && v <= 100)) return std::nullopt;
    o.kind = ObjectiveKind::kSigmaPercentile;
    o.percentile = v;
    return o;
  }
  if (name == "resolution") {
    o.kind = ObjectiveKind::kResolution;
    return o;
  }
  if (name == "mix") {
    o.kind = ObjectiveKind::kMix;
    return o;
  }
  if (name == "calibration") {
    o.kind = ObjectiveKind::kCalibration;
    return o;
  }
  if (name.size() > 3 && name.compare(name.size() - 3, 3, "-n1") == 0) {
    const std::optional<Objective> base = ParseObjective(name.substr(0, name.size() - 3));
    if (!base || base->kind != ObjectiveKind::kCoverage) return std::nullopt;
    o = *base;
    o.kind = ObjectiveKind::kCoverageN1;
    return o;
  }
  return std::nullopt;
}

std::string ObjectiveName(const Objective& o) {
  switch (o.kind) {
    case ObjectiveKind::kCoverage:
      return "coverage" + std::to_string(o.k);
    case ObjectiveKind::kSigmaMean:
      return "sigma-mean";
    case ObjectiveKind::kSigmaPercentile: {
      std::string p = Format("%g", o.percentile);
      return "sigma-p" + p;
    }
    case ObjectiveKind::kResolution:
      return "resolution";
    case ObjectiveKind::kMix:
      return "mix";
    case ObjectiveKind::kCoverageN1:
      return "coverage" + std::to_string(o.k) + "-n1";
    case ObjectiveKind::kCalibration:
      return "calibration";
  }
  return "?";
}

bool ObjectiveHigherIsBetter(const Objective& o) {
  return o.kind != ObjectiveKind::kSigmaMean && o.kind != ObjectiveKind::kSigmaPercentile;
}

// ---------------------------------------------------------------------------------------------
// Target points

std::vector<TargetPoint> SampleTargets(const Scene& scene, int count,
                                       const std::vector<std::string>& surfaces,
                                       bool include_region, std::uint64_t seed) {
  if (count < 1)
    throw InputError(scene.path, "", "the number of target points must be positive",
                     "use {points} 1000 or more");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<TargetPoint> out;
  const bool region = surfaces.empty() || include_region;
  const int region_count = surfaces.empty() ? count : (include_region ? count / 2 : 0);
  const int surface_count = count - region_count;

  if (region && region_count > 0) {
    const Region& r = scene.study.region;
    const Aabb& box = r.box;
    const Vec3 size = box.size();
    // Cells of equal volume: about region_count of them, stratified per axis.
    const double volume =
        std::max(size.x(), 1e-300) * std::max(size.y(), 1e-300) * std::max(size.z(), 1e-300);
    const double h = std::cbrt(volume / region_count);
    Eigen::Vector3i n;
    for (int a = 0; a < 3; ++a)
      n[a] = std::max(1, static_cast<int>(std::lround(size[a] / std::max(h, 1e-300))));
    while (static_cast<long long>(n.x()) * n.y() * n.z() > 4LL * region_count) {
      const int a = n.x() >= n.y() && n.x() >= n.z() ? 0 : (n.y() >= n.z() ? 1 : 2);
      n[a] = std::max(1, n[a] / 2);
    }
    std::vector<const SceneObject*> solids;
    for (const SceneObject& o : scene.objects) {
      if (!o.solid || o.mesh.triangles.empty()) continue;
      const Aabb b = o.mesh.Bounds();
      if ((b.max.array() < box.min.array()).any() || (b.min.array() > box.max.array()).any())
        continue;
      solids.push_back(&o);
    }
    std::vector<std::unique_ptr<InsideMesh>> inside;
    for (const SceneObject* o : solids) inside.push_back(std::make_unique<InsideMesh>(o->mesh));
    std::unique_ptr<InsideMesh> region_mesh;
    if (r.kind == Region::Kind::kMesh && !r.mesh.triangles.empty())
      region_mesh = std::make_unique<InsideMesh>(r.mesh);
    for (int i = 0; i < n.x(); ++i)
      for (int j = 0; j < n.y(); ++j)
        for (int k = 0; k < n.z(); ++k) {
          const Vec3 u(uni(rng), uni(rng), uni(rng));
          const Vec3 p =
              box.min + Vec3((i + u.x()) / n.x() * size.x(), (j + u.y()) / n.y() * size.y(),
                             (k + u.z()) / n.z() * size.z());
          if (region_mesh && !region_mesh->Inside(p)) continue;
          bool solid = false;
          for (const auto& s : inside) solid = solid || s->Inside(p);
          if (solid) continue;
          out.push_back({p, std::nullopt});
        }
  }

  if (!surfaces.empty() && surface_count > 0) {
    struct Tri {
      Vec3 a, b, c, n;
      double area;
    };
    std::vector<Tri> tris;
    for (const std::string& name : surfaces) {
      bool found = false;
      for (const SceneObject& o : scene.objects) {
        if (o.name != name && o.name.rfind(name + "/", 0) != 0) continue;
        found = true;
        for (const Eigen::Vector3i& t : o.mesh.triangles) {
          const Vec3& a = o.mesh.vertices[t[0]];
          const Vec3& b = o.mesh.vertices[t[1]];
          const Vec3& c = o.mesh.vertices[t[2]];
          const Vec3 cr = (b - a).cross(c - a);
          const double area = 0.5 * cr.norm();
          if (!(area > 0)) continue;
          tris.push_back({a, b, c, cr.normalized(), area});
        }
      }
      if (!found) {
        std::string names;
        for (const SceneObject& o : scene.objects) names += (names.empty() ? "" : ", ") + o.name;
        throw InputError("{target_surfaces}", "",
                         "no object called '" + name + "' in " + scene.path, "objects: " + names);
      }
    }
    if (tris.empty())
      throw InputError("{target_surfaces}", "", "the target surfaces have no area",
                       "name objects with triangles");
    std::vector<double> cumulative;
    double total = 0;
    for (const Tri& t : tris) cumulative.push_back(total += t.area);
    for (int s = 0; s < surface_count; ++s) {
      // Stratified in the cumulative area: one sample per equal-area slice.
      const double a = (s + uni(rng)) / surface_count * total;
      const std::size_t idx = std::min<std::size_t>(
          tris.size() - 1,
          std::upper_bound(cumulative.begin(), cumulative.end(), a) - cumulative.begin());
      const Tri& t = tris[idx];
      double r1 = uni(rng), r2 = uni(rng);
      if (r1 + r2 > 1) {
        r1 = 1 - r1;
        r2 = 1 - r2;
      }
      out.push_back({t.a + r1 * (t.b - t.a) + r2 * (t.c - t.a), t.n});
    }
  }
  if (out.empty())
    throw InputError(
        scene.path, "$.study.region", "no target point could be placed",
        "the region lies inside solid objects; move the region or name target surfaces");
  return out;
}

// ---------------------------------------------------------------------------------------------
// Perturbation (the Euler angles are analysis/geometry/pose.h)

Rig PerturbCameras(const Rig& rig, const std::vector<int>& cameras, double move, double rotate_deg,
                   std::uint64_t seed) {
  Rig out = rig;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto direction = [&]() {
    Vec3 d;
    do d = Vec3(normal(rng), normal(rng), normal(rng));
    while (d.norm() < 1e-6);
    return d.normalized();
  };
  for (int idx : cameras) {
    Camera& c = out.cameras.at(idx);
    const Vec3 t = direction() * move;
    // Pan / tilt away: the axis is perpendicular to the optical axis, so the view really turns.
    const Vec3 z = c.world_from_camera.linear().col(2);
    Vec3 axis = direction();
    axis = axis - axis.dot(z) * z;
    if (axis.norm() < 1e-6) axis = z.unitOrthogonal();
    axis.normalize();
    const Mat3 R =
        Eigen::AngleAxisd(Rad(rotate_deg), axis).toRotationMatrix() * c.world_from_camera.linear();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = R;
    pose.translation() = c.center() + t;
    c.world_from_camera = pose;
  }
  return out;
}

namespace suggest_detail {

double RotationAngleDeg(const Mat3& a, const Mat3& b) {
  return Deg(Eigen::AngleAxisd(a.transpose() * b).angle());
}

// ---------------------------------------------------------------------------------------------
// Exact evaluation

ExactEvaluator::ExactEvaluator(const Scene& scene, const Rig& rig, const RayCaster& caster,
                               const std::vector<TargetPoint>& targets, const Objective& objective,
                               const std::vector<int>& selected,
                               const std::vector<const RayCaster*>& sample_casters)
    : caster_(caster), targets_(targets), objective_(objective) {
  casters_ = sample_casters;
  if (casters_.empty()) casters_.push_back(&caster_);
  scene_scale_ = std::max(scene.Bounds().diagonal(), 1e-300);
  geometry_scale_ = std::max(scene.ContentBounds().diagonal(), 1e-300);
  region_scale_ = scene.study.region.box.diagonal();
  if (!(region_scale_ > 0)) region_scale_ = scene_scale_;
  sigma_cap_mm_ = region_scale_ * 1000.0;
  pixel_sigma_ = scene.study.pixel_sigma;
  std::vector<Camera> fixed;
  const std::set<int> sel(selected.begin(), selected.end());
  for (int i = 0; i < static_cast<int>(rig.cameras.size()); ++i) {
    if (sel.count(i)) {
      selected_.push_back(rig.cameras[i]);
      selected_rig_.push_back(i);
    } else if (rig.cameras[i].enabled) {
      fixed.push_back(rig.cameras[i]);
      fixed_rig_.push_back(i);
      fixed_ids_.push_back(rig.cameras[i].id);
    }
  }
  // A density scale for the soft maximum (keeps d^8 in range for any unit of length).
  Vec3 centre = scene.study.region.box.empty() ? Vec3::Zero() : scene.study.region.box.center();
  density_scale_ = 0;
  for (const Camera& c : rig.cameras) {
    const double dist = std::max((c.center() - centre).norm(), 1e-12 * scene_scale_);
    density_scale_ = std::max(density_scale_, c.model.intrinsics().fx / dist);
  }
  if (!(density_scale_ > 0) || !std::isfinite(density_scale_)) density_scale_ = 1;

  const std::size_t n = targets_.size();
  fixed_.count.assign(n, 0);
  fixed_.J.assign(n, Mat3::Zero());
  fixed_.dmax.assign(n, 0.0);
  fixed_.dpow.assign(n, 0.0);
  const bool n1 = objective_.kind == ObjectiveKind::kCoverageN1;
  if (n1) fixed_.seen_by.assign(n, {});
  const auto testers = Testers(fixed);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const TargetPoint& t = targets_[i];
                        const Vec3* normal = t.normal ? &*t.normal : nullptr;
                        const VisibilityTester& tester = *testers[Sample(i)];
                        for (int c = 0; c < static_cast<int>(fixed.size()); ++c) {
                          Mat23 A;
                          if (tester.Test(c, t.p, normal, &A) != ViewResult::kSeen) continue;
                          const double s = PixelSigma(fixed[c]);
                          fixed_.count[i] += 1;
                          fixed_.J[i] += A.transpose() * A / (s * s);
                          const double d = PixelDensity(A);
                          fixed_.dmax[i] = std::max(fixed_.dmax[i], d);
                          fixed_.dpow[i] += std::pow(d / density_scale_, kSoftMaxPower);
                          if (n1) fixed_.seen_by[i].push_back(c);
                        }
                      }
                    });

  if (objective_.kind == ObjectiveKind::kCalibration) {
    if (!scene.study.calibration)
      throw InputError(scene.path, "$.study.calibration",
                       "the calibration objective needs the study's calibration target",
                       "add \"calibration\": {\"target\": \"wand\"} (or a board) to \"study\"; "
                       "docs/calibration.md");
    calib_spec_ = *scene.study.calibration;
    // The poses are drawn once, for the rig as it starts (a board turns to a camera of that rig),
    // so every candidate is judged on the same poses; on the static scene (the caster as placed).
    const VisibilityTester all(rig.cameras, caster_, geometry_scale_);
    calib_poses_ = SampleCalibrationPoses(scene, all, calib_spec_);
    const VisibilityTester fixed_tester(fixed, caster_, geometry_scale_);
    calib_fixed_.resize(fixed.size());
    for (std::size_t c = 0; c < fixed.size(); ++c)
      calib_fixed_[c] = CalibrationBits(fixed_tester, static_cast<int>(c));
    calib_fixed_shared_.assign(fixed.size(), std::vector<std::int64_t>(fixed.size(), 0));
    for (std::size_t a = 0; a < fixed.size(); ++a)
      for (std::size_t b = a; b < fixed.size(); ++b)
        calib_fixed_shared_[a][b] = calib_fixed_shared_[b][a] =
            SharedBits(calib_fixed_[a], calib_fixed_[b]);
  }
}

std::vector<std::uint64_t> ExactEvaluator::CalibrationBits(const VisibilityTester& tester,
                                                           int camera) const {
  const std::size_t poses = calib_poses_.size();
  std::vector<std::uint8_t> seen(poses, 0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, poses, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t p = r.begin(); p != r.end(); ++p)
          seen[p] = ObservesPose(tester, camera, calib_spec_, calib_poses_[p]) ? 1 : 0;
      });
  std::vector<std::uint64_t> bits((poses + 63) / 64, 0);
  for (std::size_t p = 0; p < poses; ++p)
    if (seen[p]) bits[p / 64] |= std::uint64_t(1) << (p % 64);
  return bits;
}

std::int64_t ExactEvaluator::SharedBits(const std::vector<std::uint64_t>& a,
                                        const std::vector<std::uint64_t>& b) {
  std::int64_t n = 0;
  for (std::size_t w = 0; w < a.size() && w < b.size(); ++w) n += __builtin_popcountll(a[w] & b[w]);
  return n;
}

std::vector<std::unique_ptr<VisibilityTester>> ExactEvaluator::Testers(
    const std::vector<Camera>& cameras) const {
  std::vector<std::unique_ptr<VisibilityTester>> out;
  for (const RayCaster* c : casters_)
    out.push_back(std::make_unique<VisibilityTester>(cameras, *c, geometry_scale_));
  return out;
}

void ExactEvaluator::OccludedByPoint(const std::vector<Ray>& rays,
                                     std::vector<uint8_t>* occluded) const {
  if (casters_.size() == 1) return casters_[0]->OccludedBatch(rays, occluded);
  const std::size_t n = targets_.size();
  occluded->assign(rays.size(), 0);
  for (std::size_t s = 0; s < casters_.size(); ++s) {
    std::vector<std::size_t> index;
    for (std::size_t r = 0; r < rays.size(); ++r)
      if (n > 0 && Sample(r % n) == s) index.push_back(r);
    std::vector<Ray> part(index.size());
    for (std::size_t k = 0; k < index.size(); ++k) part[k] = rays[index[k]];
    std::vector<uint8_t> hit;
    casters_[s]->OccludedBatch(part, &hit);
    for (std::size_t k = 0; k < index.size(); ++k) (*occluded)[index[k]] = hit[k];
  }
}

Metrics ExactEvaluator::Evaluate(const std::vector<Eigen::Isometry3d>& poses,
                                 const std::vector<double>& focal_scales) const {
  ++evaluations_;
  // Each selected camera's view, then the sums in the order Combine adds them (the same rounding).
  std::vector<CameraView> views(selected_.size());
  std::vector<const CameraView*> ptrs(selected_.size());
  for (std::size_t c = 0; c < selected_.size(); ++c) {
    const Eigen::Isometry3d pose = c < poses.size() ? poses[c] : selected_[c].world_from_camera;
    const double scale = c < focal_scales.size() ? focal_scales[c] : 1.0;
    views[c] = View(static_cast<int>(c), pose, scale);
    ptrs[c] = &views[c];
  }
  return Summary(ptrs);
}

CameraView ExactEvaluator::View(int c, const Eigen::Isometry3d& pose, double focal_scale) const {
  Camera cam = selected_[c];
  cam.world_from_camera = pose;
  if (focal_scale != 1.0) cam = Zoomed(cam, focal_scale);
  const auto testers = Testers({cam});
  const std::size_t n = targets_.size();
  CameraView v;
  v.seen.assign(n, 0);
  v.info.assign(n, Mat3::Zero());
  v.density.assign(n, 0.0);
  const double s = PixelSigma(cam);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const TargetPoint& t = targets_[i];
                        Mat23 A;
                        if (testers[Sample(i)]->Test(0, t.p, t.normal ? &*t.normal : nullptr, &A) !=
                            ViewResult::kSeen)
                          continue;
                        v.seen[i] = 1;
                        v.info[i] = A.transpose() * A / (s * s);
                        v.density[i] = PixelDensity(A);
                      }
                    });
  if (objective_.kind == ObjectiveKind::kCalibration) {
    const VisibilityTester tester({cam}, caster_, geometry_scale_);
    v.calib = CalibrationBits(tester, 0);
  }
  return v;
}

Metrics ExactEvaluator::Combine(const std::vector<const CameraView*>& views,
                                bool objective_only) const {
  ++evaluations_;
  const bool counts_only = objective_.kind == ObjectiveKind::kCoverage ||
                           objective_.kind == ObjectiveKind::kCoverageN1 ||
                           objective_.kind == ObjectiveKind::kCalibration;
  if (objective_only && counts_only) {
    const std::size_t n = targets_.size();
    std::size_t k_count = 0;
    std::vector<int> count(n);
    for (std::size_t i = 0; i < n; ++i) {
      count[i] = fixed_.count[i];
      for (const CameraView* v : views) count[i] += v->seen[i];
      k_count += count[i] >= objective_.k;
    }
    Metrics m;
    m.coverage_k = n > 0 ? double(k_count) / n : 0.0;
    m.objective = m.coverage_k;
    AddObjectiveMeasures(count, views, &m);
    return m;
  }
  return Summary(views);
}

Metrics ExactEvaluator::Summary(const std::vector<const CameraView*>& views) const {
  const std::size_t n = targets_.size();
  std::vector<int> count = fixed_.count;
  std::vector<Mat3> J = fixed_.J;
  std::vector<double> dmax = fixed_.dmax;
  // Cameras in the order Evaluate adds them, so the sums round the same way.
  for (const CameraView* v : views)
    for (std::size_t i = 0; i < n; ++i) {
      if (!v->seen[i]) continue;
      count[i] += 1;
      J[i] += v->info[i];
      dmax[i] = std::max(dmax[i], v->density[i]);
    }
  return Summarise(count, J, dmax, views);
}

void ExactEvaluator::AddObjectiveMeasures(const std::vector<int>& count,
                                          const std::vector<const CameraView*>& views,
                                          Metrics* m) const {
  const std::size_t nfixed = fixed_rig_.size(), nsel = selected_rig_.size();
  auto id_of = [&](std::size_t c) { return c < nfixed ? fixed_ids_[c] : selected_[c - nfixed].id; };
  auto rig_of = [&](std::size_t c) {
    return c < nfixed ? fixed_rig_[c] : selected_rig_[c - nfixed];
  };
  if (objective_.kind == ObjectiveKind::kCoverageN1) {
    // A camera's failure loses exactly the points it sees that have k cameras, no more.
    const std::size_t n = count.size();
    std::vector<std::int64_t> lost(nfixed + nsel, 0);
    std::int64_t k_count = 0;
    for (std::size_t i = 0; i < n; ++i) {
      k_count += count[i] >= objective_.k;
      if (count[i] != objective_.k) continue;
      for (int f : fixed_.seen_by[i]) ++lost[f];
      for (std::size_t c = 0; c < nsel && c < views.size(); ++c)
        if (views[c]->seen[i]) ++lost[nfixed + c];
    }
    Metrics::N1 r;
    std::int64_t worst = 0;
    int worst_rig = -1;
    for (std::size_t c = 0; c < lost.size(); ++c)
      if (worst_rig < 0 || lost[c] > worst || (lost[c] == worst && rig_of(c) < worst_rig)) {
        worst = lost[c];
        worst_rig = rig_of(c);
        r.worst_camera = id_of(c);
      }
    r.coverage_k = n > 0 ? double(k_count - worst) / n : 0.0;
    m->n1 = r;
    m->objective = r.coverage_k;
  }
  if (objective_.kind == ObjectiveKind::kCalibration) {
    // The co-visibility matrix: the fixed cameras' block once, the selected cameras' rows now.
    const std::size_t nc = nfixed + nsel;
    std::vector<std::vector<std::int64_t>> shared(nc, std::vector<std::int64_t>(nc, 0));
    auto bits = [&](std::size_t c) -> const std::vector<std::uint64_t>& {
      return c < nfixed ? calib_fixed_[c] : views[c - nfixed]->calib;
    };
    for (std::size_t a = 0; a < nc; ++a)
      for (std::size_t b = a; b < nc; ++b)
        shared[a][b] = shared[b][a] =
            a < nfixed && b < nfixed ? calib_fixed_shared_[a][b] : SharedBits(bits(a), bits(b));
    Metrics::Calibration r;
    r.poses = static_cast<std::int64_t>(calib_poses_.size());
    // The maximum spanning tree (Prim, complete graph): its weakest edge is the chain's strength.
    if (nc == 1) r.weakest = shared[0][0];
    if (nc > 1) {
      std::vector<bool> in(nc, false);
      std::vector<std::int64_t> best(nc, -1);
      std::vector<std::size_t> from(nc, 0);
      in[0] = true;
      for (std::size_t c = 1; c < nc; ++c) best[c] = shared[0][c];
      r.weakest = std::numeric_limits<std::int64_t>::max();
      for (std::size_t step = 1; step < nc; ++step) {
        std::size_t next = nc;
        for (std::size_t c = 0; c < nc; ++c)
          if (!in[c] && (next == nc || best[c] > best[next])) next = c;
        in[next] = true;
        r.tree_total += best[next];
        if (best[next] < r.weakest) {
          r.weakest = best[next];
          r.weakest_a = id_of(from[next]);
          r.weakest_b = id_of(next);
        }
        for (std::size_t c = 0; c < nc; ++c)
          if (!in[c] && shared[next][c] > best[c]) {
            best[c] = shared[next][c];
            from[c] = next;
          }
      }
    }
    const CalibrationGraph graph =
        BuildCalibrationGraph(shared, std::vector<bool>(nc, true), calib_spec_.min_shared);
    r.components = static_cast<int>(graph.components.size());
    r.uncalibratable = static_cast<int>(graph.uncalibratable.size());
    m->calibration = r;
    m->objective = static_cast<double>(r.weakest);
  }
}

Metrics ExactEvaluator::Summarise(const std::vector<int>& count, const std::vector<Mat3>& J,
                                  const std::vector<double>& dmax,
                                  const std::vector<const CameraView*>& views) const {
  Metrics m;
  const std::size_t n = count.size();
  if (n == 0) return m;
  std::vector<double> sigma(n, kInf);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        if (count[i] < 2) continue;
                        const Information info = DecomposeInformation(J[i], false);
                        if (!info.observable) continue;
                        sigma[i] = 1000.0 / std::sqrt(info.eigenvalues(0));
                      }
                    });
  std::size_t k_count = 0, two = 0, untri = 0;
  double sum = 0, min_res = kInf;
  for (std::size_t i = 0; i < n; ++i) {
    k_count += count[i] >= objective_.k;
    two += count[i] >= 2;
    untri += std::isinf(sigma[i]);
    sum += std::min(sigma[i], sigma_cap_mm_);
    min_res = std::min(min_res, dmax[i]);
  }
  m.coverage_k = double(k_count) / n;
  m.coverage2 = double(two) / n;
  m.untriangulable = double(untri) / n;
  m.sigma_mean = sum / n;
  m.min_resolution = min_res;
  std::sort(sigma.begin(), sigma.end());
  auto rank = [&](double p) {
    const std::size_t r = static_cast<std::size_t>(std::ceil(p / 100.0 * n));
    return sigma[std::clamp<std::size_t>(r, 1, n) - 1];
  };
  m.sigma_p50 = rank(50);
  m.sigma_p90 = rank(90);
  m.sigma_p95 = rank(95);
  switch (objective_.kind) {
    case ObjectiveKind::kCoverage:
      m.objective = m.coverage_k;
      break;
    case ObjectiveKind::kSigmaMean:
      m.objective = m.sigma_mean;
      break;
    case ObjectiveKind::kSigmaPercentile:
      m.objective = rank(objective_.percentile);
      break;
    case ObjectiveKind::kResolution:
      m.objective = m.min_resolution;
      break;
    case ObjectiveKind::kMix: {
      const double s = ref_sigma_mean_ > 0 ? ref_sigma_mean_ : m.sigma_mean;
      const double r = ref_min_resolution_ > 0 ? ref_min_resolution_ : 0;
      m.objective = objective_.w_coverage * m.coverage_k + objective_.w_sigma * (s / m.sigma_mean) +
                    objective_.w_resolution * (r > 0 ? m.min_resolution / r : 0.0);
      break;
    }
    case ObjectiveKind::kCoverageN1:
    case ObjectiveKind::kCalibration:
      break;  // AddObjectiveMeasures
  }
  AddObjectiveMeasures(count, views, &m);
  return m;
}

double ExactEvaluator::Score(const Metrics& m) const {
  if (std::isnan(m.objective)) return -kInf;
  // A sigma percentile that falls on an untriangulable point is +inf; among those, fewer
  // untriangulable points is better (and any finite percentile is better still).
  if (objective_.kind == ObjectiveKind::kSigmaPercentile && std::isinf(m.objective))
    return -1e300 * (1.0 + m.untriangulable);
  // Between two chains of equal strength the one with more shared poses along its tree is better:
  // the tree's total, as a fraction below 1, breaks the tie without changing the order of
  // strengths.
  if (objective_.kind == ObjectiveKind::kCalibration && m.calibration) {
    const double cams = static_cast<double>(fixed_rig_.size() + selected_rig_.size());
    return m.objective +
           double(m.calibration->tree_total) / (cams * double(m.calibration->poses) + 1.0);
  }
  return ObjectiveHigherIsBetter(objective_) ? m.objective : -m.objective;
}

// ---------------------------------------------------------------------------------------------
// Pose chart

PoseChart PoseChart::Make(const Camera& camera, const CameraLimits& limits) {
  PoseChart c;
  c.start = camera.world_from_camera;
  c.max_move = limits.max_move;
  c.max_rotate = Rad(limits.max_rotate_deg);
  c.mount = limits.mount;
  const Vec3 axis = limits.mount.axis.normalized();
  switch (limits.mount.kind) {
    case MountConstraint::Kind::kFree:
    case MountConstraint::Kind::kBox:
      c.basis = Mat3::Identity();
      break;
    case MountConstraint::Kind::kLine:
      c.basis = axis;
      break;
    case MountConstraint::Kind::kPlane: {
      int a = 0;
      for (int i = 1; i < 3; ++i)
        if (std::abs(axis[i]) < std::abs(axis[a])) a = i;
      const Vec3 u = axis.cross(Vec3::Unit(a)).normalized();
      const Vec3 v = axis.cross(u).normalized();
      c.basis.resize(3, 2);
      c.basis.col(0) = u;
      c.basis.col(1) = v;
      break;
    }
  }
  c.dims_t = c.max_move > 0 ? static_cast<int>(c.basis.cols()) : 0;
  c.dims_r = c.max_rotate > 0 ? 3 : 0;
  double zoom_lo = 0, zoom_hi = 0;  // ln(f / f0) at the wide and the narrow end
  if (limits.max_hfov_deg > 0) {
    const Intrinsics& k = camera.model.intrinsics();
    zoom_lo = std::log(FocalFromHfov(Rad(limits.max_hfov_deg), k.width, k.model) / k.fx);
    zoom_hi = std::log(FocalFromHfov(Rad(limits.min_hfov_deg), k.width, k.model) / k.fx);
    c.log_focal_range = std::max(std::abs(zoom_lo), std::abs(zoom_hi));
    c.dims_f = c.log_focal_range > 1e-12 ? 1 : 0;  // a one-value range is no zoom
  }
  c.lower.assign(c.dims(), -1.0);
  c.upper.assign(c.dims(), 1.0);
  if (c.dims_f > 0) {
    c.lower[c.dims_t + c.dims_r] = std::min(0.0, zoom_lo / c.log_focal_range);
    c.upper[c.dims_t + c.dims_r] = std::max(0.0, zoom_hi / c.log_focal_range);
  }
  if (limits.mount.kind == MountConstraint::Kind::kBox && c.dims_t == 3) {
    const Vec3 c0 = camera.center();
    for (int a = 0; a < 3; ++a) {
      c.lower[a] = std::max(-1.0, (limits.mount.box.min[a] - c0[a]) / c.max_move);
      c.upper[a] = std::min(1.0, (limits.mount.box.max[a] - c0[a]) / c.max_move);
    }
  }
  return c;
}

Eigen::Isometry3d PoseChart::Pose(const double* x) const {
  Eigen::Isometry3d pose = start;
  if (dims_t > 0) {
    Eigen::VectorXd t(dims_t);
    for (int i = 0; i < dims_t; ++i) t[i] = x[i] * max_move;
    pose.translation() = start.translation() + basis * t;
  }
  if (dims_r > 0) {
    const Vec3 w = Vec3(x[dims_t], x[dims_t + 1], x[dims_t + 2]) * max_rotate;
    const double angle = w.norm();
    if (angle > 0)
      pose.linear() = start.linear() * Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  }
  return pose;
}

void PoseChart::Project(double* x) const {
  auto project = [&](int from, int n) {
    double norm2 = 0;
    for (int i = from; i < from + n; ++i) norm2 += x[i] * x[i];
    if (norm2 > 1.0) {
      const double s = 1.0 / std::sqrt(norm2);
      for (int i = from; i < from + n; ++i) x[i] *= s;
    }
    for (int i = from; i < from + n; ++i) x[i] = std::clamp(x[i], lower[i], upper[i]);
  };
  if (dims_t > 0) project(0, dims_t);
  if (dims_r > 0) project(dims_t, 3);
  if (dims_f > 0) {
    const int i = dims_t + dims_r;
    x[i] = std::clamp(x[i], lower[i], upper[i]);
  }
}

Camera Zoomed(const Camera& camera, double scale) {
  Camera out = camera;
  Intrinsics k = camera.model.intrinsics();
  k.fx *= scale;
  k.fy *= scale;
  out.model = CameraModel(k);
  return out;
}

bool InKeepOut(const std::vector<Aabb>& keep_out, const Vec3& p) {
  for (const Aabb& b : keep_out)
    if (b.Contains(p)) return true;
  return false;
}

Placement::Placement(const Scene& scene, const Rig& rig, const SuggestOptions& options)
    : keep_out_(options.keep_out), distance_(scene.AllTriangles()) {
  for (int index : options.cameras) {
    const double start = index >= 0 && index < static_cast<int>(rig.cameras.size())
                             ? distance_.Distance(rig.cameras[index].center(), options.clearance)
                             : 0.0;
    required_.push_back(std::min(options.clearance, start));
  }
}

const CameraLimits& LimitsOf(const SuggestOptions& options, std::size_t i) {
  return options.limits.size() == 1 ? options.limits[0] : options.limits[i];
}

SearchStart BeginSearch(const Rig& rig, const SuggestOptions& options, int target_points,
                        ExactEvaluator& ev) {
  SearchStart b;
  for (std::size_t c = 0; c < options.cameras.size(); ++c) {
    b.charts.push_back(PoseChart::Make(rig.cameras[options.cameras[c]], LimitsOf(options, c)));
    b.start.push_back(rig.cameras[options.cameras[c]].world_from_camera);
  }
  Suggestion& s = b.suggestion;
  s.objective = options.objective;
  s.target_points = target_points;
  s.before = ev.Evaluate(b.start);
  ev.SetReference(s.before.sigma_mean, s.before.min_resolution);
  if (options.objective.kind == ObjectiveKind::kMix) s.before = ev.Evaluate(b.start);
  return b;
}

// ---------------------------------------------------------------------------------------------
// Snapping

std::vector<Eigen::Isometry3d> SnapPoses(const std::vector<PoseChart>& charts,
                                         const std::vector<Eigen::Isometry3d>& poses,
                                         const SuggestOptions& options,
                                         const Placement& placement) {
  std::vector<Eigen::Isometry3d> out = poses;
  for (std::size_t c = 0; c < charts.size(); ++c) {
    const PoseChart& ch = charts[c];
    const Eigen::Isometry3d& p = poses[c];
    Eigen::Isometry3d q = p;
    // A camera the search left where it was stays exactly there (not moved onto the grid).
    if (p.translation() == ch.start.translation() && p.linear() == ch.start.linear()) continue;
    // Translation in the mount's coordinates (metres). Along a mount direction that is a world
    // axis the coordinate itself lands on a multiple of the step (installable numbers in the scene
    // file); along any other direction the move is a multiple of the step.
    if (options.snap_move > 0 && ch.dims_t > 0) {
      const double step = options.snap_move;
      const Vec3 c0 = ch.start.translation();
      const Eigen::VectorXd y = ch.basis.transpose() * (p.translation() - c0);
      // World axis k and sign of basis column i, or -1 when it is oblique.
      auto world_axis = [&](int i, double* sign) {
        for (int k = 0; k < 3; ++k)
          if (std::abs(std::abs(ch.basis(k, i)) - 1.0) < 1e-12) {
            *sign = ch.basis(k, i) > 0 ? 1.0 : -1.0;
            return k;
          }
        return -1;
      };
      auto make = [&](bool toward_start) {
        Eigen::VectorXd r(y.size());
        for (int i = 0; i < y.size(); ++i) {
          double sign = 1;
          const int k = world_axis(i, &sign);
          if (k >= 0) {
            const double target = c0[k] + sign * y[i];  // the world coordinate
            double g = std::round(target / step);
            if (toward_start)
              g = target > c0[k] ? std::floor(target / step) : std::ceil(target / step);
            r[i] = sign * (g * step - c0[k]);
          } else {
            const double q = y[i] / step;
            r[i] = (toward_start ? std::trunc(q) : std::round(q)) * step;
          }
        }
        return Vec3(c0 + ch.basis * r);
      };
      auto admissible = [&](const Vec3& centre) {
        if ((centre - c0).norm() > ch.max_move * (1 + 1e-12)) return false;
        if (ch.mount.kind == MountConstraint::Kind::kBox && !ch.mount.box.Contains(centre))
          return false;
        return placement.Admissible(c, centre);
      };
      Vec3 centre = make(false);
      if (!admissible(centre)) centre = make(true);
      if (!admissible(centre)) centre = c0;
      if ((centre - c0).norm() <= 1e-12 * std::max(1.0, c0.norm())) centre = c0;  // round-off
      q.translation() = centre;
    }
    if (options.snap_rotate_deg > 0 && ch.dims_r > 0) {
      const Vec3 y0 = YawPitchRollDeg(ch.start.linear());
      const Vec3 y1 = YawPitchRollDeg(p.linear());
      Vec3 delta;
      for (int i = 0; i < 3; ++i) delta[i] = WrapDeg(y1[i] - y0[i]);
      auto make = [&](bool truncate) {
        Vec3 r;
        for (int i = 0; i < 3; ++i) {
          const double s = delta[i] / options.snap_rotate_deg;
          r[i] = (truncate ? std::trunc(s) : std::round(s)) * options.snap_rotate_deg;
        }
        return Mat3(RotationFromYawPitchRollDeg(y0 + r));
      };
      const double limit = Deg(ch.max_rotate) * (1 + 1e-9) + 1e-9;
      bool unchanged = true;
      for (int i = 0; i < 3; ++i)
        unchanged = unchanged && std::round(delta[i] / options.snap_rotate_deg) == 0;
      Mat3 R = unchanged ? ch.start.linear() : make(false);
      if (RotationAngleDeg(ch.start.linear(), R) > limit) R = make(true);
      if (RotationAngleDeg(ch.start.linear(), R) > limit) R = ch.start.linear();
      q.linear() = R;
    }
    out[c] = q;
  }
  return out;
}

void FillChanges(const Rig& rig, const SuggestOptions& options,
                 const std::vector<Eigen::Isometry3d>& poses,
                 const std::vector<double>& focal_scales, const Placement& placement,
                 Suggestion* s) {
  s->cameras.clear();
  for (std::size_t c = 0; c < options.cameras.size(); ++c) {
    const Camera& cam = rig.cameras[options.cameras[c]];
    CameraChange ch;
    ch.index = options.cameras[c];
    ch.id = cam.id;
    ch.before = cam.world_from_camera;
    ch.after = poses[c];
    ch.move_m = (ch.after.translation() - ch.before.translation()).norm();
    ch.rotate_deg = RotationAngleDeg(ch.before.linear(), ch.after.linear());
    const Intrinsics& k = cam.model.intrinsics();
    ch.focal_scale = c < focal_scales.size() ? focal_scales[c] : 1.0;
    ch.hfov_before_deg = Deg(HfovFromFocal(k.fx, k.width, k.model));
    ch.hfov_after_deg = Deg(HfovFromFocal(k.fx * ch.focal_scale, k.width, k.model));
    ch.surface_distance_before = placement.SurfaceDistanceAt(ch.before.translation());
    ch.surface_distance_after = placement.SurfaceDistanceAt(ch.after.translation());
    s->cameras.push_back(ch);
  }
}

}  // namespace suggest_detail

void SuggestOptions::Check(const Scene& scene, const Rig& rig) const {
  const std::string& file = scene_path.empty() ? scene.path : scene_path;
  if (cameras.empty())
    throw InputError(file, "{cameras}", "no camera selected",
                     "name the cameras to move, e.g. {cameras} 3,5");
  if (limits.size() != 1 && limits.size() != cameras.size())
    throw InputError(file, "{max_move}",
                     "one set of limits, or one per selected camera, is needed");
  std::set<int> seen;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const int idx = cameras[i];
    if (idx < 0 || idx >= static_cast<int>(rig.cameras.size()))
      throw InputError(file, "{cameras}",
                       "camera index " + std::to_string(idx) + " is not in rig '" + rig.name + "'");
    const Camera& cam = rig.cameras[idx];
    if (!seen.insert(idx).second)
      throw InputError(file, "{cameras}", "camera '" + cam.id + "' is selected twice");
    if (cam.ptz)  // its file pose is its home, not its current setting (docs/ptz.md)
      throw InputError(file, "{cameras}", "camera '" + cam.id + "' is a PTZ camera",
                       "suggest moves fixed cameras; set a PTZ camera's pan, tilt and zoom in its "
                       "\"ptz\" block");
    if (!cam.enabled)
      throw InputError(file, "{cameras}", "camera '" + cam.id + "' is disabled",
                       "enable it in the scene file to move it");
    const CameraLimits& l = suggest_detail::LimitsOf(*this, i);
    if (!(l.max_move >= 0) || !std::isfinite(l.max_move))
      throw InputError(
          file, "{max_move}",
          "the largest move must be a finite length >= 0 (got " + Format("%g", l.max_move) + ")");
    if (!(l.max_rotate_deg >= 0) || !(l.max_rotate_deg < 180))
      throw InputError(file, "{max_rotate_deg}",
                       "the largest rotation must be in [0, 180) degrees (got " +
                           Format("%g", l.max_rotate_deg) + ")");
    if (l.min_hfov_deg != 0 || l.max_hfov_deg != 0) {
      const Intrinsics& k = cam.model.intrinsics();
      const double limit = k.model == LensModel::kFisheye ? 360.0 : 180.0;
      if (!(l.min_hfov_deg > 0) || !(l.max_hfov_deg >= l.min_hfov_deg) || !(l.max_hfov_deg < limit))
        throw InputError(file, "{hfov_range}",
                         "the field-of-view range must satisfy 0 < MIN <= MAX < " +
                             Format("%g", limit) + " degrees");
      const double hfov = Deg(HfovFromFocal(k.fx, k.width, k.model));
      if (hfov < l.min_hfov_deg - 1e-9 || hfov > l.max_hfov_deg + 1e-9)
        throw InputError(file, "{hfov_range}",
                         "camera '" + cam.id + "' has a field of view of " + Format("%.6g", hfov) +
                             " degrees, outside the range",
                         "the range must hold the current field of view");
    }
    const MountConstraint& m = l.mount;
    if ((m.kind == MountConstraint::Kind::kLine || m.kind == MountConstraint::Kind::kPlane) &&
        !(m.axis.norm() > 0 && m.axis.allFinite()))
      throw InputError(file, m.kind == MountConstraint::Kind::kLine ? "{rail}" : "{plane}",
                       "the direction must be a non-zero vector");
    if (m.kind == MountConstraint::Kind::kBox && !m.box.Contains(cam.center()))
      throw InputError(file, "{mount_box}", "camera '" + cam.id + "' is outside its mounting box",
                       "the box must hold the camera's current centre");
    if (suggest_detail::InKeepOut(keep_out, cam.center()))
      throw InputError(file, "{keep_out}", "camera '" + cam.id + "' is inside a keep-out box",
                       "a keep-out box must not hold a selected camera's current centre");
  }
  if (!(clearance >= 0) || !std::isfinite(clearance))
    throw InputError(file, "{clearance}", "must be a finite length >= 0 (metres)");
  if (!(snap_move >= 0) || !std::isfinite(snap_move))
    throw InputError(file, "{snap_move}", "must be a finite length >= 0");
  if (!(snap_rotate_deg >= 0) || !std::isfinite(snap_rotate_deg))
    throw InputError(file, "{snap_rotate_deg}", "must be a finite angle >= 0");
  if (objective.k < 1 || objective.k > 64)
    throw InputError(file, "{objective}", "k must be in 1..64");
}

// ---------------------------------------------------------------------------------------------
// Exact evaluation of a whole rig, and the baseline

Metrics EvaluateExact(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const std::vector<TargetPoint>& targets, const Objective& objective,
                      const std::vector<const RayCaster*>& sample_casters) {
  suggest_detail::ExactEvaluator ev(scene, rig, caster, targets, objective, {}, sample_casters);
  Metrics m = ev.Evaluate({});
  if (objective.kind == ObjectiveKind::kMix) {
    ev.SetReference(m.sigma_mean, m.min_resolution);
    m = ev.Evaluate({});
  }
  return m;
}

Suggestion BaselineSearch(const Scene& scene, const Rig& rig, const RayCaster& caster,
                          const std::vector<TargetPoint>& targets, const SuggestOptions& options,
                          std::int64_t evaluation_budget, std::uint64_t seed, bool adaptive_step) {
  using namespace suggest_detail;
  options.Check(scene, rig);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  ExactEvaluator ev(scene, rig, caster, targets, options.objective, options.cameras,
                    options.sample_casters);
  const Placement placement(scene, rig, options);
  SearchStart begin = BeginSearch(rig, options, static_cast<int>(targets.size()), ev);
  const std::vector<PoseChart>& charts = begin.charts;
  const std::vector<Eigen::Isometry3d>& start = begin.start;
  Suggestion& s = begin.suggestion;
  std::vector<std::vector<double>> best(charts.size());
  int total_dims = 0;
  for (std::size_t c = 0; c < charts.size(); ++c) {
    best[c].assign(charts[c].dims(), 0.0);
    total_dims += charts[c].dims();
  }
  Metrics best_m = s.before;
  double best_score = ev.Score(best_m);
  s.trace.push_back({elapsed(), ev.evaluations(), best_m.objective});
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  double step = 0.25;  // standard deviation per parameter, in units of the limits
  std::vector<std::vector<double>> cand = best;
  std::vector<Eigen::Isometry3d> poses = start;
  std::vector<double> scales(charts.size(), 1.0);
  int rejected_in_a_row = 0;
  std::vector<CameraView> views(charts.size());
  std::vector<const CameraView*> view_ptrs(charts.size());
  while (total_dims > 0 && ev.evaluations() < evaluation_budget && rejected_in_a_row < 10000) {
    bool ok = true;
    for (std::size_t c = 0; c < charts.size(); ++c) {
      for (int i = 0; i < charts[c].dims(); ++i) cand[c][i] = best[c][i] + step * normal(rng);
      charts[c].Project(cand[c].data());
      poses[c] = charts[c].Pose(cand[c].data());
      scales[c] = charts[c].FocalScale(cand[c].data());
      ok = ok && placement.Admissible(c, poses[c].translation());
    }
    if (!ok) {  // an inadmissible candidate costs no evaluation
      ++rejected_in_a_row;
      continue;
    }
    rejected_in_a_row = 0;
    // The same fast exact evaluation as the nudge's screening: the objective alone (for coverage,
    // no covariances), the full metrics only for a new best.
    for (std::size_t c = 0; c < charts.size(); ++c) {
      views[c] = ev.View(static_cast<int>(c), poses[c], scales[c]);
      view_ptrs[c] = &views[c];
    }
    const Metrics m = ev.Combine(view_ptrs, /*objective_only=*/true);
    const double score = ev.Score(m);
    if (score > best_score) {
      best_score = score;
      best_m = ev.Summary(view_ptrs);
      best = cand;
      if (adaptive_step) step = std::min(1.0, step * 1.5);
    } else if (adaptive_step) {
      step = std::max(1e-4, step * std::pow(1.5, -0.25));
    }
    s.trace.push_back({elapsed(), ev.evaluations(), best_m.objective});
  }
  for (std::size_t c = 0; c < charts.size(); ++c) {
    poses[c] = charts[c].Pose(best[c].data());
    scales[c] = charts[c].FocalScale(best[c].data());
  }
  s.improved = best_score > ev.Score(s.before);
  if (!s.improved) {
    poses = start;
    scales.assign(charts.size(), 1.0);
  }
  s.after = s.improved ? best_m : s.before;
  FillChanges(rig, options, poses, scales, placement, &s);
  s.evaluations = ev.evaluations();
  s.seconds = elapsed();
  s.message = s.improved ? "baseline improved the objective" : "baseline found no improvement";
  return s;
}

std::vector<TargetPoint> SampleTimeTargets(const Scene& scene,
                                           const std::vector<TimeSample>& samples_in, int points,
                                           std::uint64_t seed) {
  if (!scene.study.targets)
    throw InputError(
        scene.path, "$.study.targets", "suggesting over time needs surface targets",
        "name the moving groups to see under \"study\": {\"targets\": {\"objects\": [...]}}");
  const std::vector<TimeSample> samples = SamplesOrAsPlaced(samples_in);
  std::vector<TargetPoint> out;
  const std::vector<std::string>& names = scene.study.targets->names;
  for (std::size_t g = 0; g < names.size(); ++g) {
    const TargetSurface surface = FindTargetSurface(scene, names[g]);
    const SurfacePoints rest = SampleTargetPoints(surface, points, seed + g);
    std::vector<Vec3> p, n;
    for (std::size_t s = 0; s < samples.size(); ++s) {
      PlaceTargetPoints(scene, surface, rest, samples[s], &p, &n);  // rigid motion, or the skin
      for (std::size_t i = 0; i < p.size(); ++i) {
        TargetPoint t;
        t.p = p[i];
        t.normal = n[i];
        t.sample = int(s);
        out.push_back(t);
      }
    }
  }
  return out;
}

}  // namespace pandora
