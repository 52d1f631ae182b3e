// Rig generators (issue 14): the cameras sit where the layout's closed form puts them and look at
// the aim point once read back through the scene format (look_at + up).
#include "analysis/rig/rig_generators.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/surface_distance.h"
#include "analysis/scene/scene.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

// The cameras as a rig of the scene format, read back.
Rig ReadBack(const std::vector<GeneratedCamera>& cameras) {
  nlohmann::json rig = {{"name", "g"}, {"cameras", nlohmann::json::array()}};
  for (const GeneratedCamera& c : cameras)
    rig["cameras"].push_back({{"id", c.id},
                              {"position", {c.position.x(), c.position.y(), c.position.z()}},
                              {"look_at", {c.look_at.x(), c.look_at.y(), c.look_at.z()}},
                              {"up", {c.up.x(), c.up.y(), c.up.z()}},
                              {"resolution", {640, 480}},
                              {"hfov_deg", 60}});
  return ParseRigJson(rig, "gen.json", "$.rig");
}

void ExpectAimedAt(const Rig& rig, const Vec3& aim) {
  for (const Camera& c : rig.cameras) {
    const Vec3 axis = c.world_from_camera.linear().col(2);
    EXPECT_LE((axis - (aim - c.center()).normalized()).norm(), 1e-12) << c.id;
    EXPECT_LE(std::abs(c.world_from_camera.linear().col(0).z()), 1e-12) << c.id;  // level: no roll
  }
}

TEST(RigGenerators, RingIsEvenlySpacedOnItsCircleAndAimed) {
  const Vec3 centre(1, -2, 2.5), aim(1, -2, 1);
  const auto cams = RingCameras(12, centre, 4.0, 15.0, aim, "r");
  ASSERT_EQ(cams.size(), 12u);
  EXPECT_EQ(cams[0].id, "r1");
  EXPECT_EQ(cams[11].id, "r12");
  for (int k = 0; k < 12; ++k) {
    const Vec3 d = cams[k].position - centre;
    EXPECT_NEAR(d.norm(), 4.0, 1e-12);
    EXPECT_NEAR(d.z(), 0.0, 1e-15);
    EXPECT_NEAR(std::atan2(d.y(), d.x()), std::remainder((15.0 + 30.0 * k) * kPi / 180.0, 2 * kPi),
                1e-12);
  }
  ExpectAimedAt(ReadBack(cams), aim);
}

TEST(RigGenerators, CeilingGridSitsAtCellCentresLookingDown) {
  const auto cams = CeilingGridCameras(3, 2, Vec2(-3, -2), Vec2(3, 2), 2.8, nullptr, "c");
  ASSERT_EQ(cams.size(), 6u);
  EXPECT_TRUE(cams[0].position.isApprox(Vec3(-2, -1, 2.8), 1e-15));
  EXPECT_TRUE(cams[5].position.isApprox(Vec3(2, 1, 2.8), 1e-15));
  const Rig rig = ReadBack(cams);
  for (const Camera& c : rig.cameras) {
    EXPECT_LE((c.world_from_camera.linear().col(2) - Vec3(0, 0, -1)).norm(), 1e-12);
    EXPECT_LE((c.world_from_camera.linear().col(1) - Vec3(0, -1, 0)).norm(),
              1e-12);  // image up is +y
  }
  const Vec3 aim(0, 0, 1);
  ExpectAimedAt(ReadBack(CeilingGridCameras(2, 2, Vec2(-3, -2), Vec2(3, 2), 2.8, &aim, "c")), aim);
}

TEST(RigGenerators, WallGridIsInsetTowardsTheAimAndAimed) {
  const Vec3 aim(0, 0, 1);
  // The wall y = 3 from x = -4 to 4: cameras 0.2 m in (towards the aim, y < 3).
  const auto cams = WallGridCameras(4, 2, Vec2(-4, 3), Vec2(4, 3), 1.0, 2.6, 0.2, aim, "w");
  ASSERT_EQ(cams.size(), 8u);
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 4; ++i) {
      const Vec3& p = cams[j * 4 + i].position;
      EXPECT_NEAR(p.x(), -4 + (i + 0.5) * 2, 1e-12);
      EXPECT_NEAR(p.y(), 2.8, 1e-12);
      EXPECT_NEAR(p.z(), 1.0 + (j + 0.5) * 0.8, 1e-12);
    }
  ExpectAimedAt(ReadBack(cams), aim);
}

TEST(RigGenerators, AlongWallsIsEvenByLengthAndInset) {
  // An L of walls: 6 m along y = -3, then 4 m up x = 3; 5 cameras every 2 m of length.
  const std::vector<Vec2> walls{Vec2(-3, -3), Vec2(3, -3), Vec2(3, 1)};
  const Vec3 aim(0, 0, 1);
  const auto cams = AlongWallsCameras(5, walls, 2.4, 0.15, aim, "a");
  ASSERT_EQ(cams.size(), 5u);
  const Vec3 expected[5] = {
      {-2, -2.85, 2.4}, {0, -2.85, 2.4}, {2, -2.85, 2.4}, {2.85, -2, 2.4}, {2.85, 0, 2.4}};
  for (int k = 0; k < 5; ++k) EXPECT_LE((cams[k].position - expected[k]).norm(), 1e-12) << k;
  ExpectAimedAt(ReadBack(cams), aim);
}

// Every generated camera keeps its stated clearance from every surface (issue 32): an L-shaped
// room (walls, floor, ceiling) with a cabinet, and layouts that put cameras on or in them: along
// the walls round the reflex corner, a wall grid beside the cabinet, a ceiling grid 2 cm under the
// ceiling, a ring with a camera inside the cabinet.
TEST(RigGenerators, EveryCameraKeepsItsClearance) {
  const Scene scene = ParseScene(R"({"objects": [
    {"name": "lab", "room": {"footprint": [[0, 0], [7, 0], [7, 3], [4, 3], [4, 5], [0, 5]],
     "height": 2.8, "furniture": [{"type": "cabinet", "at": [1, 4.7]}]}}],
    "rigs": [{"name": "r", "cameras": [{"id": "c", "position": [1, 1, 2], "look_at": [2, 2, 1],
      "resolution": [640, 480], "hfov_deg": 60}]}],
    "study": {"region": {"box": {"min": [0.5, 0.5, 0.1], "max": [3.5, 4.5, 2]}}}})",
                                 "l.json");
  const Vec3 aim(2, 2, 1);
  struct Case {
    const char* name;
    std::vector<GeneratedCamera> cameras;
    double clearance;
  };
  // Along [(0, 0), (7, 0), (7, 3)] (10 m), camera 3 of 5 is at 7 m: the corner.
  const std::vector<Vec2> walls = {{0, 0}, {7, 0}, {7, 3}};
  const std::vector<Case> cases = {
      {"along", AlongWallsCameras(5, walls, 2.4, 0.1, aim, "a"), 0.1},
      {"wall grid", WallGridCameras(4, 3, Vec2(0, 5), Vec2(3, 5), 0.5, 2.5, 0.1, aim, "w"), 0.1},
      {"ceiling grid", CeilingGridCameras(3, 3, Vec2(0.2, 0.2), Vec2(3.8, 4.8), 2.78, nullptr, "g"),
       0.05},
      {"ring", RingCameras(8, Vec3(1.3, 3.5, 1.5), 1.2, 0, aim, "r"), 0.05}};
  const SurfaceDistance distance(scene.AllTriangles());
  for (Case c : cases) {
    int closer = 0;
    for (const GeneratedCamera& g : c.cameras) {
      bool inside = false;
      for (const SceneObject& o : scene.objects)
        inside |= o.solid && InsideMesh(o.mesh).Inside(g.position);
      closer += inside || distance.Distance(g.position) < c.clearance * (1 - 1e-6);
    }
    EXPECT_GT(closer, 0) << c.name << ": the case must start with cameras too close "
                         << c.cameras[0].position.transpose();
    const std::vector<std::string> notes =
        KeepClearance(scene, c.clearance, "--" + std::string(c.name), &c.cameras);
    EXPECT_EQ(int(notes.size()), closer) << c.name;
    for (const GeneratedCamera& g : c.cameras) {
      EXPECT_GE(distance.Distance(g.position), c.clearance * (1 - 1e-6))
          << c.name << " " << g.id << " at " << g.position.transpose();
      for (const SceneObject& o : scene.objects)
        EXPECT_FALSE(o.solid && InsideMesh(o.mesh).Inside(g.position)) << c.name << " " << g.id;
    }
  }
}

}  // namespace
}  // namespace pandora
