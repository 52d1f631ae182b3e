#pragma once
/// \file plan_import.h
/// Floor plans from CAD (`pandora import-plan`, docs/scene-format.md "Floor plans"): the lines and
/// polylines of a DXF file by layer (dxflib stays inside plan_import_dxf.cpp), and the scene parts
/// they make: wall centre lines extruded into walls with the door and window openings drawn on
/// their own layers cut out (a lintel over a door, a sill and a lintel round a window), closed
/// polylines on the furniture layer extruded into furniture, a floor and a ceiling slab.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/scene/builders.h"

namespace pandora {

/// What a DXF file holds that a plan needs, in metres.
struct PlanDrawing {
  struct Polyline {
    std::string layer;
    std::vector<Vec2> points;
    bool closed = false;
  };
  std::vector<Polyline> polylines;  ///< LINEs are open 2-point polylines.
  double metres_per_unit = 1;
  std::string units;  ///< How the unit was found: "$INSUNITS 6 (m)", or as given.
  /// Every layer with a line or polyline, sorted, and how many entities of other kinds (arcs,
  /// circles, text, blocks) were skipped.
  std::vector<std::string> layers;
  int skipped = 0;
};

/// Reads `path` (ASCII or binary DXF). The unit comes from `units` when given (metres per drawing
/// unit), else from the header's $INSUNITS (1 in, 2 ft, 4 mm, 5 cm, 6 m, ...). Throws InputError
/// (file = path) when the file cannot be read or parsed, has no unit, or has a coordinate that is
/// not finite or beyond 1e6 m.
PlanDrawing ReadDxfPlan(const std::string& path, std::optional<double> units);

/// How a plan's layers become a scene.
struct PlanOptions {
  std::string walls = "walls", doors = "doors", windows = "windows";
  /// Furniture layers and the height of each one's pieces (metres).
  std::vector<std::pair<std::string, double>> furniture = {{"furniture", 0.75}};
  double height = 2.8, thickness = 0.15, door_height = 2.1, window_sill = 0.9, window_height = 1.2,
         slab = 0.2;
  bool floor = true, ceiling = true;
};

/// A block of the built plan: a box of `size` centred at `centre`, turned by `yaw_deg` about +z.
struct PlanBox {
  std::string name;
  Vec3 centre = Vec3::Zero(), size = Vec3::Ones();
  double yaw_deg = 0;
};

struct PlanScene {
  std::vector<PlanBox> boxes;  ///< Walls, lintels, sills, floor and ceiling.
  struct Extrusion {
    std::string name;
    Polygon2 polygon;
    double height = 0;
  };
  std::vector<Extrusion> furniture;
  Aabb walls_bounds;  ///< Bounds of the walls' centre lines (z: 0 to the height).
  int doors = 0, windows = 0;
  std::vector<std::string> notes;  ///< Entities that were not used, and why.
};

/// The scene parts of `drawing`. Throws InputError(file, "", ...) when the walls layer has no
/// lines, naming the layers the drawing has.
PlanScene BuildPlan(const PlanDrawing& drawing, const PlanOptions& options,
                    const std::string& file);

/// The scene file text of `plan` (JSON, metres): its boxes and furniture extrusions as solid
/// objects, a first rig "start" (four cameras in the corners of the walls' inner bounds, 0.3 m
/// below the ceiling, aimed at the study region's centre) and a study of the inside (0.05 m above
/// the floor to 2.05 m, 0.1 m voxels).
std::string PlanSceneText(const PlanScene& plan, const PlanOptions& options);

}  // namespace pandora
