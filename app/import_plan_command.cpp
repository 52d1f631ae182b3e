// `pandora import-plan`: a scene file from a DXF floor plan (walls with their door and window
// openings, furniture, floor and ceiling; docs/scene-format.md "Floor plans").
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/scene/plan_import.h"
#include "analysis/scene/scene.h"
#include "analysis/scene/scene_text.h"
#include "analysis/util/error.h"
#include "analysis/util/output_transaction.h"
#include "analysis/util/units.h"
#include "app/cli.h"
#include "app/commands.h"

namespace pandora::app {
namespace {

struct ImportPlanArgs {
  std::string plan, out, units;
  std::vector<std::string> furniture;  ///< --furniture LAYER[:HEIGHT], repeatable.
  double furniture_height = 0.75;
  PlanOptions options;
  bool replace = false, quiet = false;
};

double UnitOption(const std::string& unit) {
  if (const double metres = MetresPerUnitNamed(unit); metres > 0) return metres;
  throw InputError("--units", "", "unknown unit '" + unit + "'", "one of m, cm, mm, in, ft");
}

void CheckLengthOption(const char* option, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi))
    throw InputError(option, "",
                     "expected " + scene_text::Number(lo).dump() + " to " +
                         scene_text::Number(hi).dump() + " m");
}

int RunImportPlan(const ImportPlanArgs& args) {
  if (args.out.empty()) throw InputError("--out", "", "where should the scene go?");
  const PlanOptions& o = args.options;
  CheckLengthOption("--height", o.height, 0.5, 100);
  CheckLengthOption("--thickness", o.thickness, 0.01, 5);
  CheckLengthOption("--door-height", o.door_height, 0.5, 100);
  CheckLengthOption("--window-sill", o.window_sill, 0, 100);
  CheckLengthOption("--window-height", o.window_height, 0.05, 100);
  CheckLengthOption("--furniture-height", args.furniture_height, 0.01, 100);
  PlanOptions options = o;
  options.furniture.clear();
  for (const std::string& item :
       args.furniture.empty() ? std::vector<std::string>{"furniture"} : args.furniture) {
    const auto colon = item.rfind(':');
    double height = args.furniture_height;
    if (colon != std::string::npos) {
      char* end = nullptr;
      const std::string number = item.substr(colon + 1);
      height = std::strtod(number.c_str(), &end);
      if (number.empty() || *end != '\0')
        throw InputError("--furniture", "", "expected LAYER or LAYER:HEIGHT, got '" + item + "'");
      CheckLengthOption("--furniture", height, 0.01, 100);
    }
    const std::string layer = item.substr(0, colon);
    if (layer.empty()) throw InputError("--furniture", "", "the layer name is empty");
    options.furniture.emplace_back(layer, height);
  }
  const std::optional<double> units =
      args.units.empty() ? std::nullopt : std::optional<double>(UnitOption(args.units));
  const PlanDrawing drawing = ReadDxfPlan(args.plan, units);
  const PlanScene plan = BuildPlan(drawing, options, args.plan);
  const std::string text = PlanSceneText(plan, options);
  // The scene must read back as a scene (every part within the limits).
  const Scene scene = ParseScene(text, args.out);
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(args.out, ec) && fs::equivalent(args.out, args.plan, ec))
    throw InputError("--out", "", "'" + args.out + "' is the floor plan itself",
                     "write the scene to another file");
  if (fs::exists(args.out, ec)) {
    if (!args.replace)
      throw InputError("--out", "", "'" + args.out + "' exists",
                       "choose another file, or --replace to overwrite it (a backup is kept)");
    const std::string old = scene_text::ReadJsonText(args.out, "scene file");
    const std::string backup = ReplaceSceneFileWithBackup(args.out, old, text);
    if (!args.quiet) std::printf("previous %s kept as %s\n", args.out.c_str(), backup.c_str());
  } else {
    OutputTransaction transaction;
    transaction.AddInput(args.plan, "floor plan");
    transaction.Write(args.out, "--out", text);
    transaction.Commit();
  }
  if (!args.quiet) {
    std::printf(
        "wrote %s: %zu objects (walls, %d door%s, %d window%s, %zu furniture, %s%s), "
        "units %s; a first rig 'start' of 4 cameras\n",
        args.out.c_str(), scene.objects.size(), plan.doors, plan.doors == 1 ? "" : "s",
        plan.windows, plan.windows == 1 ? "" : "s", plan.furniture.size(),
        o.floor ? "floor" : "no floor", o.ceiling ? ", ceiling" : ", no ceiling",
        drawing.units.c_str());
    for (const std::string& note : plan.notes) std::printf("note: %s\n", note.c_str());
  }
  return 0;
}

}  // namespace

// Registers `pandora import-plan` and its options.
Command AddImportPlanCommand(CLI::App& app, CommonOptions& /*common*/) {
  auto args = std::make_shared<ImportPlanArgs>();
  ImportPlanArgs& a = *args;
  PlanOptions& o = a.options;
  CLI::App* c = app.add_subcommand(
      "import-plan",
      "Make a scene file from a DXF floor plan: wall centre lines extruded into walls, door and "
      "window openings, furniture outlines, floor and ceiling");
  c->add_option("plan", a.plan, "Floor plan (DXF)")->required();
  c->add_option("-o,--out", a.out, "The scene file to write")->required();
  c->add_flag("--replace", a.replace, "Overwrite --out when it exists (keeps a backup)");
  c->add_option("--walls,--layer", o.walls, "Layer of the walls' centre lines")
      ->capture_default_str();
  c->add_option("--doors", o.doors, "Layer of door openings (a line across each)")
      ->capture_default_str();
  c->add_option("--windows", o.windows, "Layer of window openings (a line across each)")
      ->capture_default_str();
  c->add_option("--furniture", a.furniture,
                "Layer of furniture outlines (closed polylines), LAYER or LAYER:HEIGHT; "
                "repeatable (default: furniture)");
  c->add_option("--height", o.height, "Wall height, metres")->capture_default_str();
  c->add_option("--thickness", o.thickness, "Wall thickness, metres")->capture_default_str();
  c->add_option("--door-height", o.door_height, "Door height, metres")->capture_default_str();
  c->add_option("--window-sill", o.window_sill, "Window sill height, metres")
      ->capture_default_str();
  c->add_option("--window-height", o.window_height, "Window height, metres")->capture_default_str();
  c->add_option("--furniture-height", a.furniture_height,
                "Height of furniture on layers given without one, metres")
      ->capture_default_str();
  c->add_option("--units", a.units,
                "The drawing's unit when its header has none (or to override it): m, cm, mm, "
                "in, ft");
  c->add_flag("!--no-floor", o.floor, "No floor slab");
  c->add_flag("!--no-ceiling", o.ceiling, "No ceiling slab");
  c->add_flag("-q,--quiet", a.quiet, "Print nothing on success");
  return {c, [args] { return RunImportPlan(*args); }};
}

}  // namespace pandora::app
