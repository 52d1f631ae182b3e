#include "analysis/scene/plan_import.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "tests/temp_dir.h"

namespace pandora {
namespace {

// A DXF (R12-style ASCII with LWPOLYLINEs) in `unit`s per metre: the 7 x 5 m lab of
// examples/lab_from_room as wall centre lines (the footprint grown by half the 0.15 m wall), a
// door on the south wall, a window on the east wall, two desks, and an arc (a door's swing) that
// is not used.
std::string LabDxf(double scale, int insunits) {
  std::ostringstream s;
  auto group = [&](int code, const std::string& v) { s << code << "\n" << v << "\n"; };
  auto num = [&](int code, double v) { s << code << "\n" << v * scale << "\n"; };
  auto lwpolyline = [&](const std::string& layer, const std::vector<Vec2>& p, bool closed) {
    group(0, "LWPOLYLINE");
    group(8, layer);
    group(90, std::to_string(p.size()));
    group(70, closed ? "1" : "0");
    for (const Vec2& v : p) num(10, v.x()), num(20, v.y());
  };
  auto line = [&](const std::string& layer, Vec2 a, Vec2 b) {
    group(0, "LINE");
    group(8, layer);
    num(10, a.x()), num(20, a.y()), num(30, 0), num(11, b.x()), num(21, b.y()), num(31, 0);
  };
  group(0, "SECTION");
  group(2, "HEADER");
  if (insunits >= 0) group(9, "$INSUNITS"), group(70, std::to_string(insunits));
  group(0, "ENDSEC");
  group(0, "SECTION");
  group(2, "ENTITIES");
  const double x = 3.575, y = 2.575;
  lwpolyline("walls", {{-x, -y}, {x, -y}, {x, y}, {-x, y}}, true);
  line("doors", {-2.9, -y}, {-2.0, -y});
  line("windows", {x, -1.0}, {x, 0.2});
  lwpolyline("furniture", {{-3.4, 1.6}, {-1.8, 1.6}, {-1.8, 2.4}, {-3.4, 2.4}}, true);
  lwpolyline("furniture", {{-0.8, 1.6}, {0.8, 1.6}, {0.8, 2.4}, {-0.8, 2.4}}, true);
  group(0, "ARC");
  group(8, "doors");
  num(10, -2.9), num(20, -y), num(30, 0), num(40, 0.9);
  group(50, "0"), group(51, "90");
  group(0, "ENDSEC");
  group(0, "EOF");
  return s.str();
}

const char* kRoomScene = R"({"objects": [
  {"name": "lab", "room": {"footprint": [[-3.5, -2.5], [3.5, -2.5], [3.5, 2.5], [-3.5, 2.5]],
   "height": 2.8, "openings": [{"wall": 0, "offset": 0.6}, {"wall": 1, "type": "window", "offset": 1.5}],
   "furniture": [{"type": "desk", "at": [-2.6, 2.0]}, {"type": "desk", "at": [0, 2.0]}]}}],
  "rigs": [{"name": "r", "cameras": [{"id": "c", "position": [3, 2, 2.5], "look_at": [0, 0, 1], "resolution": [1280, 720], "hfov_deg": 60}]}],
  "study": {"region": {"box": {"min": [-3, -2, 0.05], "max": [3, 2, 2]}}}})";

std::string Write(const testing::TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = (dir.path() / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// The imported plan is the room-object scene: rays from inside the room in every direction hit
// the same surface at the same distance (to float precision), through the door and the window too.
TEST(PlanImport, TheLabsPlanImportsIntoTheSameRoom) {
  testing::TempDir dir;
  for (const auto& [scale, code] : {std::pair<double, int>{1.0, 6}, {1000.0, 4}, {100.0, 5}}) {
    const PlanDrawing drawing =
        ReadDxfPlan(Write(dir, "lab.dxf", LabDxf(scale, code)), std::nullopt);
    EXPECT_DOUBLE_EQ(drawing.metres_per_unit, 1.0 / scale);
    EXPECT_EQ(drawing.skipped, 1);  // the arc
    const PlanScene plan = BuildPlan(drawing, PlanOptions(), "lab.dxf");
    EXPECT_EQ(plan.doors, 1);
    EXPECT_EQ(plan.windows, 1);
    ASSERT_EQ(plan.furniture.size(), 2u);
    const Scene imported = ParseScene(PlanSceneText(plan, PlanOptions()), "plan.json");
    const Scene room = ParseScene(kRoomScene, "room.json");
    const auto a = MakeEmbreeRayCaster(imported.AllTriangles());
    const auto b = MakeEmbreeRayCaster(room.AllTriangles());
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    int through_openings = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 origin(3.3 * u(rng), 2.3 * u(rng), 1.4 + 1.3 * u(rng));
      const Vec3 dir = Vec3(u(rng), u(rng), u(rng)).normalized();
      if (origin.y() > 1.5 && origin.z() < 0.8) continue;  // inside or under a desk
      const Ray ray{origin, dir, 0, 100};
      const auto ha = a->Intersect(ray), hb = b->Intersect(ray);
      ASSERT_EQ(ha.has_value(), hb.has_value()) << origin.transpose() << " " << dir.transpose();
      if (!ha) {
        ++through_openings;
        continue;
      }
      EXPECT_NEAR(ha->t, hb->t, 1e-5) << origin.transpose() << " " << dir.transpose();
    }
    EXPECT_GT(through_openings, 50);
  }
}

TEST(PlanImport, BadPlansAreOneLineInputErrors) {
  testing::TempDir dir;
  auto error = [&](const std::string& text, std::optional<double> units = std::nullopt,
                   const std::string& walls = "walls") {
    try {
      PlanOptions o;
      o.walls = walls;
      BuildPlan(ReadDxfPlan(Write(dir, "p.dxf", text), units), o, "p.dxf");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(read)");
  };
  EXPECT_NE(error(LabDxf(1, -1)).find("does not say its unit"), std::string::npos);
  EXPECT_EQ(error(LabDxf(1, -1), 1.0), "(read)");
  EXPECT_NE(error(LabDxf(1, 6), std::nullopt, "wall")
                .find("the drawing's layers with lines: "
                      "'doors', 'furniture', 'walls', "
                      "'windows'"),
            std::string::npos);
  EXPECT_NE(error(LabDxf(1e9, 6)).find("beyond 1e6 m"), std::string::npos);
  // Damaged files: truncated and overwritten anywhere, they read or fail with an InputError.
  const std::string good = LabDxf(1, 6);
  std::mt19937_64 rng(3);
  for (int i = 0; i < 1000; ++i) {
    std::string bad = good.substr(0, 1 + rng() % (good.size() - 1));
    if (i % 2)
      for (int k = 0; k < 4; ++k) bad[rng() % bad.size()] = char(rng() % 256);
    const std::string result = error(bad);
    EXPECT_TRUE(result == "(read)" || result.find("p.dxf") != std::string::npos) << result;
  }
}

}  // namespace
}  // namespace pandora
