// Plausibility checks of a rig (analysis/rig/rig_check.h): cameras inside solids, outside the
// modelled geometry or the room, seeing nothing of the region, and lenses whose model folds back
// inside the image.
#include "analysis/rig/rig_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/motion.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

std::string Format(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::string Point(const Vec3& p) {
  return "(" + Format("%.3g", p.x()) + ", " + Format("%.3g", p.y()) + ", " + Format("%.3g", p.z()) +
         ")";
}

// A share in percent with enough digits to be non-zero when it is.
std::string Percent(double fraction) {
  const double p = 100.0 * fraction;
  if (p > 0 && p < 0.01) return "< 0.01%";
  return Format(p < 1 ? "%.2f%%" : "%.1f%%", p);
}

// Angle (radians) between the optical axis (+z) and a unit ray.
double AxisAngle(const Vec3& ray) { return std::atan2(ray.head<2>().norm(), ray.z()); }

// Point-in-solid tests: the given trees (RigCheckOptions::object_tree), or built on first use per
// object (CGAL AABB trees are not free).
class Solids {
 public:
  Solids(const Scene& scene, const RigCheckOptions& options) : scene_(scene), given_(options) {
    for (std::size_t o = 0; o < scene.objects.size(); ++o)
      if (scene.objects[o].solid && !scene.objects[o].mesh.triangles.empty()) {
        objects_.push_back(static_cast<int>(o));
        bounds_.push_back(scene.objects[o].mesh.Bounds());
      }
    tests_.resize(objects_.size(), nullptr);
    own_.resize(objects_.size());
  }
  /// The object index of a solid containing p, or -1. With `strict`, a point within `tolerance` of
  /// the surface (some axis offset by it is outside) does not count.
  int Containing(const Vec3& p, bool strict = false, double tolerance = 0) {
    for (std::size_t i = 0; i < objects_.size(); ++i) {
      if (!bounds_[i].Contains(p)) continue;
      const InsideMesh& test = Test(i);
      if (!test.Inside(p)) continue;
      bool on_surface = false;
      for (int a = 0; strict && a < 6 && !on_surface; ++a) {
        Vec3 q = p;
        q[a / 2] += (a % 2 ? tolerance : -tolerance);
        on_surface = !test.Inside(q);
      }
      if (!on_surface) return objects_[i];
    }
    return -1;
  }

 private:
  const InsideMesh& Test(std::size_t i) {
    if (!tests_[i] && given_.object_tree) tests_[i] = given_.object_tree(objects_[i]);
    if (!tests_[i]) {
      own_[i] = std::make_unique<InsideMesh>(scene_.objects[objects_[i]].mesh);
      tests_[i] = own_[i].get();
    }
    return *tests_[i];
  }
  const Scene& scene_;
  const RigCheckOptions& given_;
  std::vector<int> objects_;
  std::vector<Aabb> bounds_;
  std::vector<const InsideMesh*> tests_;
  std::vector<std::unique_ptr<InsideMesh>> own_;
};

// Cell centres of an n^3 lattice over the region box, inside the region and outside every solid.
std::vector<Vec3> RegionSamples(const Scene& scene, int n, const RigCheckOptions& options,
                                Solids* solids) {
  const Region& region = scene.study.region;
  std::vector<Vec3> out;
  if (region.box.empty() || n < 1) return out;
  const InsideMesh* inside = nullptr;
  std::unique_ptr<InsideMesh> own;
  if (region.kind == Region::Kind::kMesh && !region.mesh.triangles.empty()) {
    if (options.region_tree) inside = options.region_tree();
    if (!inside) {
      own = std::make_unique<InsideMesh>(region.mesh);
      inside = own.get();
    }
  }
  const Vec3 size = region.box.size();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Vec3 p = region.box.min + Vec3((i + 0.5) / n * size.x(), (j + 0.5) / n * size.y(),
                                             (k + 0.5) / n * size.z());
        if (inside && !inside->Inside(p)) continue;
        if (solids->Containing(p) >= 0) continue;
        out.push_back(p);
      }
  return out;
}

int RigIndex(const Scene& scene, const Rig& rig) {
  for (std::size_t r = 0; r < scene.rigs.size(); ++r)
    if (&scene.rigs[r] == &rig) return static_cast<int>(r);
  for (std::size_t r = 0; r < scene.rigs.size(); ++r)
    if (scene.rigs[r].name == rig.name) return static_cast<int>(r);
  return 0;
}

std::string ObjectName(const Scene& scene, int object) {
  return object >= 0 && object < static_cast<int>(scene.objects.size())
             ? "'" + scene.objects[object].name + "'"
             : "an object";
}

// Along the segment from `inner` (reachable) to `outer`, the last point the lens reaches, by
// bisection to `tolerance` pixels; `outer` itself when it is reachable.
Vec2 LastReachable(const CameraModel& model, const Vec2& inner, const Vec2& outer,
                   double tolerance = 1e-3) {
  if (model.Unproject(outer)) return outer;
  double lo = 0, hi = 1;  // fractions along the segment: lo reachable, hi not
  const double length = (outer - inner).norm();
  for (int i = 0; i < 64 && (hi - lo) * length > tolerance; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (model.Unproject(inner + mid * (outer - inner)))
      lo = mid;
    else
      hi = mid;
  }
  return inner + lo * (outer - inner);
}

// Edge-to-edge angle along the image row (axis 0) or column (axis 1) through the principal point.
double EffectiveFov(const CameraModel& model, int axis) {
  const Intrinsics& k = model.intrinsics();
  const double extent = axis == 0 ? k.width - 0.5 : k.height - 0.5;
  const double pp = axis == 0 ? k.cx : k.cy;
  const double other =
      axis == 0 ? std::clamp(k.cy, -0.5, k.height - 0.5) : std::clamp(k.cx, -0.5, k.width - 0.5);
  auto pixel = [&](double t) { return axis == 0 ? Vec2(t, other) : Vec2(other, t); };
  const Vec2 centre = pixel(std::clamp(pp, -0.5, extent));
  if (!model.Unproject(centre)) return 0.0;
  // The angle is flat in the pixel position where the domain ends (the radial map turns there):
  // bisect to 1e-9 pixel so that the angle is exact to about 1e-6 rad.
  const Vec2 a = LastReachable(model, centre, pixel(-0.5), 1e-9);
  const Vec2 b = LastReachable(model, centre, pixel(extent), 1e-9);
  const Vec3 ra = *model.Unproject(a), rb = *model.Unproject(b);
  if (pp >= -0.5 && pp <= extent) return (AxisAngle(ra) + AxisAngle(rb)) * kDegPerRad;
  return std::atan2(ra.cross(rb).norm(), ra.dot(rb)) * kDegPerRad;
}

// Valid values that are almost surely mistakes (Warning::Kind::kImplausible; rig_check.h).
template <class CameraPath>
void CheckPlausibleValues(const Scene& scene, const Rig& rig, const CameraPath& camera_path,
                          std::vector<Warning>* out) {
  auto add = [&](const std::string& path, const std::string& reason) {
    out->push_back({Warning::Kind::kImplausible, "", path, reason});
  };
  auto metres = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g m", v);
    return std::string(b);
  };
  const Aabb& region = scene.study.region.box;
  // The whole scene (geometry, region and cameras): a room of 7 cm or 700 km is a unit mistake; a
  // small study region alone is not (the trauma room studies a 22 cm neck).
  Aabb extent = scene.ContentBounds();
  for (const Camera& c : rig.cameras) extent.Extend(c.center());
  if (!extent.empty()) {
    const double longest = extent.size().maxCoeff();
    if (longest < 0.5 || longest > 2e4)
      add("$.units",
          "the scene (its geometry, region and cameras) spans " + metres(longest) +
              ": are the file's units right (a file in metres read as cm, or the reverse)?");
  }
  if (!region.empty()) {
    for (const auto& [name, r] : scene.study.regions) {
      Aabb meet = r.box;
      meet.min = meet.min.cwiseMax(region.min);
      meet.max = meet.max.cwiseMin(region.max);
      if ((meet.max.array() < meet.min.array()).any())
        add("$.study.regions." + name,
            "the region '" + name + "' lies outside the study region: it holds no voxel of it");
    }
  }
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const Intrinsics& k = rig.cameras[c].model.intrinsics();
    const double hfov = HfovFromFocal(k.fx, k.width, k.model) * kDegPerRad;
    if (hfov < 3.2)
      add(camera_path(c) + ".hfov_deg",
          "camera '" + rig.cameras[c].id + "' has a field of view of " +
              std::to_string(hfov).substr(0, 5) + " degrees: radians written as degrees (" +
              std::to_string(hfov * 180 / kPi).substr(0, 5) + " degrees)?");
  }
  // Moving groups: one that lies outside the study region at a time sample, or whose centre passes
  // through a solid object that does not move between two samples (a person keyframed through a
  // wall). One warning per group, the first such sample.
  if (!scene.motions.empty()) {
    TriangleMesh still;
    for (std::size_t o = 0; o < scene.objects.size(); ++o) {
      const SceneObject& obj = scene.objects[o];
      if (!obj.solid || MotionOfObject(scene, int(o)) >= 0 || obj.skin >= 0) continue;
      const int base = int(still.vertices.size());
      still.vertices.insert(still.vertices.end(), obj.mesh.vertices.begin(),
                            obj.mesh.vertices.end());
      for (const auto& tri : obj.mesh.triangles)
        still.triangles.push_back(tri + Eigen::Vector3i::Constant(base));
    }
    const auto walls = still.triangles.empty() ? nullptr : MakeEmbreeRayCaster(still);
    const std::vector<TimeSample> samples = scene.TimeSamples();
    for (std::size_t m = 0; m < scene.motions.size(); ++m) {
      const ObjectMotion& motion = scene.motions[m];
      Aabb rest;
      for (int o : motion.objects) rest.Extend(scene.objects[o].mesh.Bounds());
      if (rest.empty()) continue;
      std::optional<Vec3> previous;
      std::string previous_label;
      for (const TimeSample& sample : samples) {
        const Eigen::Isometry3d T = MotionTransform(scene, int(m), sample);
        Aabb moved;
        for (int c = 0; c < 8; ++c)
          moved.Extend(T * Vec3(c & 1 ? rest.max.x() : rest.min.x(),
                                c & 2 ? rest.max.y() : rest.min.y(),
                                c & 4 ? rest.max.z() : rest.min.z()));
        const std::string path = "$.motions." + motion.name;
        if (!region.empty() && ((moved.max.array() < region.min.array()).any() ||
                                (moved.min.array() > region.max.array()).any())) {
          add(path, "the moving group '" + motion.name +
                        "' lies entirely outside the study region at " + sample.label +
                        ": is the motion in the file's units and frame?");
          break;
        }
        const Vec3 centre = moved.center();
        // Between two samples of keyframes the group moves along a line (named poses and random
        // draws are no path).
        if (walls && previous && motion.kind == ObjectMotion::Kind::kKeyframes) {
          const Vec3 step = centre - *previous;
          const double length = step.norm();
          if (length > 1e-9) {
            if (const auto hit = walls->Intersect(Ray{*previous, step / length, 0.0, length})) {
              add(path, "the moving group '" + motion.name +
                            "' passes through a solid object between " + previous_label + " and " +
                            sample.label + " (" + metres(hit->t) + " along its path)");
              break;
            }
          }
        }
        previous = centre;
        previous_label = sample.label;
      }
    }
  }
  for (std::size_t i = 0; i < scene.study.pixel_targets.size(); ++i) {
    const PixelTarget& t = scene.study.pixel_targets[i];
    if (t.size_m > 2.0)
      add("$.study.pixel_targets[" + std::to_string(i) + "]",
          "the pixel target '" + t.name + "' is " + metres(t.size_m) +
              " across: a marker or a face that size? (units)");
  }
}

// Within this of a surface, a camera centre is "on" it (Warning::Kind::kOnSurface).
constexpr double kOnSurfaceDistance = 1e-3;

// The nearest surface from `p` along the 26 directions of a cube's faces, edges and corners, up to
// `limit` (returned when nothing is nearer): exact for the axis-aligned walls of a room, and within
// a factor 1.2 of the true distance for any plane.
double NearestSurfaceAlong26(const RayCaster& caster, const Vec3& p, double limit) {
  double best = limit + 1;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) {
        if (!x && !y && !z) continue;
        const Vec3 d = Vec3(x, y, z).normalized();
        if (const auto hit = caster.Intersect(Ray{p, d, 0.0, limit})) best = std::min(best, hit->t);
      }
  return best;
}

}  // namespace

const char* WarningKindName(Warning::Kind kind) {
  switch (kind) {
    case Warning::Kind::kInsideSolid:
      return "inside_solid";
    case Warning::Kind::kOutsideRoom:
      return "outside_room";
    case Warning::Kind::kSeesNoRegion:
      return "sees_no_region";
    case Warning::Kind::kLensDomain:
      return "lens_domain";
    case Warning::Kind::kOnSurface:
      return "on_surface";
    case Warning::Kind::kImplausible:
      return "implausible";
  }
  return "unknown";
}

std::string FormatWarning(const std::string& file, const Warning& w) {
  return file + ": " + w.json_path + ": " + w.reason;
}

LensCoverage ComputeLensCoverage(const CameraModel& model) {
  LensCoverage c;
  const Intrinsics& k = model.intrinsics();
  c.nominal_hfov_deg = HfovFromFocal(k.fx, k.width, k.model) * kDegPerRad;
  c.nominal_vfov_deg = HfovFromFocal(k.fy, k.height, k.model) * kDegPerRad;
  c.hfov_deg = EffectiveFov(model, 0);
  c.vfov_deg = EffectiveFov(model, 1);
  const double x0 = -0.5, x1 = k.width - 0.5, y0 = -0.5, y1 = k.height - 0.5;
  for (const Vec2& corner : {Vec2(x0, y0), Vec2(x1, y0), Vec2(x0, y1), Vec2(x1, y1)})
    if (!model.Unproject(corner)) c.domain_ends_inside_image = true;
  if (!c.domain_ends_inside_image) return c;  // the reachable set is star-shaped: all of it
  const int rows = std::min(k.height, 1024);
  const double cx = std::clamp(k.cx, x0, x1);
  double reachable = 0;  // sum over rows of the reachable share of the row
  for (int i = 0; i < rows; ++i) {
    const double y = y0 + (i + 0.5) * k.height / rows;
    const Vec2 centre(cx, y);
    if (!model.Unproject(centre)) continue;
    const double left = LastReachable(model, centre, Vec2(x0, y)).x();
    const double right = LastReachable(model, centre, Vec2(x1, y)).x();
    reachable += (right - left) / k.width;
  }
  c.unreachable_fraction = std::clamp(1.0 - reachable / rows, 0.0, 1.0);
  return c;
}

namespace {

// The per-camera checks of CheckRig, and what they share: the scene's geometry, the region's
// sample points and the reference point inside the region.
struct CameraChecks {
  const Scene& scene;
  const RayCaster& caster;
  const RigCheckOptions& options;
  const std::vector<int>& triangle_object;
  const Aabb& geometry;
  double pad;
  Solids& solids;
  const std::vector<Vec3>& samples;
  double scale;
  const VisibilityTester& tester;
  double eps;
  const Vec3& reference;
  bool enclosed;

  // Where camera `cam` is (inside a solid, on a surface, outside the room); false when it is not
  // placed where it could see the region.
  template <class Add>
  bool Placement(const Camera& cam, const Vec3& centre, const Add& add) const {
    // Where the camera is.
    bool placed = true;
    const int solid = solids.Containing(centre, /*strict=*/true, 1e-6 * scale);
    if (solid >= 0) {
      add(Warning::Kind::kInsideSolid, ".position",
          "camera '" + cam.id + "' is inside the solid object " + ObjectName(scene, solid) +
              " (centre " + Point(centre) + " m): it sees nothing; move it out");
      placed = false;
    } else if (NearestSurfaceAlong26(caster, centre, kOnSurfaceDistance) <= kOnSurfaceDistance) {
      // On a wall's face (a layout set in by nothing): the fields and the renderer both take the
      // centre's side of the surface (the segments start a tolerance away from the centre), but a
      // real camera's body cannot be there.
      add(Warning::Kind::kOnSurface, ".position",
          "camera '" + cam.id + "' sits on a surface (its centre " + Point(centre) +
              " m is within 1 mm of one): it sees what lies on its centre's side; move it off the "
              "surface");
    }
    if (solid < 0 && enclosed &&
        ((centre.array() < geometry.min.array() - pad).any() ||
         (centre.array() > geometry.max.array() + pad).any())) {
      add(Warning::Kind::kOutsideRoom, ".position",
          "camera '" + cam.id + "' is outside the modelled room: its centre " + Point(centre) +
              " m lies outside the bounds of the scene's geometry " + Point(geometry.min) + " to " +
              Point(geometry.max) + " m");
      placed = false;
    } else if (solid < 0 && enclosed) {
      // From the reference point towards the camera: a surface before it and nothing after it.
      const Vec3 to = centre - reference;
      const double distance = to.norm();
      if (distance > 2 * eps) {
        const Vec3 d = to / distance;
        const auto wall = caster.Intersect(Ray{reference, d, eps, distance - eps});
        const bool beyond = caster.Occluded(Ray{centre, d, eps, 1e3 * scale});
        // And the camera has no free line of sight to any region sample (a camera above a lamp
        // in a room without a ceiling still sees around it).
        bool all_blocked = wall && !beyond;
        for (std::size_t k = 0; all_blocked && k < samples.size(); ++k) {
          const Vec3 v = samples[k] - centre;
          const double l = v.norm();
          all_blocked = l > 2 * eps && caster.Occluded(Ray{centre, v / l, eps, l - eps});
        }
        if (all_blocked) {
          const int object = wall->triangle >= 0 && wall->triangle < int(triangle_object.size())
                                 ? triangle_object[wall->triangle]
                                 : -1;
          add(Warning::Kind::kOutsideRoom, ".position",
              "camera '" + cam.id +
                  "' is outside the modelled room: seen from the region it is "
                  "behind " +
                  ObjectName(scene, object) + " with nothing beyond it (centre " + Point(centre) +
                  " m)");
          placed = false;
        }
      }
    }
    return placed;
  }

  // What camera `c` sees of the region's sample points, and why not: a warning when it sees none.
  template <class Add>
  void RegionView(std::size_t c, const Camera& cam, const Vec3& centre, bool placed,
                  const Add& add) const {
    // What it sees of the region's sample points, and why not.
    std::map<ViewResult, int> why;
    std::map<int, int> occluders;  // object -> lines of sight it blocks where the point is in view
    int seen = 0;
    for (const Vec3& X : samples) {
      const ViewResult g = tester.TestGeometry(static_cast<int>(c), X);
      const Vec3 to = X - centre;
      const double distance = to.norm();
      std::optional<RayHit> hit;
      if (g == ViewResult::kSeen && distance > 2 * tester.epsilon())
        hit = caster.Intersect(
            Ray{centre, to / distance, tester.epsilon(), distance - tester.epsilon()});
      int object = -1;
      if (hit && hit->triangle >= 0 && hit->triangle < static_cast<int>(triangle_object.size()))
        object = triangle_object[hit->triangle];
      if (g == ViewResult::kSeen && !hit) {
        ++seen;
      } else if (g == ViewResult::kSeen) {
        ++why[ViewResult::kOccluded];
        ++occluders[object];
      } else {
        ++why[g];
      }
    }
    const bool sees_nothing = c < options.visible_voxels.size() ? options.visible_voxels[c] == 0
                                                                : (!samples.empty() && seen == 0);
    if (placed && sees_nothing) {
      ViewResult main = ViewResult::kOutsideImage;
      int most = -1;
      for (const auto& [r, n] : why)
        if (n > most) main = r, most = n;
      std::string cause;
      switch (main) {
        case ViewResult::kOutOfRange:
          cause = "the region is outside its working range";
          break;
        case ViewResult::kNotProjectable:
          cause = "the region is behind it";
          break;
        case ViewResult::kOccluded: {
          int object = -1, n = 0;
          for (const auto& [o, count] : occluders)
            if (count > n) object = o, n = count;
          cause = "its view is blocked" + (object >= 0 ? " by " + ObjectName(scene, object) : "");
          break;
        }
        default:
          cause = "the region is outside its image";
          break;
      }
      const std::string basis =
          c < options.visible_voxels.size()
              ? "none of the region's voxels"
              : "none of " + std::to_string(samples.size()) + " sample points of the region";
      add(Warning::Kind::kSeesNoRegion, "",
          "camera '" + cam.id + "' sees " + basis + " (mostly: " + cause +
              "); aim it at the region or disable it");
    }
  }
};

}  // namespace

std::vector<Warning> CheckRig(const Scene& scene, const Rig& rig, const RayCaster& caster,
                              const RigCheckOptions& options) {
  std::vector<Warning> out;
  const int rig_index = RigIndex(scene, rig);
  auto camera_path = [&](std::size_t c) {
    return "$.rigs[" + std::to_string(rig_index) + "].cameras[" + std::to_string(c) + "]";
  };
  CheckPlausibleValues(scene, rig, camera_path, &out);
  // The object of each triangle in scene.AllTriangles() order (the caster's), and the bounds of
  // all of them, without a copy of the triangles.
  std::vector<int> triangle_object;
  Aabb geometry;
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const TriangleMesh& mesh = scene.objects[o].mesh;
    for (const Vec3& v : mesh.vertices) geometry.Extend(v);
    triangle_object.insert(triangle_object.end(), mesh.triangles.size(), static_cast<int>(o));
  }
  const double pad = 1e-9 * std::max(1.0, geometry.diagonal());
  Solids solids(scene, options);
  const std::vector<Vec3> samples =
      RegionSamples(scene, std::max(1, options.region_samples_per_axis), options, &solids);
  const double scale = std::max(scene.Bounds().diagonal(), 1e-9);
  const VisibilityTester tester(rig.cameras, caster, scale);
  const double eps = tester.epsilon();
  // The reference point: the free region sample nearest the region's centre. The region is
  // enclosed (a room) when every horizontal ray from it meets geometry.
  Vec3 reference = scene.study.region.box.center();
  bool enclosed = false;
  if (!samples.empty()) {
    reference =
        *std::min_element(samples.begin(), samples.end(), [&](const Vec3& a, const Vec3& b) {
          return (a - scene.study.region.box.center()).squaredNorm() <
                 (b - scene.study.region.box.center()).squaredNorm();
        });
    enclosed = true;
    for (int k = 0; k < 16 && enclosed; ++k) {
      const double a = 2 * kPi * k / 16;
      enclosed =
          caster.Occluded(Ray{reference, Vec3(std::cos(a), std::sin(a), 0), eps, 1e3 * scale});
    }
  }

  const CameraChecks checks{scene, caster, options, triangle_object, geometry, pad, solids, samples,
                            scale, tester, eps,     reference,       enclosed};
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& cam = rig.cameras[c];
    if (!cam.enabled) continue;
    const Vec3 centre = cam.center();
    auto add = [&](Warning::Kind kind, const std::string& key, const std::string& reason) {
      out.push_back({kind, cam.id, camera_path(c) + key, reason});
    };

    const bool placed = checks.Placement(cam, centre, add);
    checks.RegionView(c, cam, centre, placed, add);

    // The lens.
    const LensCoverage lens = ComputeLensCoverage(cam.model);
    if (lens.domain_ends_inside_image)
      add(Warning::Kind::kLensDomain, ".distortion",
          "camera '" + cam.id +
              "': the distortion model folds back inside the image (its valid, "
              "monotonic domain ends there): " +
              Percent(lens.unreachable_fraction) +
              " of the pixels are reached by no ray; effective FOV " +
              Format("%.1f", lens.hfov_deg) + " x " + Format("%.1f", lens.vfov_deg) +
              " deg (nominal " + Format("%.1f", lens.nominal_hfov_deg) + " x " +
              Format("%.1f", lens.nominal_vfov_deg) + "); check the coefficients");
  }
  return out;
}

}  // namespace pandora
