// Calibration feasibility (analysis/rig/calibration.h): wand counts worked out by hand, the graph
// of a hand-made matrix, a camera that looks away found uncalibratable, determinism for a seed,
// each board rule flipping an observation where the geometry says it must, and bad scene-file
// input.
#include "analysis/rig/calibration.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "tests/expect_input_error.h"
#include "tests/fixtures.h"

namespace pandora {
namespace {

using Matrix = std::vector<std::vector<std::int64_t>>;

// A quad (two triangles) at y = `y` spanning x and z in [-half, half].
TriangleMesh WallAtY(double y, double half) {
  TriangleMesh wall;
  wall.vertices = {Vec3(-half, y, -half), Vec3(half, y, -half), Vec3(half, y, half),
                   Vec3(-half, y, half)};
  wall.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  return wall;
}

CalibrationPose At(const Vec3& p) {
  CalibrationPose pose;
  pose.position = p;
  return pose;
}

TEST(Calibration, WandCountsWorkedOutByHand) {
  // Cameras 3 m from the origin, 60 x 46.8 degree pinholes (640 x 480): A on -x, B on +x, C on -y
  // looking at the origin; E on +y behind a 2 x 2 m wall at y = 1.5.
  const auto caster = MakeEmbreeRayCaster(WallAtY(1.5, 1.0));
  const std::vector<Camera> cams{testing::TestCamera("A", Vec3(-3, 0, 0), Vec3::Zero()),
                                 testing::TestCamera("B", Vec3(3, 0, 0), Vec3::Zero()),
                                 testing::TestCamera("C", Vec3(0, -3, 0), Vec3::Zero()),
                                 testing::TestCamera("E", Vec3(0, 3, 0), Vec3::Zero())};
  const VisibilityTester tester(cams, *caster, 10.0);
  const std::vector<CalibrationPose> poses{
      At(Vec3(0, 0, 0)),    // A, B, C on their axes; E's line crosses the wall
      At(Vec3(0.5, 0, 0)),  // A, B on axis; C 9.5 deg off axis; E's line crosses the wall at x 0.25
      At(Vec3(0, 2.5,
              0)),  // E only: 39.8 deg off A's and B's axes (> 30), C's line crosses the wall
      At(Vec3(0, -2.5, 0)),  // C only (0.5 m in front of it); A, B 39.8 deg off axis; E walled off
      At(Vec3(-2.2, 0, 1)),  // B only: 51 deg above A's axis, 36 deg off C's and E's
  };
  CalibrationSpec spec;
  spec.target = CalibrationSpec::Target::kWand;
  spec.min_shared = 2;
  const CalibrationResult r = EvaluateCalibration(tester, spec, poses);
  EXPECT_EQ(r.poses, 5);
  EXPECT_EQ(r.observed, (std::vector<std::int64_t>{2, 3, 3, 1}));
  EXPECT_EQ(r.shared, (Matrix{{2, 2, 2, 0}, {2, 3, 2, 0}, {2, 2, 3, 0}, {0, 0, 0, 1}}));
  EXPECT_EQ(r.poses_observed, 5);
  EXPECT_EQ(r.poses_shared, 2);
  // Why the others are missed: A never for occlusion, C once (the third), E three times.
  const auto missed = [&](int c, BoardView v) { return r.missed[c][static_cast<int>(v)]; };
  EXPECT_EQ(missed(0, BoardView::kNotInImage), 3);
  EXPECT_EQ(missed(0, BoardView::kOccluded), 0);
  EXPECT_EQ(missed(2, BoardView::kNotInImage), 1);
  EXPECT_EQ(missed(2, BoardView::kOccluded), 1);
  EXPECT_EQ(missed(3, BoardView::kNotInImage), 1);
  EXPECT_EQ(missed(3, BoardView::kOccluded), 3);
  // Links A-B, A-C, B-C (2 shared poses each); E is alone.
  EXPECT_EQ(r.graph.component, (std::vector<int>{0, 0, 0, 1}));
  EXPECT_EQ(r.graph.components, (std::vector<std::vector<int>>{{0, 1, 2}, {3}}));
  EXPECT_EQ(r.graph.largest, 0);
  EXPECT_EQ(r.graph.uncalibratable, std::vector<int>{3});
  EXPECT_FALSE(r.calibratable);
  // The spanning tree takes A-B and A-C (ties in (a, b) order); B-C would close a cycle.
  ASSERT_EQ(r.graph.weakest_links.size(), 2u);
  EXPECT_EQ(r.graph.weakest_links[0].a, 0);
  EXPECT_EQ(r.graph.weakest_links[0].b, 1);
  EXPECT_EQ(r.graph.weakest_links[1].a, 0);
  EXPECT_EQ(r.graph.weakest_links[1].b, 2);
  EXPECT_EQ(r.graph.weakest_links[1].shared, 2);
}

TEST(Calibration, GraphOfAHandMadeMatrix) {
  // Camera 4 is disabled: its strong link to 3 must not count.
  const Matrix shared{{100, 50, 30, 10, 0},
                      {50, 80, 40, 0, 0},
                      {30, 40, 90, 25, 0},
                      {10, 0, 25, 30, 60},
                      {0, 0, 0, 60, 70}};
  const std::vector<bool> enabled{true, true, true, true, false};
  CalibrationGraph g = BuildCalibrationGraph(shared, enabled, 20);
  // Edges >= 20: 0-1 50, 1-2 40, 0-2 30, 2-3 25. Maximum spanning tree: 0-1, 1-2, 2-3.
  EXPECT_EQ(g.component, (std::vector<int>{0, 0, 0, 0, -1}));
  EXPECT_TRUE(g.uncalibratable.empty());
  ASSERT_EQ(g.weakest_links.size(), 3u);
  EXPECT_EQ(g.weakest_links[0].a, 2);
  EXPECT_EQ(g.weakest_links[0].b, 3);
  EXPECT_EQ(g.weakest_links[0].shared, 25);
  EXPECT_EQ(g.weakest_links[1].shared, 40);
  EXPECT_EQ(g.weakest_links[2].shared, 50);
  // At 26 the 2-3 link breaks: camera 3 is alone and uncalibratable.
  g = BuildCalibrationGraph(shared, enabled, 26);
  EXPECT_EQ(g.components, (std::vector<std::vector<int>>{{0, 1, 2}, {3}}));
  EXPECT_EQ(g.uncalibratable, std::vector<int>{3});
  // At 31 only 0-1 and 1-2 remain, and camera 3 observes fewer than 31 poses.
  g = BuildCalibrationGraph(shared, enabled, 31);
  EXPECT_EQ(g.uncalibratable, std::vector<int>{3});
  ASSERT_EQ(g.weakest_links.size(), 2u);
  EXPECT_EQ(g.weakest_links[0].shared, 40);
}

// The box room (4 x 4 x 2.5 m, tests/fixtures.h) with four cameras on a ring 1.8 m from the
// region's centre, 1.5 m above it, and a fifth camera by the east wall looking at it.
Scene RoomWithAwayCamera() {
  Scene scene = testing::BoxRoom();
  Rig rig = testing::RingRig(4, 1.8, 1.5, Vec3(0, 0, 0.5));
  rig.cameras.push_back(testing::TestCamera("away", Vec3(1.5, 0, 1), Vec3(2, 0, 1)));
  scene.rigs.push_back(rig);
  return scene;
}

TEST(Calibration, CameraLookingAwayIsUncalibratable) {
  const Scene scene = RoomWithAwayCamera();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  CalibrationSpec spec;
  spec.target = CalibrationSpec::Target::kWand;
  spec.samples = 400;
  const CalibrationResult r = SimulateCalibration(scene, scene.rigs[0], *caster, spec);
  EXPECT_EQ(r.poses, 400);
  // The ring sees the whole (empty) region: every pose, by every ring camera.
  for (int c = 0; c < 4; ++c) EXPECT_EQ(r.observed[c], 400) << r.camera_ids[c];
  EXPECT_EQ(r.observed[4], 0);
  EXPECT_EQ(r.graph.components, (std::vector<std::vector<int>>{{0, 1, 2, 3}, {4}}));
  EXPECT_EQ(r.graph.largest, 0);
  EXPECT_EQ(r.graph.uncalibratable, std::vector<int>{4});
  EXPECT_FALSE(r.calibratable);
  EXPECT_EQ(r.graph.weakest_links.size(), 3u);

  // Disabled, it leaves the graph: the rest is calibratable.
  Rig without = scene.rigs[0];
  without.cameras[4].enabled = false;
  const CalibrationResult r2 = SimulateCalibration(scene, without, *caster, spec);
  EXPECT_EQ(r2.graph.component[4], -1);
  EXPECT_TRUE(r2.graph.uncalibratable.empty());
  EXPECT_TRUE(r2.calibratable);
}

TEST(Calibration, SolidsAndRegionBoundPositions) {
  // A solid box filling the region's lower half: every pose lands in the upper half.
  Scene scene = RoomWithAwayCamera();
  scene.objects.push_back(
      testing::TestObject("block", MakeBox(Vec3(1.2, 1.2, 0.5)), Vec3(0, 0, 0.25), true));
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const VisibilityTester tester(scene.rigs[0].cameras, *caster, 5.0);
  CalibrationSpec spec;
  spec.samples = 300;
  const std::vector<CalibrationPose> poses = SampleCalibrationPoses(scene, tester, spec);
  ASSERT_EQ(poses.size(), 300u);
  for (const CalibrationPose& p : poses) {
    EXPECT_TRUE(scene.study.region.box.Contains(p.position));
    EXPECT_GT(p.position.z(), 0.5);
  }
}

TEST(Calibration, DeterministicForASeed) {
  const Scene scene = RoomWithAwayCamera();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  CalibrationSpec spec;
  spec.target = CalibrationSpec::Target::kBoard;
  spec.samples = 300;
  spec.seed = 7;
  const CalibrationResult a = SimulateCalibration(scene, scene.rigs[0], *caster, spec);
  CalibrationResult b;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    b = SimulateCalibration(scene, scene.rigs[0], *caster, spec);
  }
  EXPECT_EQ(a.shared, b.shared);
  EXPECT_EQ(a.missed, b.missed);
  EXPECT_EQ(a.poses_observed, b.poses_observed);
  EXPECT_GT(a.poses_shared, 0);
  // Another seed draws other poses.
  const VisibilityTester tester(scene.rigs[0].cameras, *caster, 5.0);
  const auto p7 = SampleCalibrationPoses(scene, tester, spec);
  spec.seed = 8;
  const auto p8 = SampleCalibrationPoses(scene, tester, spec);
  EXPECT_NE(p7[0].position, p8[0].position);
  spec.seed = 7;
  const auto again = SampleCalibrationPoses(scene, tester, spec);
  for (std::size_t i = 0; i < p7.size(); ++i) {
    EXPECT_EQ(p7[i].position, again[i].position);
    EXPECT_EQ(p7[i].orientation, again[i].orientation);
  }
}

// A board of 7 x 5 squares of 4 cm, centred 2 m in front of a camera at the origin looking along
// +x (60 degree pinhole, 640 x 480), its front normal turned `yaw_deg` from facing the camera
// about the vertical.
CalibrationPose BoardInFront(double yaw_deg, const Vec3& centre = Vec3(2, 0, 0)) {
  const double a = yaw_deg * kPi / 180;
  CalibrationPose pose;
  pose.position = centre;
  const Vec3 n(-std::cos(a), std::sin(a), 0);
  pose.orientation.col(0) = Vec3(std::sin(a), std::cos(a), 0);
  pose.orientation.col(2) = n;
  pose.orientation.col(1) = n.cross(pose.orientation.col(0));
  return pose;
}

TEST(Calibration, BoardTiltAndPixelRules) {
  const auto caster = MakeEmbreeRayCaster(TriangleMesh{});
  const std::vector<Camera> cams{testing::TestCamera("c", Vec3::Zero(), Vec3(1, 0, 0))};
  const VisibilityTester tester(cams, *caster, 5.0);
  const double f = cams[0].model.intrinsics().fx;  // 320 / tan(30 deg)
  CalibrationBoard board;                          // 7 x 5 squares of 0.04 m
  // Facing the camera, the board is parallel to the image plane at depth 2: every square edge
  // projects to exactly f * 0.04 / 2 pixels (11.09).
  const double edge = f * 0.04 / 2;
  double min_edge = 0;
  board.min_px_per_square = edge - 0.01;
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(0), &min_edge), BoardView::kSeen);
  EXPECT_NEAR(min_edge, edge, 1e-9);
  board.min_px_per_square = edge + 0.01;
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(0), &min_edge), BoardView::kTooSmall);
  // Farther away the squares shrink: at depth 3 an edge is f * 0.04 / 3 (7.39) pixels.
  board.min_px_per_square = 8;
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(0, Vec3(2.5, 0, 0))), BoardView::kSeen);
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(0, Vec3(3, 0, 0)), &min_edge),
            BoardView::kTooSmall);
  EXPECT_NEAR(min_edge, f * 0.04 / 3, 0.05);

  // Tilt: turned 50 degrees it is detected under a 60 degree limit, not under 45; turned 70 it is
  // not under 60; turned 180 its back faces the camera.
  board.min_px_per_square = 4;  // 11.09 cos(50 deg) = 7.1 px: the pixel rule stays out of the way
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(50)), BoardView::kSeen);
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(70)), BoardView::kTilted);
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(180)), BoardView::kTilted);
  board.tilt_max_deg = 45;
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(50)), BoardView::kTilted);
  board.tilt_max_deg = 60;

  // Every corner must be in the image: at depth 2 the image reaches 2 tan(30 deg) = 1.155 m off
  // axis, so a 0.28 m board centred 1.0 m off axis fits (its edge at 1.14) and 1.03 m off does not
  // (1.17).
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(0, Vec3(2, 1.0, 0))), BoardView::kSeen);
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(0, Vec3(2, 1.03, 0))), BoardView::kNotInImage);
  EXPECT_EQ(TestBoard(tester, 0, board, BoardInFront(0, Vec3(2, -1.03, 0))),
            BoardView::kNotInImage);

  // A 1 cm post at 1 m, in front of one corner only, hides the board.
  TriangleMesh post = MakeBox(Vec3(0.01, 0.01, 0.01));
  const Vec3 corner = BoardCorners(board, BoardInFront(0)).front();
  for (Vec3& v : post.vertices) v += 0.5 * corner;
  const auto post_caster = MakeEmbreeRayCaster(post);
  const VisibilityTester blocked(cams, *post_caster, 5.0);
  EXPECT_EQ(TestBoard(blocked, 0, board, BoardInFront(0)), BoardView::kOccluded);
  EXPECT_EQ(TestBoard(blocked, 0, board, BoardInFront(0, Vec3(2, 0.2, 0))), BoardView::kSeen);

  // A wand is a point: seen regardless of any orientation.
  CalibrationSpec wand;
  EXPECT_TRUE(ObservesPose(tester, 0, wand, BoardInFront(180)));
}

nlohmann::json SceneWithCalibration(const nlohmann::json& calibration) {
  nlohmann::json scene = nlohmann::json::parse(R"({
    "rigs": [{"name": "main", "cameras": [
      {"id": "c0", "position": [0, 0, 1], "look_at": [1, 0, 1], "resolution": [1000, 800], "hfov_deg": 90}
    ]}],
    "study": {"region": {"box": {"min": [-1, -1, 0], "max": [1, 1, 2]}}}
  })");
  scene["study"]["calibration"] = calibration;
  return scene;
}

std::string PathOfError(const nlohmann::json& calibration) {
  const InputError e =
      testing::ErrorOf([&] { ParseScene(SceneWithCalibration(calibration).dump(), "s.json"); });
  EXPECT_EQ(e.file(), "s.json");
  return e.json_path();
}

TEST(Calibration, SceneFileSectionAndItsErrors) {
  // Defaults, and the file's units applied to the square size.
  Scene s = ParseScene(SceneWithCalibration({{"target", "board"}}).dump(), "s.json");
  ASSERT_TRUE(s.study.calibration);
  EXPECT_EQ(s.study.calibration->target, CalibrationSpec::Target::kBoard);
  EXPECT_EQ(s.study.calibration->samples, 2000);
  EXPECT_EQ(s.study.calibration->min_shared, 20);
  EXPECT_EQ(s.study.calibration->board.squares_x, 7);
  EXPECT_EQ(s.study.calibration->board.squares_y, 5);
  EXPECT_DOUBLE_EQ(s.study.calibration->board.square_m, 0.04);
  nlohmann::json cm = SceneWithCalibration({{"target", "board"},
                                            {"samples", 50},
                                            {"seed", 3},
                                            {"board", {{"squares", {9, 6}}, {"square_m", 5}}}});
  cm["units"] = "cm";
  s = ParseScene(cm.dump(), "s.json");
  EXPECT_EQ(s.study.calibration->board.squares_x, 9);
  EXPECT_DOUBLE_EQ(s.study.calibration->board.square_m, 0.05);
  EXPECT_EQ(s.study.calibration->seed, 3u);
  EXPECT_FALSE(ParseScene(SceneWithCalibration({{"target", "wand"}}).dump(), "s.json")
                   .study.calibration->target == CalibrationSpec::Target::kBoard);

  EXPECT_EQ(PathOfError(nlohmann::json::object()), "$.study.calibration");
  EXPECT_EQ(PathOfError({{"target", "stick"}}), "$.study.calibration.target");
  EXPECT_EQ(PathOfError({{"target", "wand"}, {"sample", 10}}), "$.study.calibration.sample");
  EXPECT_EQ(PathOfError({{"target", "wand"}, {"samples", 0}}), "$.study.calibration.samples");
  EXPECT_EQ(PathOfError({{"target", "wand"}, {"samples", 10}, {"min_shared", 11}}),
            "$.study.calibration.min_shared");
  EXPECT_EQ(PathOfError({{"target", "wand"}, {"board", {{"squares", {7, 5}}}}}),
            "$.study.calibration.board");
  EXPECT_EQ(PathOfError({{"target", "board"}, {"orientation", "random"}}),
            "$.study.calibration.orientation");
  EXPECT_EQ(PathOfError({{"target", "board"}, {"board", {{"squares", {7}}}}}),
            "$.study.calibration.board.squares");
  EXPECT_EQ(PathOfError({{"target", "board"}, {"board", {{"squares", {7, 1}}}}}),
            "$.study.calibration.board.squares[1]");
  EXPECT_EQ(PathOfError({{"target", "board"}, {"board", {{"square_m", -1}}}}),
            "$.study.calibration.board.square_m");
  EXPECT_EQ(PathOfError({{"target", "board"}, {"board", {{"tilt_max_deg", 90}}}}),
            "$.study.calibration.board.tilt_max_deg");
  EXPECT_EQ(PathOfError({{"target", "board"}, {"board", {{"min_px_per_square", "8"}}}}),
            "$.study.calibration.board.min_px_per_square");
  EXPECT_EQ(PathOfError({{"target", "board"}, {"board", {{"squares", {7, 5}}, {"size", 1}}}}),
            "$.study.calibration.board.size");
}

TEST(Calibration, JsonHoldsTheCountsAndGraphByCameraId) {
  const Scene scene = RoomWithAwayCamera();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  CalibrationSpec spec;
  spec.samples = 100;
  const CalibrationResult r = SimulateCalibration(scene, scene.rigs[0], *caster, spec);
  const nlohmann::json j = r;
  EXPECT_EQ(j.at("target"), "wand");
  EXPECT_EQ(j.at("poses"), 100);
  EXPECT_EQ(j.at("cameras").size(), 5u);
  EXPECT_EQ(j.at("shared").at(0).at(0), j.at("per_camera").at(0).at("observed"));
  EXPECT_EQ(j.at("uncalibratable"), nlohmann::json::array({"away"}));
  EXPECT_EQ(j.at("components").at(1), nlohmann::json::array({"away"}));
  EXPECT_EQ(j.at("calibratable"), false);
  EXPECT_FALSE(j.contains("board"));
  EXPECT_EQ(j.at("per_camera").at(4).at("missed").at("not_in_image"), 100);
  EXPECT_FALSE(j.at("per_camera").at(4).at("missed").contains("tilted"));
  const std::string text = FormatCalibration(r);
  EXPECT_NE(text.find("uncalibratable: away"), std::string::npos) << text;
}

}  // namespace
}  // namespace pandora
