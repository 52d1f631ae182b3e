#include "analysis/scene/builders.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>

#include "analysis/geometry/primitives.h"
#include "analysis/scene/scene.h"
#include "analysis/scene/surface_targets.h"
#include "analysis/util/error.h"

namespace pandora {
namespace {

double TriangleArea2(const Polygon2& p, const Eigen::Vector3i& t) {
  const Vec2 a = p[t[0]], b = p[t[1]], c = p[t[2]];
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

// An L-shaped footprint (area 7 x 5 minus 3 x 2 = 29 m^2), clockwise to test orientation handling.
Polygon2 LShape() { return {{0, 0}, {0, 5}, {4, 5}, {4, 3}, {7, 3}, {7, 0}}; }

TEST(Builders, TriangulationCoversTheLShapeCounterClockwise) {
  const Polygon2 l = LShape();
  for (const Polygon2& p : {l, Polygon2(l.rbegin(), l.rend())}) {
    const std::vector<Eigen::Vector3i> tris = TriangulatePolygon(p);
    ASSERT_EQ(tris.size(), p.size() - 2);
    double area = 0;
    for (const Eigen::Vector3i& t : tris) {
      EXPECT_GT(TriangleArea2(p, t), 0);
      area += 0.5 * TriangleArea2(p, t);
    }
    EXPECT_NEAR(area, 29.0, 1e-11);
    EXPECT_NEAR(std::abs(SignedArea2(p)) * 0.5, 29.0, 1e-12);
  }
}

TEST(Builders, ExtrusionIsAClosedPrismOfAreaTimesHeight) {
  const TriangleMesh prism = ExtrudePolygon(LShape(), -0.2, 2.8);
  EXPECT_TRUE(CheckClosed(prism).closed) << CheckClosed(prism).description;
  EXPECT_NEAR(SignedVolume(prism), 29.0 * 3.0, 1e-9);
}

TEST(Builders, PolygonProblemsAreNamed) {
  EXPECT_EQ(PolygonProblem(LShape()), "");
  EXPECT_NE(PolygonProblem({{0, 0}, {1, 0}}).find("at least 3"), std::string::npos);
  EXPECT_NE(PolygonProblem({{0, 0}, {2, 2}, {2, 0}, {0, 2}}).find("cross"), std::string::npos);
  EXPECT_NE(PolygonProblem({{0, 0}, {1, 0}, {1, 0.0001}, {0, 1}}).find("shorter than 1 mm"),
            std::string::npos);
}

// A 7 x 5 m room, walls 0.15 m, 3 m high, slabs 0.2 m, a door (0.9 x 2.1) on wall 0 and a window
// (1.2 x 1.2, sill 0.9) on wall 1: every part closed; volumes in closed form.
TEST(Builders, RoomVolumesMatchTheClosedForm) {
  RoomSpec room;
  room.footprint = {{-3.5, -2.5}, {3.5, -2.5}, {3.5, 2.5}, {-3.5, 2.5}};
  room.height = 3.0;
  room.thickness = 0.15;
  room.openings = {{0, 0.6, 0.9, 0, 2.1}, {1, 1.5, 1.2, 0.9, 1.2}};
  int bad = 0;
  ASSERT_EQ(RoomProblem(room, &bad), "");
  const std::vector<BuiltPart> parts = BuildRoom(room);
  std::map<std::string, double> volume;
  for (const BuiltPart& p : parts) {
    const TriangleMesh welded = WeldVertices(p.mesh);
    // A wall with gaps is several closed blocks; each block alone is closed, so the whole is.
    EXPECT_TRUE(CheckClosed(p.mesh).closed) << p.name << ": " << CheckClosed(p.mesh).description;
    volume[p.name] = SignedVolume(p.mesh);
    (void)welded;
  }
  const double t = 0.15, outer = (7 + 2 * t) * (5 + 2 * t);
  double walls = 0;
  for (int w = 0; w < 4; ++w) walls += volume["wall" + std::to_string(w)];
  EXPECT_NEAR(walls, (outer - 35.0) * 3.0 - t * (0.9 * 2.1 + 1.2 * 1.2), 1e-9);
  EXPECT_NEAR(volume["floor"], outer * 0.2, 1e-9);
  EXPECT_NEAR(volume["ceiling"], outer * 0.2, 1e-9);
  // The door's gap: nothing of wall 0 between x = -2.9 and -2.0 below 2.1 m; wall above it.
  for (const BuiltPart& p : parts) {
    if (p.name != "wall0") continue;
    for (const Vec3& v : p.mesh.vertices)
      EXPECT_FALSE(v.x() > -2.9 + 1e-9 && v.x() < -2.0 - 1e-9 && v.z() < 2.1 - 1e-9)
          << v.transpose();
  }
}

TEST(Builders, RoomProblemsNameTheOpening) {
  RoomSpec room;
  room.footprint = LShape();
  int bad = -1;
  EXPECT_EQ(RoomProblem(room, &bad), "");  // an L (a reflex corner) is fine
  room.openings = {{0, 1.0, 0.9, 0, 2.1}, {0, 1.5, 0.9, 0, 2.1}};
  EXPECT_NE(RoomProblem(room, &bad).find("overlaps opening 0"), std::string::npos);
  EXPECT_EQ(bad, 1);
  room.openings = {{6, 1.0, 0.9, 0, 2.1}};
  EXPECT_NE(RoomProblem(room, &bad).find("no wall 6"), std::string::npos);
  room.openings = {{0, 4.5, 0.9, 0, 2.1}};  // wall 0 is 5 m long
  EXPECT_NE(RoomProblem(room, &bad).find("not within"), std::string::npos);
  room.openings = {{0, 1.0, 0.9, 1.0, 2.1}};
  EXPECT_NE(RoomProblem(room, &bad).find("above the room's height"), std::string::npos);
  room.openings = {};
  room.footprint = {{0, 0}, {10, 0}, {0, 0.5}};  // a corner of 2.9 degrees
  EXPECT_NE(RoomProblem(room, &bad).find("sharper than 10 degrees"), std::string::npos);
}

Aabb PartsBounds(const std::vector<BuiltPart>& parts, const std::string& only = "") {
  Aabb b;
  for (const BuiltPart& p : parts)
    if (only.empty() || p.name == only) b.Extend(p.mesh.Bounds());
  return b;
}

TEST(Builders, PeopleHaveTheirHeightAndStandOnTheFloor) {
  for (double h : {0.9, 1.6, 1.75, 2.1}) {
    for (const std::string& pose : PersonPoses()) {
      PersonSpec spec;
      spec.height = h;
      spec.pose = pose;
      const std::vector<BuiltPart> parts = BuildPerson(spec);
      ASSERT_EQ(parts.size(), 16u);
      for (const BuiltPart& p : parts) {
        EXPECT_TRUE(CheckClosed(p.mesh).closed) << pose << " " << p.name;
        EXPECT_GT(p.radius, 0);
      }
      const Aabb b = PartsBounds(parts);
      if (pose == "sitting") {
        // Sitting on a seat at knee height: the thighs' underside there, the head about 0.5 h
        // above the seat, feet on the floor.
        EXPECT_NEAR(PartsBounds(parts, "thigh_l").min.z(), 0.285 * h, 0.01 * h);
        EXPECT_NEAR(b.min.z(), 0, 0.02 * h) << pose;
        EXPECT_GT(b.max.z(), 0.7 * h);
        EXPECT_LT(b.max.z(), 0.8 * h);
      } else {
        EXPECT_NEAR(b.min.z(), 0, 1e-12) << pose;
        EXPECT_NEAR(b.max.z(), h, (pose == "walking" ? 0.05 : 0.005) * h) << pose;
      }
      // Left is +y; the feet point along +x.
      EXPECT_GT(PartsBounds(parts, "hand_l").center().y(), 0.1 * h);
      EXPECT_LT(PartsBounds(parts, "hand_r").center().y(), -0.1 * h);
      const Aabb foot = PartsBounds(parts, "foot_l");
      EXPECT_GT(foot.max.x() - foot.min.x(), 0.13 * h);
    }
  }
}

TEST(Builders, WalkTimesAreLengthOverSpeedPlusTurns) {
  WalkSpec walk;
  walk.path = {{0, 0}, {3, 0}, {3, 4}};
  walk.speed = 1.5;
  walk.turn_s = 0.5;
  const Vec3 anchor(1, 1, 0);
  const auto frames = WalkKeyframes(walk, anchor, 90.0);  // placed facing +y
  ASSERT_EQ(frames.size(), 4u);                           // start, leg, turn, leg
  EXPECT_DOUBLE_EQ(frames[1].first, 2.0);
  EXPECT_DOUBLE_EQ(frames[2].first, 2.5);
  EXPECT_DOUBLE_EQ(frames[3].first, 2.5 + 4 / 1.5);
  EXPECT_NEAR(frames[0].second.yaw_deg, -90, 1e-12);  // faces +x on the first leg
  EXPECT_NEAR(frames[3].second.yaw_deg, 0, 1e-12);    // then +y: turned back
  EXPECT_NEAR((frames[3].second.move - Vec3(2, 3, 0)).norm(), 0, 1e-12);
  // A closed walk returns; yaw never jumps by more than half a turn between frames.
  walk.closed = true;
  const auto loop = WalkKeyframes(walk, anchor, 0.0);
  EXPECT_NEAR((loop.back().second.move - Vec3(-1, -1, 0)).norm(), 0, 1e-12);
  for (std::size_t i = 1; i < loop.size(); ++i)
    EXPECT_LE(std::abs(loop[i].second.yaw_deg - loop[i - 1].second.yaw_deg), 180 + 1e-9);
}

TEST(Builders, WanderKeepsClearOfSolidsAndOtherWalkers) {
  // A 6 x 4 m floor with a 1 x 1 m block in the middle and a second walker.
  Footprint2 block;
  const Vec2 a(-0.5, -0.5), b(0.5, -0.5), c(0.5, 0.5), d(-0.5, 0.5);
  block.triangles = {{a, b, c}, {a, c, d}};
  WanderSpec spec;
  spec.region.Extend(Vec3(-3, -2, 0));
  spec.region.Extend(Vec3(3, 2, 0));
  spec.duration_s = 60;
  spec.seed = 7;
  const Vec3 start_a(-2, -1, 0), start_b(2, 1, 0);
  const auto first = WanderKeyframes(spec, start_a, 0, block, {});
  spec.seed = 8;
  const OtherWalker other{start_a, first};
  const auto second = WanderKeyframes(spec, start_b, 0, block, {other});
  EXPECT_EQ(WanderKeyframes(spec, start_b, 0, block, {other}).size(), second.size());  // seeded
  const OtherWalker self{start_b, second};
  int legs = 0;
  for (std::size_t i = 1; i < second.size(); ++i)
    legs += (second[i].second.move - second[i - 1].second.move).norm() > 0.1;
  EXPECT_GE(legs, 8);
  EXPECT_GE(second.back().first, 60.0);
  double closest_block = 1e9, closest_other = 1e9;
  for (double t = 0; t <= 60; t += 0.01) {
    const Vec2 p = self.At(t), q = other.At(t);
    closest_block = std::min(closest_block, block.Distance(p));
    closest_other = std::min(closest_other, (p - q).norm());
    EXPECT_TRUE(p.x() >= -3 - 1e-9 && p.x() <= 3 + 1e-9 && p.y() >= -2 - 1e-9 && p.y() <= 2 + 1e-9)
        << "t = " << t;
  }
  // Checked every 0.05 s at <= 1 m/s per walker: between checks the gap closes by at most 0.1 m.
  EXPECT_GE(closest_block, spec.radius - 0.05);
  EXPECT_GE(closest_other, 2 * spec.radius - 0.1);
  EXPECT_THROW(WanderKeyframes(spec, Vec3(0, 0, 0), 0, block, {}), std::invalid_argument);
}

std::string LabText(const std::string& room_extra, const std::string& motions,
                    const std::string& targets = R"("targets": {"points": 500})") {
  return R"({"objects": [
    {"name": "lab", "room": {"footprint": [[-3.5, -2.5], [3.5, -2.5], [3.5, 2.5], [-3.5, 2.5]],
      "height": 3)" +
         room_extra + R"(}},
    {"name": "alice", "person": {"height": 1.7}, "position": [-1, 0, 0], "rotation_deg": [0, 0, 90]},
    {"name": "bob", "person": {"pose": "walking"}, "position": [1, 1, 0]}],
  "motions": {)" +
         motions + R"(},
  "rigs": [{"name": "r", "cameras": [{"id": "c", "position": [3, 2, 2.5], "look_at": [0, 0, 1], "resolution": [1280, 720], "hfov_deg": 60}]}],
  "study": {"region": {"box": {"min": [-3, -2, 0.05], "max": [3, 2, 2]}}, )" +
         targets + R"(, "time": {"samples": 4}}})";
}

TEST(Builders, RoomsAndPeopleLoadAsObjectsWithTargetsAndWalks) {
  const Scene scene = ParseScene(LabText(R"(, "openings": [{"wall": 0, "offset": 1}],
                "furniture": [{"type": "desk", "at": [-2.5, 2]}, {"type": "desk", "at": [0, 2]},
                              {"name": "plinth", "size": [1, 1, 0.4], "at": [2, -1.5]}])",
                                         R"("alice": {"walk": {"path": [[-1, 0], [1, -1]]}},
                 "bob": {"wander": {"region": {"min": [-2, -1], "max": [2, 1]}, "seed": 3,
                                    "duration_s": 20}})"),
                                 "lab.json");
  std::set<std::string> names;
  for (const SceneObject& o : scene.objects) names.insert(o.name);
  for (const char* n : {"lab/wall0", "lab/wall3", "lab/floor", "lab/ceiling", "lab/desk",
                        "lab/desk2", "lab/plinth", "alice/head", "bob/foot_r"})
    EXPECT_TRUE(names.count(n)) << n;
  ASSERT_EQ(scene.people.size(), 2u);
  EXPECT_NEAR(scene.people[0].facing_deg, 90, 1e-9);
  ASSERT_TRUE(scene.study.targets);
  EXPECT_EQ(scene.study.targets->names, (std::vector<std::string>{"alice", "bob"}));
  ASSERT_EQ(scene.motions.size(), 2u);
  // Alice faces +y as placed; her walk heads to (1, -1): yaw = heading - 90.
  const double heading = std::atan2(-1.0, 2.0) * 180 / M_PI;
  EXPECT_NEAR(scene.motions[0].keyframes.front().second.yaw_deg, heading - 90, 1e-9);
  EXPECT_EQ(scene.TimeSamples().size(), 4u);
  // Every target point on a person is on the body's surface: inside no other part.
  const TargetSurface surface = FindTargetSurface(scene, "bob");
  const SurfacePoints points = SampleTargetPoints(surface, 500, 1);
  ASSERT_EQ(points.points.size(), 500u);
  int inside = 0;
  for (std::size_t i = 0; i < points.points.size(); ++i)
    for (std::size_t o = 0; o < surface.capsules.size(); ++o) {
      const auto& c = *surface.capsules[o];
      const Vec3 ab = c.b - c.a, p = points.points[i];
      const double t = std::clamp((p - c.a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      inside += (c.a + t * ab - p).norm() < 0.9 * c.radius;
    }
  EXPECT_EQ(inside, 0);
}

std::string LoadError(const std::string& text) {
  try {
    ParseScene(text, "lab.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(loaded)";
}

TEST(Builders, BadRoomsPeopleAndWalksAreOneLineErrors) {
  const std::string none = R"("alice": {"walk": {"path": [[-1, 0], [1, 0]]}})";
  EXPECT_NE(LoadError(LabText(R"(, "openings": [{"wall": 4, "offset": 1}])", none))
                .find("$.objects[0].room.openings[0]: no wall 4"),
            std::string::npos);
  EXPECT_NE(LoadError(LabText(R"(, "furniture": [{"type": "dsek", "at": [0, 0]}])", none))
                .find("did you mean 'desk'"),
            std::string::npos);
  EXPECT_NE(LoadError(LabText("", R"("alice": {"walk": {"path": [[-1, 0]]}})"))
                .find("$.motions.alice.walk.path: a walk needs at least 2 way points"),
            std::string::npos);
  // Bob starts inside the desk.
  EXPECT_NE(LoadError(LabText(R"(, "furniture": [{"type": "desk", "at": [1, 1]}])",
                              R"("bob": {"wander": {"region": {"min": [-2, -1], "max": [2, 1]}}})"))
                .find("$.motions.bob.wander: the walker's start"),
            std::string::npos);
  EXPECT_NE(LoadError(LabText("", none, R"("targets": {"points": 500, "objects": ["carol"]})"))
                .find("no object or group named 'carol'"),
            std::string::npos);
}

}  // namespace
}  // namespace pandora
