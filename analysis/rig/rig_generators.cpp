// Rig generators: rings, ceiling and wall grids, cameras along walls (docs/rig-generators.md).
#include "analysis/rig/rig_generators.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/surface_distance.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

GeneratedCamera Aimed(const std::string& id, const Vec3& p, const Vec3& aim) {
  GeneratedCamera c;
  c.id = id;
  c.position = p;
  c.look_at = aim;
  // Looking straight up or down: +z cannot be the up direction; +y then.
  const Vec3 d = (aim - p).normalized();
  c.up = std::abs(d.z()) > 1.0 - 1e-9 ? Vec3::UnitY() : Vec3::UnitZ();
  return c;
}

std::string Id(const std::string& prefix, int k) { return prefix + std::to_string(k + 1); }

// The unit normal of wall a -> b in xy on the side of `aim`.
Vec2 Inward(const Vec2& a, const Vec2& b, const Vec3& aim) {
  const Vec2 d = (b - a).normalized();
  Vec2 n(-d.y(), d.x());
  if (n.dot(aim.head<2>() - a) < 0) n = -n;
  return n;
}

}  // namespace

std::vector<GeneratedCamera> RingCameras(int count, const Vec3& centre, double radius,
                                         double start_deg, const Vec3& aim,
                                         const std::string& prefix) {
  std::vector<GeneratedCamera> out;
  for (int k = 0; k < count; ++k) {
    const double a = (start_deg + 360.0 * k / count) * kPi / 180.0;
    out.push_back(Aimed(Id(prefix, k), centre + radius * Vec3(std::cos(a), std::sin(a), 0.0), aim));
  }
  return out;
}

std::vector<GeneratedCamera> CeilingGridCameras(int nx, int ny, const Vec2& min_xy,
                                                const Vec2& max_xy, double z, const Vec3* aim,
                                                const std::string& prefix) {
  std::vector<GeneratedCamera> out;
  const Vec2 step((max_xy.x() - min_xy.x()) / nx, (max_xy.y() - min_xy.y()) / ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const Vec3 p(min_xy.x() + (i + 0.5) * step.x(), min_xy.y() + (j + 0.5) * step.y(), z);
      out.push_back(
          Aimed(Id(prefix, static_cast<int>(out.size())), p, aim ? *aim : Vec3(p - Vec3::UnitZ())));
    }
  return out;
}

std::vector<GeneratedCamera> WallGridCameras(int nu, int nz, const Vec2& a, const Vec2& b,
                                             double z0, double z1, double inset, const Vec3& aim,
                                             const std::string& prefix) {
  std::vector<GeneratedCamera> out;
  const Vec2 n = Inward(a, b, aim);
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nu; ++i) {
      const Vec2 xy = a + (i + 0.5) / nu * (b - a) + inset * n;
      const Vec3 p(xy.x(), xy.y(), z0 + (j + 0.5) / nz * (z1 - z0));
      out.push_back(Aimed(Id(prefix, static_cast<int>(out.size())), p, aim));
    }
  return out;
}

std::vector<GeneratedCamera> AlongWallsCameras(int count, const std::vector<Vec2>& walls, double z,
                                               double inset, const Vec3& aim,
                                               const std::string& prefix) {
  std::vector<double> length{0.0};
  for (std::size_t i = 1; i < walls.size(); ++i)
    length.push_back(length.back() + (walls[i] - walls[i - 1]).norm());
  std::vector<GeneratedCamera> out;
  const double total = length.back();
  for (int k = 0; k < count; ++k) {
    const double s = (k + 0.5) * total / count;
    std::size_t i = 1;
    while (i + 1 < walls.size() && length[i] < s) ++i;
    const Vec2& a = walls[i - 1];
    const Vec2& b = walls[i];
    const double t = (s - length[i - 1]) / (length[i] - length[i - 1]);
    const Vec2 xy = a + t * (b - a) + inset * Inward(a, b, aim);
    out.push_back(Aimed(Id(prefix, k), Vec3(xy.x(), xy.y(), z), aim));
  }
  return out;
}

namespace {
std::string ClearanceMetres(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}
}  // namespace

// Moves each generated camera away from the scene's surfaces until its centre is at least
// `clearance` from every one (a camera near a corner, set in from its own wall, can sit on the next
// wall's face): along the distance's gradient (away from the nearest point), a few steps for
// corners. The aim point stays. Returns one note per moved camera; throws InputError naming
// `option` when a camera cannot be cleared (it is inside a solid thicker than the room allows).
std::vector<std::string> KeepClearance(const Scene& scene, double clearance,
                                       const std::string& option,
                                       std::vector<GeneratedCamera>* cameras) {
  std::vector<std::string> notes;
  const TriangleMesh mesh = scene.AllTriangles();
  if (mesh.triangles.empty()) return notes;
  const SurfaceDistance distance(mesh);
  const double h = 1e-5 * std::max(1.0, clearance);
  // The solids a camera may have landed inside (a cabinet a ring passes through).
  std::vector<std::unique_ptr<InsideMesh>> solids;
  for (const SceneObject& o : scene.objects)
    if (o.solid) solids.push_back(std::make_unique<InsideMesh>(o.mesh));
  auto gradient = [&](const Vec3& p, double limit) {
    Vec3 g;
    for (int a = 0; a < 3; ++a) {
      Vec3 e = Vec3::Zero();
      e[a] = h;
      g[a] = (distance.Distance(p + e, limit) - distance.Distance(p - e, limit)) / (2 * h);
    }
    return g;
  };
  for (GeneratedCamera& c : *cameras) {
    const Vec3 start = c.position;
    // Inside a solid: out towards the aim point (into the open room), then on.
    auto inside = [&solids](const Vec3& p) {
      for (const auto& s : solids)
        if (s->Inside(p)) return true;
      return false;
    };
    if (inside(c.position)) {
      const Vec3 to_aim = c.look_at - c.position;
      const double step = std::max(0.25 * clearance, 1e-3);
      for (double t = step; t < to_aim.norm() && inside(c.position); t += step)
        c.position = start + t * to_aim.normalized();
    }
    for (int step = 0; step < 32; ++step) {
      const double d = distance.Distance(c.position, 2 * clearance);
      if (d >= clearance * (1 - 1e-9)) break;
      Vec3 grad = gradient(c.position, 4 * clearance);
      if (!(grad.norm() > 1e-6))
        grad = (c.look_at - c.position).normalized();  // on a surface: go towards the aim
      c.position += (clearance - d + 1e-6 * clearance) * grad.normalized();
    }
    const double d = distance.Distance(c.position, 2 * clearance);
    if (inside(c.position))
      throw InputError(option, "", "camera " + c.id + " is inside a solid object",
                       "move the layout out of the objects");
    if (d < clearance * (1 - 1e-6))
      throw InputError(option, "",
                       "camera " + c.id + " cannot be kept " + ClearanceMetres(clearance) +
                           " m from every surface (it is " + ClearanceMetres(d) + " m from one)",
                       "move the layout away from the walls and objects");
    if ((c.position - start).norm() > 0)
      notes.push_back("camera " + c.id + " moved " + ClearanceMetres((c.position - start).norm()) +
                      " m away from a surface it was within " + ClearanceMetres(clearance) +
                      " m of (or inside)");
  }
  return notes;
}

}  // namespace pandora
