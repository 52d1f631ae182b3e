// `pandora rig`: generate a rig (ring, ceiling or wall grid, cameras along walls) and write it into
// the scene file, with a backup (docs/rig-generators.md).
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/surface_distance.h"
#include "analysis/rig/rig_check.h"
#include "analysis/rig/rig_generators.h"
#include "analysis/scene/scene_text.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/options.h"
#include "app/output.h"
#include "suggest/suggestion_file.h"

namespace pandora::app {
namespace {

int Count(const std::string& option, double v, int max) {
  if (!(v >= 1) || v != std::floor(v) || v > max)
    throw InputError(option, "", "expected a whole number from 1 to " + std::to_string(max));
  return static_cast<int>(v);
}

double Positive(const std::string& option, double v) {
  if (!(v > 0) || !std::isfinite(v))
    throw InputError(option, "", "must be a positive number of metres");
  return v;
}

std::string Metres(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

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
  for (GeneratedCamera& c : *cameras) {
    const Vec3 start = c.position;
    for (int step = 0; step < 32; ++step) {
      const double d = distance.Distance(c.position, 2 * clearance);
      if (d >= clearance * (1 - 1e-9)) break;
      Vec3 grad;
      for (int a = 0; a < 3; ++a) {
        Vec3 e = Vec3::Zero();
        e[a] = h;
        grad[a] = (distance.Distance(c.position + e, 4 * clearance) -
                   distance.Distance(c.position - e, 4 * clearance)) /
                  (2 * h);
      }
      if (!(grad.norm() > 1e-6))
        grad = (c.look_at - c.position).normalized();  // on a surface: go towards the aim
      c.position += (clearance - d + 1e-6 * clearance) * grad.normalized();
    }
    const double d = distance.Distance(c.position, 2 * clearance);
    if (d < clearance * (1 - 1e-6))
      throw InputError(option, "",
                       "camera " + c.id + " cannot be kept " + Metres(clearance) +
                           " m from every surface (it is " + Metres(d) + " m from one)",
                       "move the layout away from the walls and objects");
    if ((c.position - start).norm() > 0)
      notes.push_back("camera " + c.id + " moved " + Metres((c.position - start).norm()) +
                      " m away from a surface it was within " + Metres(clearance) + " m of");
  }
  return notes;
}

}  // namespace

int RunRig(const RigArgs& args) {
  const int generators =
      !args.ring.empty() + !args.grid.empty() + !args.wall_grid.empty() + !args.along.empty();
  if (generators != 1)
    throw InputError(
        "--ring", "",
        generators ? "give one layout, not " + std::to_string(generators) : "which layout?",
        "one of --ring N, --grid NX,NY, --wall-grid NU,NZ or --along X0,Y0,X1,Y1[,...]");
  if (args.name.empty()) throw InputError("--name", "", "the new rig needs a name");
  LoadOptions lo;  // meshes too: the cameras keep their clearance from every surface
  const std::string text = scene_text::ReadJsonText(args.scene, "scene file");
  const Scene scene = ParseScene(text, args.scene, lo);
  const Aabb& region = scene.study.region.box;
  const Vec3 aim = args.aim.empty() ? Vec3(region.center()) : ParseVec3("--aim", args.aim);
  const auto [width, height] = ParseImageSize("--resolution", args.resolution);
  if (!(args.hfov_deg > 0 && args.hfov_deg < 180))
    throw InputError("--hfov", "", "must be in (0, 180) degrees");
  const std::string prefix = args.prefix.empty() ? args.name + "_" : args.prefix;
  std::vector<GeneratedCamera> cameras;
  if (!args.ring.empty()) {
    const int n = Count("--ring", ParseNumbers("--ring", args.ring, 1)[0], 1000);
    if (std::isnan(args.radius))
      throw InputError("--radius", "", "a ring needs its radius", "e.g. --radius 4");
    if (std::isnan(args.height))
      throw InputError("--height", "", "a ring needs its height", "e.g. --height 2.5");
    Vec2 c = region.center().head<2>();
    if (!args.center.empty()) {
      const std::vector<double> xy = ParseNumbers("--center", args.center, 2);
      c = Vec2(xy[0], xy[1]);
    }
    cameras = RingCameras(n, Vec3(c.x(), c.y(), args.height), Positive("--radius", args.radius),
                          args.start_deg, aim, prefix);
  } else if (!args.grid.empty()) {
    const std::vector<double> g = ParseNumbers("--grid", args.grid, 2);
    const int nx = Count("--grid", g[0], 100), ny = Count("--grid", g[1], 100);
    if (args.rect.empty())
      throw InputError("--rect", "", "a ceiling grid needs its rectangle X0,Y0,X1,Y1");
    const std::vector<double> r = ParseNumbers("--rect", args.rect, 4);
    if (!(r[2] > r[0] && r[3] > r[1]))
      throw InputError("--rect", "", "expected X0 < X1 and Y0 < Y1");
    if (std::isnan(args.height))
      throw InputError("--height", "", "a ceiling grid needs its height");
    const Vec3* aimed = args.aim.empty() ? nullptr : &aim;
    cameras =
        CeilingGridCameras(nx, ny, Vec2(r[0], r[1]), Vec2(r[2], r[3]), args.height, aimed, prefix);
  } else if (!args.wall_grid.empty()) {
    const std::vector<double> g = ParseNumbers("--wall-grid", args.wall_grid, 2);
    const int nu = Count("--wall-grid", g[0], 100), nz = Count("--wall-grid", g[1], 100);
    if (args.wall.empty()) throw InputError("--wall", "", "a wall grid needs its wall X0,Y0,X1,Y1");
    const std::vector<double> w = ParseNumbers("--wall", args.wall, 4);
    if (!(std::hypot(w[2] - w[0], w[3] - w[1]) > 0))
      throw InputError("--wall", "", "the wall has no length");
    if (args.z_range.empty())
      throw InputError("--z-range", "", "a wall grid needs its heights Z0,Z1");
    const std::vector<double> z = ParseNumbers("--z-range", args.z_range, 2);
    if (!(z[1] >= z[0])) throw InputError("--z-range", "", "expected Z0 <= Z1");
    cameras = WallGridCameras(nu, nz, Vec2(w[0], w[1]), Vec2(w[2], w[3]), z[0], z[1], args.inset,
                              aim, prefix);
  } else {
    const std::vector<std::string> items = SplitList(args.along);
    if (items.size() < 4 || items.size() % 2)
      throw InputError("--along", "", "expected corners X0,Y0,X1,Y1[,X2,Y2...] (two or more)");
    const std::vector<double> xy = ParseNumbers("--along", args.along, items.size());
    std::vector<Vec2> walls;
    for (std::size_t i = 0; i < xy.size(); i += 2) {
      walls.emplace_back(xy[i], xy[i + 1]);
      if (walls.size() > 1 && !((walls.back() - walls[walls.size() - 2]).norm() > 0))
        throw InputError("--along", "",
                         "wall " + std::to_string(walls.size() - 1) + " has no length");
    }
    if (args.count < 1 || args.count > 1000)
      throw InputError("--count", "", "expected 1 to 1000 cameras");
    if (std::isnan(args.height))
      throw InputError("--height", "", "cameras along walls need their height");
    cameras = AlongWallsCameras(args.count, walls, args.height, args.inset, aim, prefix);
  }
  // Every camera keeps its clearance from every surface: the inset (walls), at least 5 cm.
  const std::string layout = !args.ring.empty()        ? "--ring"
                             : !args.grid.empty()      ? "--grid"
                             : !args.wall_grid.empty() ? "--wall-grid"
                                                       : "--along";
  const double clearance =
      (layout == "--wall-grid" || layout == "--along") ? std::max(args.inset, 0.05) : 0.05;
  const std::vector<std::string> moved = KeepClearance(scene, clearance, layout, &cameras);
  for (const GeneratedCamera& c : cameras) {
    scene.CheckLength(c.position.norm(), "--ring", "a camera position");
    if (!((c.look_at - c.position).norm() > 1e-9))
      throw InputError("--aim", "", "camera " + c.id + " sits on the point it should look at",
                       "move --aim");
  }

  // The rig in the file's form and units, appended (or replacing the rig of that name).
  using scene_text::ordered_json;
  ordered_json root = scene_text::ParseOrdered(text, args.scene);
  const double mpu = scene_text::MetresPerUnit(root, args.scene);
  auto point = [&](const Vec3& v) {
    return ordered_json::array({scene_text::Number(scene_text::Clean(v.x() / mpu)),
                                scene_text::Number(scene_text::Clean(v.y() / mpu)),
                                scene_text::Number(scene_text::Clean(v.z() / mpu))});
  };
  ordered_json rig = {{"name", args.name}, {"cameras", ordered_json::array()}};
  for (const GeneratedCamera& c : cameras)
    rig["cameras"].push_back({{"id", c.id},
                              {"position", point(c.position)},
                              {"look_at", point(c.look_at)},
                              {"up", ordered_json::array({c.up.x(), c.up.y(), c.up.z()})},
                              {"resolution", {width, height}},
                              {"hfov_deg", scene_text::Number(scene_text::Clean(args.hfov_deg))}});
  bool replaced = false;
  for (ordered_json& r : root["rigs"])
    if (r.is_object() && r.contains("name") && r["name"] == args.name) {
      if (!args.replace)
        throw InputError("--name", "", "the scene already has a rig '" + args.name + "'",
                         "choose another --name, or --replace to overwrite it");
      r = rig;
      replaced = true;
    }
  if (!replaced) root["rigs"].push_back(rig);
  const std::string new_text = scene_text::DumpLike(root, text);
  // The new file must read: the whole scene (meshes too), for the rig's plausibility warnings.
  const Scene after = ParseScene(new_text, args.scene);
  const Rig& written = after.FindRig(args.name);
  const auto caster = MakeEmbreeRayCaster(after.AllTriangles());
  const std::vector<Warning> warnings = CheckRig(after, written, *caster);
  if (args.dry_run) {
    std::fputs(new_text.c_str(), stdout);
  } else {
    const std::string backup = ReplaceSceneFileWithBackup(args.scene, text, new_text);
    if (!args.quiet)
      std::printf("%s rig %s (%zu cameras) in %s (previous file kept as %s)\n",
                  replaced ? "replaced" : "wrote", args.name.c_str(), cameras.size(),
                  args.scene.c_str(), backup.c_str());
  }
  if (!args.quiet)
    for (const std::string& note : moved) std::printf("%s\n", note.c_str());
  std::fflush(stdout);
  for (const Warning& w : warnings)
    std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(args.scene, w).c_str());
  return 0;
}

// Registers `pandora rig` and its options.
Command AddRigCommand(CLI::App& app, CommonOptions& /*common*/) {
  auto args = std::make_shared<RigArgs>();
  RigArgs& rig_args = *args;
  CLI::App* rg = app.add_subcommand("rig",
                                    "Generate a rig (ring, ceiling or wall grid, cameras along "
                                    "walls) and write it into the scene file (keeps a backup)");
  rg->add_option("scene", rig_args.scene, "Scene file (JSON)")->required();
  rg->add_option("--name", rig_args.name, "Name of the new rig")->required();
  rg->add_flag("--replace", rig_args.replace, "Overwrite the rig of that name");
  rg->add_option(
      "--ring", rig_args.ring,
      "Layout: N cameras on a horizontal circle (--radius, --height, --center X,Y,Z, --start-deg)");
  rg->add_option("--grid", rig_args.grid,
                 "Layout: NX,NY cameras over a ceiling rectangle (--rect X0,Y0,X1,Y1, --height), "
                 "looking down unless --aim");
  rg->add_option(
      "--wall-grid", rig_args.wall_grid,
      "Layout: NU,NZ cameras over a wall (--wall X0,Y0,X1,Y1, --z-range Z0,Z1, --inset)");
  rg->add_option(
      "--along", rig_args.along,
      "Layout: --count cameras evenly along walls X0,Y0,X1,Y1[,X2,Y2...] (--height, --inset)");
  rg->add_option("--count", rig_args.count, "With --along: how many cameras");
  rg->add_option("--radius", rig_args.radius, "Ring radius, metres");
  rg->add_option("--height", rig_args.height, "Camera height, metres");
  rg->add_option("--center", rig_args.center, "Ring centre X,Y (default: the region's centre)");
  rg->add_option("--start-deg", rig_args.start_deg,
                 "Ring: the first camera's angle from +x, degrees");
  rg->add_option("--rect", rig_args.rect, "Ceiling grid rectangle X0,Y0,X1,Y1, metres");
  rg->add_option("--wall", rig_args.wall, "Wall grid: the wall segment X0,Y0,X1,Y1, metres");
  rg->add_option("--z-range", rig_args.z_range, "Wall grid: heights Z0,Z1, metres");
  rg->add_option("--inset", rig_args.inset, "Distance in from the wall, metres")
      ->capture_default_str();
  rg->add_option("--aim", rig_args.aim,
                 "Point every camera looks at X,Y,Z (default: the region's centre)");
  rg->add_option("--resolution", rig_args.resolution, "Image size WxH")->capture_default_str();
  rg->add_option("--hfov", rig_args.hfov_deg, "Horizontal field of view, degrees")
      ->capture_default_str();
  rg->add_option("--prefix", rig_args.prefix, "Camera id prefix (default: the rig's name and _)");
  rg->add_flag("--dry-run", rig_args.dry_run, "Print the new scene file instead of writing it");
  rg->add_flag("-q,--quiet", rig_args.quiet, "Print nothing on success");
  return {rg, [args] { return RunRig(*args); }};
}

}  // namespace pandora::app
