#include "analysis/scene/plan_import.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "analysis/scene/scene_text.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

struct Segment {
  Vec2 a, b;
  int index = 0;  ///< The entity's number on its layer (1-based), for names.
};

std::vector<Segment> Segments(const PlanDrawing& drawing, const std::string& layer) {
  std::vector<Segment> out;
  int index = 0;
  for (const PlanDrawing::Polyline& p : drawing.polylines) {
    if (p.layer != layer) continue;
    ++index;
    const std::size_t n = p.points.size();
    for (std::size_t i = 0; i + 1 < n + (p.closed ? 1 : 0); ++i)
      if ((p.points[(i + 1) % n] - p.points[i]).norm() > 1e-6)
        out.push_back({p.points[i], p.points[(i + 1) % n], index});
  }
  return out;
}

// A box along the segment from a to b (a wall piece, a lintel), `thickness` wide, z0 to z1.
PlanBox AlongSegment(const std::string& name, const Vec2& a, const Vec2& b, double thickness,
                     double z0, double z1) {
  PlanBox box;
  box.name = name;
  const Vec2 mid = 0.5 * (a + b);
  box.centre = Vec3(mid.x(), mid.y(), 0.5 * (z0 + z1));
  box.size = Vec3((b - a).norm(), thickness, z1 - z0);
  box.yaw_deg = std::atan2(b.y() - a.y(), b.x() - a.x()) * kDegPerRad;
  return box;
}

using scene_text::ordered_json;

ordered_json Num(double v) { return scene_text::Number(scene_text::Clean(v)); }
ordered_json Xyz(const Vec3& v) {
  return ordered_json::array({Num(v.x()), Num(v.y()), Num(v.z())});
}

}  // namespace

PlanScene BuildPlan(const PlanDrawing& drawing, const PlanOptions& options,
                    const std::string& file) {
  const std::vector<Segment> walls = Segments(drawing, options.walls);
  if (walls.empty()) {
    std::string have;
    for (const std::string& l : drawing.layers) have += (have.empty() ? "'" : ", '") + l + "'";
    throw InputError(file, "", "no lines or polylines on the walls layer '" + options.walls + "'",
                     have.empty()
                         ? "the drawing has no lines at all"
                         : "the drawing's layers with lines: " + have + "; give {walls} LAYER");
  }
  const double t = options.thickness, h = options.height, tol = 1e-3;
  PlanScene scene;
  struct Opening {
    Segment s;
    bool door;
  };
  std::vector<Opening> openings;
  for (const Segment& s : Segments(drawing, options.doors)) openings.push_back({s, true});
  for (const Segment& s : Segments(drawing, options.windows)) openings.push_back({s, false});

  for (std::size_t w = 0; w < walls.size(); ++w) {
    const Segment& wall = walls[w];
    const double length = (wall.b - wall.a).norm();
    const Vec2 d = (wall.b - wall.a) / length, n(-d.y(), d.x());
    // Openings on this wall's line (both ends within half the thickness of it) cut it.
    std::vector<std::pair<double, double>> cuts;
    for (const Opening& o : openings) {
      if (std::abs((o.s.a - wall.a).dot(n)) > 0.5 * t + tol ||
          std::abs((o.s.b - wall.a).dot(n)) > 0.5 * t + tol)
        continue;
      double s0 = (o.s.a - wall.a).dot(d), s1 = (o.s.b - wall.a).dot(d);
      if (s0 > s1) std::swap(s0, s1);
      s0 = std::max(s0, 0.0), s1 = std::min(s1, length);
      if (s1 - s0 > tol) cuts.emplace_back(s0, s1);
    }
    std::sort(cuts.begin(), cuts.end());
    // An end that meets another wall is extended by half the thickness, closing the corner.
    auto meets = [&](const Vec2& p) {
      for (std::size_t o = 0; o < walls.size(); ++o)
        if (o != w && DistanceToSegment(p, walls[o].a, walls[o].b) <= tol) return true;
      return false;
    };
    const double start_ext = meets(wall.a) ? 0.5 * t : 0, end_ext = meets(wall.b) ? 0.5 * t : 0;
    double at = -start_ext;
    int piece = 0;
    auto add = [&](double s0, double s1) {
      if (s1 - s0 <= tol) return;
      const std::string name =
          "walls/" + std::to_string(w + 1) + (cuts.empty() ? "" : "." + std::to_string(++piece));
      scene.boxes.push_back(AlongSegment(name, wall.a + s0 * d, wall.a + s1 * d, t, 0, h));
    };
    for (const auto& [s0, s1] : cuts) {
      add(at, s0);
      at = std::max(at, s1);
    }
    add(at, length + end_ext);
    scene.walls_bounds.Extend(Vec3(wall.a.x(), wall.a.y(), 0));
    scene.walls_bounds.Extend(Vec3(wall.b.x(), wall.b.y(), h));
  }
  // Each opening's blocks along its own line: a lintel over a door; a sill and a lintel round a
  // window.
  int door = 0, window = 0;
  for (const Opening& o : openings) {
    if (o.door) {
      const std::string name = "doors/" + std::to_string(++door);
      if (options.door_height < h - tol)
        scene.boxes.push_back(
            AlongSegment(name + "/lintel", o.s.a, o.s.b, t, options.door_height, h));
    } else {
      const std::string name = "windows/" + std::to_string(++window);
      const double top = options.window_sill + options.window_height;
      if (options.window_sill > tol)
        scene.boxes.push_back(
            AlongSegment(name + "/sill", o.s.a, o.s.b, t, 0, options.window_sill));
      if (top < h - tol)
        scene.boxes.push_back(AlongSegment(name + "/lintel", o.s.a, o.s.b, t, top, h));
    }
  }
  scene.doors = door, scene.windows = window;
  // Slabs over the walls' outer bounds.
  const Aabb& b = scene.walls_bounds;
  const Vec2 lo = b.min.head<2>() - Vec2::Constant(0.5 * t),
             hi = b.max.head<2>() + Vec2::Constant(0.5 * t);
  PlanBox slab;
  slab.size = Vec3(hi.x() - lo.x(), hi.y() - lo.y(), options.slab);
  if (options.floor) {
    slab.name = "floor";
    slab.centre = Vec3(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), -0.5 * options.slab);
    scene.boxes.push_back(slab);
  }
  if (options.ceiling) {
    slab.name = "ceiling";
    slab.centre = Vec3(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), h + 0.5 * options.slab);
    scene.boxes.push_back(slab);
  }
  int item = 0;
  for (const PlanDrawing::Polyline& p : drawing.polylines) {
    const auto layer =
        std::find_if(options.furniture.begin(), options.furniture.end(),
                     [&p](const std::pair<std::string, double>& f) { return f.first == p.layer; });
    if (layer == options.furniture.end()) continue;
    Polygon2 polygon = p.points;
    if (!p.closed && polygon.size() > 3 && (polygon.front() - polygon.back()).norm() <= tol)
      polygon.pop_back();  // drawn closed by repeating the first point
    else if (!p.closed) {
      scene.notes.push_back("an open polyline on furniture layer '" + p.layer +
                            "' was skipped (furniture is a closed polyline)");
      continue;
    }
    const std::string problem = PolygonProblem(polygon);
    if (!problem.empty()) {
      scene.notes.push_back("furniture polyline " + std::to_string(item + 1) +
                            " was skipped: " + problem);
      continue;
    }
    scene.furniture.push_back({p.layer + "/" + std::to_string(++item), polygon, layer->second});
  }
  if (drawing.skipped > 0)
    scene.notes.push_back(drawing.skipped == 1
                              ? std::string("1 entity that is not a line or a polyline (an arc, "
                                            "circle, text or block) was not used")
                              : std::to_string(drawing.skipped) +
                                    " entities that are not lines or polylines (arcs, circles, "
                                    "text, blocks) were not used");
  return scene;
}

std::string PlanSceneText(const PlanScene& plan, const PlanOptions& o) {
  ordered_json objects = ordered_json::array();
  for (const PlanBox& b : plan.boxes) {
    ordered_json object = {
        {"name", b.name}, {"box", {{"size", Xyz(b.size)}}}, {"position", Xyz(b.centre)}};
    if (std::abs(b.yaw_deg) > 0) object["rotation_deg"] = Xyz(Vec3(0, 0, b.yaw_deg));
    object["solid"] = true;
    objects.push_back(object);
  }
  for (const PlanScene::Extrusion& f : plan.furniture) {
    ordered_json polygon = ordered_json::array();
    for (const Vec2& p : f.polygon) polygon.push_back({Num(p.x()), Num(p.y())});
    objects.push_back({{"name", f.name},
                       {"extrusion", {{"polygon", polygon}, {"height", Num(f.height)}}},
                       {"solid", true}});
  }
  const Aabb& w = plan.walls_bounds;
  const double inset = 0.5 * o.thickness + 0.05;
  const Vec3 lo(w.min.x() + inset, w.min.y() + inset, 0.05),
      hi(w.max.x() - inset, w.max.y() - inset, std::min(2.05, o.height - 0.05));
  const Vec3 aim(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), 0.5 * (lo.z() + hi.z()));
  ordered_json cameras = ordered_json::array();
  const double in = 0.5 * o.thickness + 0.3, z = o.height - 0.3;
  int k = 0;
  for (const Vec2& c : {Vec2(w.min.x() + in, w.min.y() + in), Vec2(w.max.x() - in, w.min.y() + in),
                        Vec2(w.max.x() - in, w.max.y() - in), Vec2(w.min.x() + in, w.max.y() - in)})
    cameras.push_back({{"id", "start_" + std::to_string(++k)},
                       {"position", Xyz(Vec3(c.x(), c.y(), z))},
                       {"look_at", Xyz(aim)},
                       {"resolution", ordered_json::array({1920, 1080})},
                       {"hfov_deg", 90}});
  ordered_json root = {{"pandora", 1},
                       {"objects", objects},
                       {"rigs", ordered_json::array({{{"name", "start"}, {"cameras", cameras}}})},
                       {"study",
                        {{"region", {{"box", {{"min", Xyz(lo)}, {"max", Xyz(hi)}}}}},
                         {"voxel_size", 0.1},
                         {"fields", ordered_json::array({"coverage", "cameras", "resolution"})}}}};
  return root.dump(2) + "\n";
}

}  // namespace pandora
