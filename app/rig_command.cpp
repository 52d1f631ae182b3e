// `pandora rig`: generate a rig (ring, ceiling or wall grid, cameras along walls) and write it into
// the scene file, with a backup (docs/rig-generators.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <set>
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
#include "suggest/propose.h"
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

// The lens keys every generated camera gets: --resolution and --hfov, or a catalogue model
// (its resolution, widest zoom, distortion, range); with --ptz a head zooming over WIDEST,NARROWEST
// (or, `--ptz zoom`, over the catalogue model's zoom range).
struct CameraTemplate {
  scene_text::ordered_json keys;
  std::optional<Vec2> range_m;  ///< near, far in metres (written in the file's units).
};
CameraTemplate CameraTemplateOf(const RigArgs& args, int width, int height) {
  using scene_text::Clean;
  using scene_text::Number;
  using scene_text::ordered_json;
  CameraTemplate t;
  double hfov = args.hfov_deg;
  if (!args.catalogue.empty()) {
    if (args.model.empty()) throw InputError("--model", "", "which catalogue model?");
    std::vector<ProposeLens> lenses;
    for (const ProposeLens& l : ReadCameraCatalogue(args.catalogue))
      if (l.model == args.model) lenses.push_back(l);
    if (lenses.empty())
      throw InputError("--model", "", "no model '" + args.model + "' in " + args.catalogue);
    const ProposeLens& widest = *std::max_element(
        lenses.begin(), lenses.end(),
        [](const ProposeLens& a, const ProposeLens& b) { return a.hfov_deg < b.hfov_deg; });
    const Intrinsics& k = widest.intrinsics;
    width = k.width, height = k.height, hfov = widest.hfov_deg;
    t.keys["resolution"] = {width, height};
    t.keys["hfov_deg"] = Number(Clean(hfov));
    if (k.model != LensModel::kPinhole) t.keys["distortion"] = scene_text::DistortionJson(k);
    t.range_m = Vec2(widest.near, widest.far < 1e8 ? widest.far : 1e6);
    if (args.ptz == "zoom") {
      if (lenses.size() < 2)
        throw InputError("--ptz", "", "model '" + args.model + "' has no zoom range",
                         "give --ptz WIDEST,NARROWEST");
      const double narrow = std::min_element(lenses.begin(), lenses.end(),
                                             [](const ProposeLens& a, const ProposeLens& b) {
                                               return a.hfov_deg < b.hfov_deg;
                                             })
                                ->hfov_deg;
      t.keys["ptz"] = {{"zoom_hfov_deg", {Number(Clean(hfov)), Number(Clean(narrow))}}};
    }
  } else {
    if (!args.model.empty()) throw InputError("--model", "", "--model needs --catalogue");
    if (args.ptz == "zoom") throw InputError("--ptz", "", "--ptz zoom needs --catalogue");
    t.keys["resolution"] = {width, height};
    t.keys["hfov_deg"] = Number(Clean(hfov));
  }
  if (!args.ptz.empty() && args.ptz != "zoom") {
    const std::vector<double> z = ParseNumbers("--ptz", args.ptz, 2);
    if (!(z[0] >= hfov - 1e-9 && z[1] <= hfov + 1e-9 && z[1] > 0 && z[0] < 180))
      throw InputError("--ptz", "",
                       "expected WIDEST,NARROWEST fields of view (degrees) round the camera's " +
                           Number(Clean(hfov)).dump() + " (WIDEST >= it >= NARROWEST > 0)");
    t.keys["ptz"] = {{"zoom_hfov_deg", {Number(Clean(z[0])), Number(Clean(z[1]))}}};
  }
  return t;
}
// The cameras of the one layout the options give (InputError naming the option at fault).
std::vector<GeneratedCamera> GenerateLayout(const RigArgs& args, const Aabb& region,
                                            const Vec3& aim, const std::string& prefix) {
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
    return RingCameras(n, Vec3(c.x(), c.y(), args.height), Positive("--radius", args.radius),
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
    return CeilingGridCameras(nx, ny, Vec2(r[0], r[1]), Vec2(r[2], r[3]), args.height, aimed,
                              prefix);
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
    return WallGridCameras(nu, nz, Vec2(w[0], w[1]), Vec2(w[2], w[3]), z[0], z[1], args.inset, aim,
                           prefix);
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
    return AlongWallsCameras(args.count, walls, args.height, args.inset, aim, prefix);
  }
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
  std::vector<GeneratedCamera> cameras = GenerateLayout(args, region, aim, prefix);
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
  ordered_json* existing = nullptr;
  for (ordered_json& r : root["rigs"])
    if (r.is_object() && r.contains("name") && r["name"] == args.name) existing = &r;
  if (args.add && args.replace) throw InputError("--add", "", "give --add or --replace, not both");
  if (existing && !args.replace && !args.add)
    throw InputError("--name", "", "the scene already has a rig '" + args.name + "'",
                     "choose another --name, --replace to overwrite it, or --add to add to it");
  // Added to a rig: the new ids continue after the ones it has (name_13, name_14, ...).
  if (existing && args.add) {
    std::set<std::string> used;
    for (const ordered_json& c : (*existing)["cameras"])
      if (c.is_object() && c.contains("id")) used.insert(scene_text::IdOf(c["id"]));
    int next = int(used.size());
    for (GeneratedCamera& c : cameras) {
      while (used.count(c.id = prefix + std::to_string(++next))) {
      }
      used.insert(c.id);
    }
  }
  const CameraTemplate lens = CameraTemplateOf(args, width, height);
  ordered_json added = ordered_json::array();
  for (const GeneratedCamera& c : cameras) {
    ordered_json camera = {{"id", c.id},
                           {"position", point(c.position)},
                           {"look_at", point(c.look_at)},
                           {"up", ordered_json::array({c.up.x(), c.up.y(), c.up.z()})}};
    for (const auto& [key, value] : lens.keys.items()) camera[key] = value;
    if (lens.range_m)
      camera["range"] = {{"near", scene_text::Number(scene_text::Clean(lens.range_m->x() / mpu))},
                         {"far", scene_text::Number(scene_text::Clean(lens.range_m->y() / mpu))}};
    added.push_back(camera);
  }
  const bool replaced = existing && !args.add;
  if (existing && args.add) {
    for (const ordered_json& c : added) (*existing)["cameras"].push_back(c);
  } else if (existing) {
    *existing = {{"name", args.name}, {"cameras", added}};
  } else {
    root["rigs"].push_back({{"name", args.name}, {"cameras", added}});
  }
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
                  replaced ? "replaced" : (existing ? "added to" : "wrote"), args.name.c_str(),
                  cameras.size(), args.scene.c_str(), backup.c_str());
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
  rg->add_flag("--add", rig_args.add,
               "Add the cameras to the rig of that name (several layouts into one rig)");
  rg->add_option("--catalogue", rig_args.catalogue,
                 "Camera catalogue (JSON, docs/propose.md): the cameras are --model");
  rg->add_option("--model", rig_args.model, "The catalogue's model for every camera");
  rg->add_option("--ptz", rig_args.ptz,
                 "Make every camera a PTZ head zooming over WIDEST,NARROWEST degrees (or \"zoom\": "
                 "the catalogue model's zoom range)");
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
