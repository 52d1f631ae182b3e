// The viewer without GL: navigation and manipulation geometry against closed forms, the stick
// mapping, scripts refused with file and JSON path, and a whole scripted session (move a camera,
// the coverage follows, suggest, accept one camera, undo, save, autosave) through ViewerModel with
// the CPU renderer as front end.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "app/session/autosave.h"
#include "render/isosurface.h"
#include "tests/fixtures.h"
#include "viewer/core/manipulate.h"
#include "viewer/core/model.h"
#include "viewer/core/navigation.h"
#include "viewer/core/script.h"
#include "viewer/core/station.h"
#include "volume/fields.h"
#include "volume/summary.h"

namespace pandora::viewer {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Navigation, OrbitKeepsDistanceAndPitchLimits) {
  OrbitView v;
  v.target = Vec3(1, 2, 0.5);
  v.distance = 4;
  v.yaw_deg = 0;
  v.pitch_deg = 0;
  EXPECT_LT((v.Eye() - Vec3(5, 2, 0.5)).norm(), 1e-12);
  v.Orbit(-300, 0);  // 90 degrees: the eye goes to +Y of the target
  EXPECT_LT((v.Eye() - Vec3(1, 6, 0.5)).norm(), 1e-12);
  v.Orbit(0, 1000);  // pitch clamps at 89
  EXPECT_EQ(v.pitch_deg, 89.0);
  EXPECT_NEAR((v.Eye() - v.target).norm(), 4.0, 1e-12);
  // The view basis is orthonormal and right-handed with screen up.
  EXPECT_NEAR(v.Forward().dot(v.Right()), 0, 1e-12);
  EXPECT_NEAR(v.Right().cross(v.Up()).dot(-v.Forward()), 1.0, 1e-12);
}

TEST(Navigation, PanMovesThePointUnderTheCursorWithIt) {
  OrbitView v = OrbitView::FromLookAt(Vec3(0, -5, 2), Vec3(0, 0, 1), 60);
  const RenderView before = v.ToRenderView(800, 600);
  // The target sits at the image centre; after panning 100 px right it sits 100 px right of centre.
  const Vec3 target = v.target;
  v.Pan(100, 0, 800);
  const RenderView after = v.ToRenderView(800, 600);
  const auto pose = LookAt(after.from, after.at, after.up);
  ASSERT_TRUE(pose);
  const Vec3 local = pose->inverse() * target;
  const double f = 0.5 * 800 / std::tan(0.5 * 60 * kRadPerDeg);
  EXPECT_NEAR(local.x() / local.z() * f, 100.0, 1e-9);
  EXPECT_NEAR(local.y() / local.z() * f, 0.0, 1e-9);
  (void)before;
  // Dolly by one step multiplies the distance by 0.85; FromLookAt round-trips the eye.
  const double d = v.distance;
  v.Dolly(1);
  EXPECT_NEAR(v.distance, 0.85 * d, 1e-12);
  const OrbitView w = OrbitView::FromLookAt(Vec3(3, -4, 2), Vec3(0, 0, 2), 40);
  EXPECT_LT((w.Eye() - Vec3(3, -4, 2)).norm(), 1e-12);
}

TEST(Navigation, LookTurnsAboutTheEye) {
  OrbitView v = OrbitView::FromLookAt(Vec3(0, 0, 1), Vec3(3, 0, 1), 50);
  const Vec3 eye = v.Eye();
  v.Look(90, 0);  // turn left: now looking along +Y
  EXPECT_LT((v.Eye() - eye).norm(), 1e-12);
  EXPECT_LT((v.Forward() - Vec3(0, 1, 0)).norm(), 1e-12);
  v.Fly(0, 0, 2);  // forward 2 m
  EXPECT_LT((v.Eye() - (eye + Vec3(0, 2, 0))).norm(), 1e-12);
}

TEST(Manipulate, AxisDragFollowsTheClosestPoint) {
  // A ray from (0, -5, 1) towards (2, 0, 1) meets the x axis line through (0, 0, 1) at x = 2.
  const Ray ray{Vec3(0, -5, 1), Vec3(2, 5, 0).normalized(), 0, 1e30};
  const auto t = AxisParameter(ray, Vec3(0, 0, 1), Vec3(1, 0, 0));
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 2.0, 1e-12);
  // Skew lines: the axis z through (1, 0, 0), the ray along x at height 3, y = 0.
  const auto s =
      AxisParameter(Ray{Vec3(-4, 0, 3), Vec3(1, 0, 0), 0, 1e30}, Vec3(1, 0, 0), Vec3(0, 0, 1));
  ASSERT_TRUE(s);
  EXPECT_NEAR(*s, 3.0, 1e-12);
  EXPECT_FALSE(AxisParameter(Ray{Vec3(0, 1, 0), Vec3(1, 0, 0), 0, 1}, Vec3::Zero(), Vec3(1, 0, 0)));
}

TEST(Manipulate, RingDragSweepsTheAngleAboutTheAxis) {
  // Looking down from (0, 0, 10) at the plane z = 0: from (1, 0, 0) to (0, 1, 0) is +90 about +Z.
  const Vec3 eye(0, 0, 10);
  const Ray a{eye, (Vec3(1, 0, 0) - eye).normalized(), 0, 1e30};
  const Ray b{eye, (Vec3(0, 1, 0) - eye).normalized(), 0, 1e30};
  EXPECT_NEAR(*SweptAngle(a, b, Vec3::Zero(), Vec3::UnitZ()), kPi / 2, 1e-12);
  EXPECT_NEAR(*SweptAngle(b, a, Vec3::Zero(), Vec3::UnitZ()), -kPi / 2, 1e-12);
  EXPECT_NEAR(*SweptAngle(a, b, Vec3::Zero(), -Vec3::UnitZ()), -kPi / 2, 1e-12);
  EXPECT_FALSE(
      SweptAngle(Ray{eye, Vec3(1, 0, 0), 0, 1}, b, Vec3::Zero(), Vec3::UnitZ()));  // parallel
  EXPECT_EQ(Snap(0.26, 0.1), 0.30000000000000004);
  EXPECT_EQ(Snap(-0.24, 0.1), -0.2);
  EXPECT_EQ(Snap(0.26, 0), 0.26);
}

TEST(Manipulate, GroupsMoveRigidlyAndPickingFindsTheNearestBody) {
  Rig rig = testing::RingRig(4, 2.0, 1.0);
  std::vector<Eigen::Isometry3d> poses;
  for (const Camera& c : rig.cameras) poses.push_back(c.world_from_camera);
  const Mat3 R = Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ()).toRotationMatrix();
  const std::vector<Eigen::Isometry3d> moved = MoveRigidly(poses, Vec3::Zero(), Vec3(0, 0, 0.5), R);
  // A quarter turn about the ring's axis takes camera i to camera i + 1's place, lifted 0.5 m.
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT(
        (moved[i].translation() - (poses[(i + 1) % 4].translation() + Vec3(0, 0, 0.5))).norm(),
        1e-12);
    EXPECT_LT((moved[i].linear() - poses[(i + 1) % 4].linear()).norm(), 1e-12);
  }
  // Pairwise distances are kept.
  EXPECT_NEAR((moved[0].translation() - moved[2].translation()).norm(),
              (poses[0].translation() - poses[2].translation()).norm(), 1e-12);
  // A ray from outside through camera 0 (at (2, 0, 1)) and on to camera 2 picks camera 0 first.
  const Ray ray{Vec3(5, 0, 1), Vec3(-1, 0, 0), 0, 1e30};
  EXPECT_EQ(PickCamera(rig, ray, 0.1), 0);
  EXPECT_EQ(PickCamera(rig, Ray{Vec3(5, 0, 1.2), Vec3(-1, 0, 0), 0, 1e30}, 0.1),
            -1);  // passes above
  EXPECT_EQ(PickCamera(rig, Ray{Vec3(5, 0, 1.05), Vec3(-1, 0, 0), 0, 1e30}, 0.1), 0);
}

TEST(Manipulate, FourthPowerStickMapping) {
  EXPECT_EQ(StickCurve(0.05), 0.0);  // dead zone
  EXPECT_EQ(StickCurve(1.0), 1.0);
  EXPECT_EQ(StickCurve(-1.0), -1.0);
  EXPECT_EQ(StickCurve(2.0), 1.0);                         // clamped
  EXPECT_NEAR(StickCurve(0.55), std::pow(0.5, 4), 1e-15);  // halfway through the travel: 1/16
  EXPECT_NEAR(StickCurve(-0.55), -std::pow(0.5, 4), 1e-15);
  // One second full forward at 0.5 m/s moves a level camera 0.5 m along its view; full right stick
  // for a second at 45 deg/s turns it 45 degrees to the right, keeping it level.
  const Camera cam = testing::TestCamera("c", Vec3(0, 0, 1), Vec3(1, 0, 1));
  Eigen::Isometry3d p = cam.world_from_camera;
  GamepadAxes forward;
  forward.left_y = -1;
  for (int i = 0; i < 60; ++i) p = GamepadMove(p, forward, 1.0 / 60, 0.5, 45);
  EXPECT_LT((p.translation() - Vec3(0.5, 0, 1)).norm(), 1e-12);
  GamepadAxes turn;
  turn.right_x = 1;
  for (int i = 0; i < 60; ++i) p = GamepadMove(p, turn, 1.0 / 60, 0.5, 45);
  const Vec3 view = p.linear().col(2);
  EXPECT_NEAR(std::atan2(view.y(), view.x()), -45 * kRadPerDeg, 1e-12);
  EXPECT_NEAR(view.z(), 0, 1e-12);
}

TEST(Station, TheDisplayImageIsTheViewThroughTheDisplay) {
  // A 0.6 x 0.4 m display at (1, 0, 1.2) facing -X (the viewer stands at smaller x), eye off-axis.
  ViewingStation s;
  s.display_center = Vec3(1, 0, 1.2);
  s.display_normal = Vec3(-1, 0, 0);
  s.display_up = Vec3(0, 0, 1);
  s.display_width = 0.6;
  s.display_height = 0.4;
  s.pixels_wide = 300;
  s.pixels_high = 200;
  s.eye = Vec3(0.2, 0.15, 1.3);
  const Camera cam = DisplayCamera(s);
  EXPECT_FALSE(cam.enabled);
  const std::array<Vec3, 4> corners = DisplayCorners(s);
  // Top left as the viewer sees it: the viewer looks along +X with +Z up, so left is +Y.
  EXPECT_LT((corners[0] - Vec3(1, 0.3, 1.4)).norm(), 1e-12);
  // Every corner projects onto the matching image corner; so does any point on the eye's ray
  // through a display point, wherever it lies in the scene.
  const Vec2 expected[4] = {Vec2(-0.5, -0.5), Vec2(299.5, -0.5), Vec2(299.5, 199.5),
                            Vec2(-0.5, 199.5)};
  for (int i = 0; i < 4; ++i) {
    const auto p = cam.model.Project(cam.world_from_camera.inverse() * corners[i]);
    ASSERT_TRUE(p);
    EXPECT_LT((*p - expected[i]).norm(), 1e-9) << i;
  }
  const Vec3 on_display = s.display_center + Vec3(0, -0.1, 0.05);
  const Vec3 beyond = s.eye + 3.7 * (on_display - s.eye);
  const auto a = cam.model.Project(cam.world_from_camera.inverse() * on_display);
  const auto b = cam.model.Project(cam.world_from_camera.inverse() * beyond);
  ASSERT_TRUE(a && b);
  EXPECT_LT((*a - *b).norm(), 1e-9);
  // (0, -0.1, +0.05) from the centre: right of centre by 0.1 m = 50 px, up 0.05 m = 25 px.
  EXPECT_LT((*a - Vec2(149.5 + 50, 99.5 - 25)).norm(), 1e-9);
}

TEST(Station, TrackerRangeCorners) {
  ViewingStation s;
  s.has_tracker = true;
  s.tracker_pose = *LookAt(Vec3(0, 0, 2), Vec3(1, 0, 2), Vec3(0, 0, 1));
  s.tracker_hfov_deg = 90;
  s.tracker_vfov_deg = 60;
  s.tracker_near = 0.5;
  s.tracker_far = 2.0;
  const std::array<Vec3, 8> c = TrackerCorners(s);
  // Far top left: 2 m along +X, left (+Y) by 2 tan 45 = 2, up by 2 tan 30.
  EXPECT_LT((c[4] - Vec3(2, 2, 2 + 2 * std::tan(30 * kRadPerDeg))).norm(), 1e-12);
  EXPECT_LT((c[2] - Vec3(0.5, -0.5, 2 - 0.5 * std::tan(30 * kRadPerDeg))).norm(), 1e-12);
}

void ExpectScriptError(const std::string& text, const std::string& json_path) {
  try {
    ParseScript(text, "s.json");
    ADD_FAILURE() << "expected InputError for " << text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "s.json");
    EXPECT_EQ(e.json_path(), json_path) << e.what();
  }
}

TEST(Script, ParsesEveryActionAndRefusesBadOnesWithTheirPath) {
  const std::vector<Action> s = ParseScript(R"([
    {"select": ["a"]}, {"move": "a", "by": [0.1, 0, 0]}, {"move": ["a"], "to": [1, 2, 3]},
    {"rotate": ["a", "b"], "axis": [0, 0, 1], "deg": 15}, {"aim": "a", "at": [0, 0, 0]},
    {"enable": "a"}, {"disable": ["b"]}, {"hfov": "a", "deg": 40}, {"undo": 1}, {"redo": 1},
    {"slice": "coverage", "axis": "y", "at": 0.5}, {"slice": ""}, {"iso": "sigma_max", "value": 2},
    {"view": "overview"}, {"orbit": [10, -5]}, {"pan": [3, 4]}, {"dolly": -1},
    {"eye": [0, -3, 2], "at": [0, 0, 1], "fov": 45}, {"light": "grid", "grid": 8, "surface": "black"},
    {"wait": "fields"}, {"suggest": ["a"], "objective": "sigma-p90", "points": 50},
    {"accept": "all"}, {"accept": ["a"]}, {"reject": 1}, {"save": "force"},
    {"screenshot": "x.png", "camera": "a"}, {"size": [640, 360]}, {"mouse": "press", "x": 1, "y": 2},
    {"key": "ctrl+z"}, {"scroll": -1}, {"gamepad": "a", "left": [0, -1], "seconds": 0.5}, {"frames": 2}
  ])",
                                            "s.json");
  ASSERT_EQ(s.size(), 32u);
  EXPECT_EQ(s[1].kind, Action::Kind::kMove);
  EXPECT_FALSE(s[1].flag);
  EXPECT_TRUE(s[2].flag);
  EXPECT_EQ(s[3].cameras, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(s[10].text2, "y");
  EXPECT_EQ(s[10].number, 0.5);
  EXPECT_TRUE(s[11].flag);
  EXPECT_TRUE(s[21].cameras.empty());
  EXPECT_TRUE(s[24].flag);
  EXPECT_EQ(s[20].number3, 50);
  EXPECT_EQ(s[30].number, 0.5);

  ExpectScriptError("{", "$");
  ExpectScriptError("{\"undo\": 1}", "$");
  ExpectScriptError("[1]", "$[0]");
  ExpectScriptError("[{\"undo\": 1}, {\"jump\": 1}]", "$[1]");
  ExpectScriptError("[{\"undo\": 1, \"redo\": 1}]", "$[0]");
  ExpectScriptError("[{\"move\": \"a\", \"by\": [0, 0]}]", "$[0].by");
  ExpectScriptError("[{\"move\": \"a\", \"by\": [0, \"x\", 0]}]", "$[0].by[1]");
  ExpectScriptError("[{\"move\": \"a\"}]", "$[0]");
  ExpectScriptError("[{\"move\": [\"a\", \"b\"], \"to\": [0, 0, 0]}]", "$[0].to");
  ExpectScriptError("[{\"move\": [], \"by\": [0, 0, 0]}]", "$[0].move");
  ExpectScriptError("[{\"rotate\": \"a\", \"axis\": [0, 0, 0], \"deg\": 5}]", "$[0].axis");
  ExpectScriptError("[{\"hfov\": \"a\", \"deg\": 0}]", "$[0].deg");
  ExpectScriptError("[{\"slice\": \"coverage\", \"axis\": \"w\"}]", "$[0].axis");
  ExpectScriptError("[{\"wait\": \"forever\"}]", "$[0].wait");
  ExpectScriptError("[{\"size\": [10, 10]}]", "$[0].size");
  ExpectScriptError("[{\"gamepad\": \"a\", \"left\": [2, 0], \"seconds\": 1}]", "$[0].left");
  ExpectScriptError("[{\"undo\": 1, \"bogus\": 2}]", "$[0].bogus");
  ExpectScriptError("[{\"eye\": [1, 1, 1], \"at\": [1, 1, 1]}]", "$[0].at");
  ExpectScriptError("[{\"move\": \"a\", \"by\": [1e300, 0, 0]}]", "$[0].by[0]");
  // Suggest's mounts, keep-out boxes and zoom range.
  const std::vector<Action> m = ParseScript(
      R"([{"suggest": ["a"], "rail": [1, 0, 0], "keep_out": [[0, 0, 0, 1, 1, 1], [2, 2, 2, 3, 3, 3]],
           "clearance": 0.2, "hfov_range": [30, 50]},
          {"suggest": ["a"], "box": [-1, -1, 0, 1, 1, 2]}])",
      "s.json");
  EXPECT_EQ(m[0].mount, "rail");
  ASSERT_EQ(m[0].keep_out.size(), 2u);
  EXPECT_EQ(m[0].keep_out[1].min, Vec3(2, 2, 2));
  EXPECT_EQ(m[0].clearance, 0.2);
  EXPECT_EQ(m[0].max_hfov, 50);
  EXPECT_EQ(m[1].mount, "box");
  EXPECT_EQ(m[1].mount_box.max, Vec3(1, 1, 2));
  ExpectScriptError(R"([{"suggest": ["a"], "rail": [1, 0, 0], "plane": [0, 0, 1]}])", "$[0]");
  ExpectScriptError(R"([{"suggest": ["a"], "rail": [0, 0, 0]}])", "$[0].rail");
  ExpectScriptError(R"([{"suggest": ["a"], "box": [1, 0, 0, 0, 1, 1]}])", "$[0].box");
  ExpectScriptError(
      R"([{"suggest": ["a"], "keep_out": [[0, 0, 0, 1, 1, 1], [0, 0, "x", 1, 1, 1]]}])",
      "$[0].keep_out[1][2]");
  ExpectScriptError(R"([{"suggest": ["a"], "hfov_range": [50, 30]}])", "$[0].hfov_range");
  // `pandora suggest`'s other options, with its defaults.
  const std::vector<Action> o = ParseScript(
      R"([{"suggest": ["a"], "objective": "mix", "weights": [1, 0.5, 0], "snap_move": 0.05, "snap_rotate": 5,
           "outer": 2, "target_surface": ["actor", "table"], "with_region": true},
          {"suggest": "a", "over_time": true}])",
      "s.json");
  EXPECT_EQ(o[0].weights, Vec3(1, 0.5, 0));
  EXPECT_EQ(o[0].snap_move, 0.05);
  EXPECT_EQ(o[0].snap_rotate, 5);
  EXPECT_EQ(o[0].outer_iterations, 2);
  EXPECT_EQ(o[0].target_surfaces, (std::vector<std::string>{"actor", "table"}));
  EXPECT_TRUE(o[0].with_region);
  EXPECT_FALSE(o[0].over_time);
  EXPECT_TRUE(o[1].over_time);
  EXPECT_EQ(o[1].number3, 1500);        // --points
  EXPECT_EQ(o[1].outer_iterations, 4);  // --outer
  EXPECT_TRUE(std::isnan(o[1].weights.x()));
  ExpectScriptError(R"([{"suggest": ["a"], "weights": [0, 0, 0]}])", "$[0].weights");
  ExpectScriptError(R"([{"suggest": ["a"], "over_time": 1}])", "$[0].over_time");
  ExpectScriptError(R"([{"suggest": ["a"], "over_time": true, "target_surface": "x"}])",
                    "$[0].over_time");
  ExpectScriptError(R"([{"suggest": ["a"], "target_surface": [""]}])", "$[0].target_surface[0]");
  ExpectScriptError(R"([{"suggest": ["a"], "outer": 0}])", "$[0].outer");
  // The pointer as a world point or a gizmo handle.
  const std::vector<Action> p = ParseScript(
      R"([{"mouse": "press", "at": [1, 2, 3]}, {"mouse": "move", "gizmo": "ry", "by": -15}, {"mouse": "release", "gizmo": "z"}])",
      "s.json");
  EXPECT_TRUE(p[0].has_a);
  EXPECT_EQ(p[0].a, Vec3(1, 2, 3));
  EXPECT_EQ(p[0].gizmo, -1);
  EXPECT_EQ(p[1].gizmo, 4);
  EXPECT_EQ(p[1].number, -15);
  EXPECT_EQ(p[2].gizmo, 2);
  EXPECT_EQ(p[2].number, 0);
  ExpectScriptError(R"([{"mouse": "press", "x": 1, "y": 1, "at": [0, 0, 0]}])", "$[0]");
  ExpectScriptError(R"([{"mouse": "press"}])", "$[0]");
  ExpectScriptError(R"([{"mouse": "press", "gizmo": "w"}])", "$[0].gizmo");
  ExpectScriptError(R"([{"mouse": "move", "x": 1, "y": 1, "by": 2}])", "$[0].by");
}

TEST(Script, CameraPanelActionsParseAndRefuseBadValuesWithTheirPath) {
  const std::vector<Action> s = ParseScript(R"([
    {"intrinsics": "a", "resolution": [320, 240]},
    {"intrinsics": ["a", "b"], "model": "brown_conrady", "k1": -0.1, "p2": 0.001},
    {"intrinsics": "a", "k4": 0.01},
    {"range": "a", "near": 0.3, "far": 5}, {"range": ["a"], "far": null}, {"range": "a", "near": 1},
    {"color": "a", "rgb": [1, 0.5, 0]}
  ])",
                                            "s.json");
  ASSERT_EQ(s.size(), 7u);
  EXPECT_EQ(s[0].kind, Action::Kind::kIntrinsics);
  EXPECT_EQ(s[0].width, 320);
  EXPECT_EQ(s[0].height, 240);
  EXPECT_TRUE(s[0].lens.empty());
  EXPECT_EQ(s[1].cameras, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(s[1].lens, "brown_conrady");
  EXPECT_EQ(s[1].coefficients[0], -0.1);
  EXPECT_EQ(s[1].coefficients[3], 0.001);
  EXPECT_TRUE(std::isnan(s[1].coefficients[1]));
  EXPECT_EQ(s[1].width, 0);
  EXPECT_EQ(s[2].coefficients[5], 0.01);
  EXPECT_EQ(s[3].kind, Action::Kind::kRange);
  EXPECT_EQ(s[3].near, 0.3);
  EXPECT_EQ(s[3].far, 5);
  EXPECT_TRUE(std::isnan(s[4].near));
  EXPECT_TRUE(std::isinf(s[4].far));
  EXPECT_TRUE(std::isnan(s[5].far));
  EXPECT_EQ(s[6].kind, Action::Kind::kColor);
  EXPECT_EQ(s[6].a, Vec3(1, 0.5, 0));

  ExpectScriptError(R"([{"intrinsics": "a"}])", "$[0]");
  ExpectScriptError(R"([{"intrinsics": [], "k1": 0}])", "$[0].intrinsics");
  ExpectScriptError(R"([{"intrinsics": "a", "resolution": [640]}])", "$[0].resolution");
  ExpectScriptError(R"([{"intrinsics": "a", "resolution": [640.5, 480]}])", "$[0].resolution");
  ExpectScriptError(R"([{"intrinsics": "a", "resolution": [0, 480]}])", "$[0].resolution");
  ExpectScriptError(R"([{"intrinsics": "a", "resolution": [640, "x"]}])", "$[0].resolution[1]");
  ExpectScriptError(R"([{"intrinsics": "a", "model": "tsai"}])", "$[0].model");
  ExpectScriptError(R"([{"intrinsics": "a", "model": "brown_conrady", "k4": 0.1}])", "$[0].k4");
  ExpectScriptError(R"([{"intrinsics": "a", "model": "fisheye", "p1": 0.1}])", "$[0].p1");
  ExpectScriptError(R"([{"intrinsics": "a", "model": "pinhole", "k1": 0.1}])", "$[0].k1");
  ExpectScriptError(R"([{"intrinsics": "a", "k1": "big"}])", "$[0].k1");
  ExpectScriptError(R"([{"intrinsics": "a", "k2": 1e6}])", "$[0].k2");
  ExpectScriptError(R"([{"intrinsics": "a", "k5": 0}])", "$[0].k5");
  ExpectScriptError(R"([{"range": "a"}])", "$[0]");
  ExpectScriptError(R"([{"range": "a", "near": -1}])", "$[0].near");
  ExpectScriptError(R"([{"range": "a", "near": 2, "far": 1}])", "$[0].far");
  ExpectScriptError(R"([{"range": "a", "far": "inf"}])", "$[0].far");
  ExpectScriptError(R"([{"range": "a", "far": 0}])", "$[0].far");
  ExpectScriptError(R"([{"color": "a"}])", "$[0]");
  ExpectScriptError(R"([{"color": "a", "rgb": [1.5, 0, 0]}])", "$[0].rgb[0]");
  ExpectScriptError(R"([{"color": "a", "rgb": "#ff0000"}])", "$[0].rgb");
  ExpectScriptError(R"([{"color": "a", "rgb": [1, 0, 0], "alpha": 1}])", "$[0].alpha");
}

// A copy of the suggest ring scene in a fresh folder (the session saves into it).
fs::path CopyScene(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("viewer_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file("tests/data/suggest_ring.json", dir / "scene.json");
  return dir / "scene.json";
}

// Share of the region seen by all four cameras of the ring.
double CoverageGe4(const ViewerModel& m) {
  const nlohmann::json ge = m.StateJson()["fields"]["coverage_ge"];
  return ge.size() >= 4 ? ge[3].get<double>() : 0.0;
}

TEST(ViewerModel, ScriptedSessionMoveSuggestAcceptUndoSave) {
  const fs::path scene = CopyScene("session");
  const std::string original_text = Read(scene);
  ViewerOptions options;
  options.fields = {"coverage", "cameras", "sigma_max"};
  options.autosave_path = session::AutosavePath(scene.string());
  options.width = 160;
  options.height = 90;
  ViewerModel m(session::Study::Load(scene.string()), options);
  CpuFrontend cpu;
  const std::string c = m.rig().cameras[1].id;
  const Vec3 start = m.rig().cameras[1].center();
  const fs::path dir = scene.parent_path();
  m.Run(ParseScript(R"([{"wait": "fields"}, {"slice": "coverage", "axis": "z", "at": 0.5},
                        {"screenshot": ")" +
                        (dir / "before.png").string() + R"("}])",
                    "s.json"),
        &cpu);
  const double before = CoverageGe4(m);
  EXPECT_GT(before, 0);
  // Turn camera 1 partly away from the region: coverage >= 4 drops, the fields follow in the
  // background.
  m.Run(ParseScript(R"([{"select": [")" + c + R"("]}, {"rotate": [")" + c +
                        R"("], "axis": [0, 0, 1], "deg": 30},
                        {"wait": "fields"}, {"screenshot": ")" +
                        (dir / "turned.png").string() + R"("}])",
                    "s.json"),
        &cpu);
  EXPECT_EQ(m.StateJson()["undo"], "rotate " + c);
  EXPECT_EQ(m.StateJson()["selection"], nlohmann::json::array({c}));
  const double turned = CoverageGe4(m);
  EXPECT_LT(turned, before);
  EXPECT_EQ(m.StateJson()["fields"]["rig_version"], m.session().rig().version());
  // The fields equal a full evaluation of the rig as edited.
  FieldOptions fo;
  fo.fields = options.fields;
  const Fields full = EvaluateFields(m.scene(), m.rig(), m.session().study().caster(), fo);
  m.session().ReadFields([&](const Fields& f, std::int64_t) {
    EXPECT_EQ(f.stats.coverage_histogram, full.stats.coverage_histogram);
  });
  EXPECT_NE(Read(dir / "before.png"), Read(dir / "turned.png"));  // the slice changed
  // The autosave holds the turned camera; the scene file is untouched.
  EXPECT_TRUE(fs::exists(options.autosave_path));
  EXPECT_EQ(Read(scene), original_text);

  // Suggest for the turned camera, accept it: coverage recovers; undo takes it back.
  m.Run(ParseScript(R"([{"suggest": [")" + c +
                        R"("], "objective": "coverage4", "max_move": 0.2, "max_rotate": 45,
                        "points": 300}, {"wait": "suggest"}])",
                    "s.json"),
        &cpu);
  ASSERT_TRUE(m.suggestion);
  EXPECT_TRUE(m.suggestion->improved) << m.suggestion->message;
  m.Run(ParseScript(R"([{"accept": [")" + c + R"("]}, {"wait": "fields"}])", "s.json"), &cpu);
  EXPECT_FALSE(m.suggestion);
  const double accepted = CoverageGe4(m);
  EXPECT_GT(accepted, turned);
  m.Run(ParseScript(R"([{"undo": 1}, {"wait": "fields"}])", "s.json"), &cpu);
  EXPECT_EQ(CoverageGe4(m), turned);
  m.Run(ParseScript(R"([{"redo": 1}, {"wait": "fields"}, {"save": 1}])", "s.json"), &cpu);
  // Saved with a backup; the autosave is gone; the scene file reloads with the accepted pose.
  EXPECT_NE(Read(scene), original_text);
  EXPECT_FALSE(fs::exists(options.autosave_path));
  bool backup = false;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find("scene.json") == 0 && e.path() != scene &&
        e.path().string().find("autosave") == std::string::npos && Read(e.path()) == original_text)
      backup = true;
  EXPECT_TRUE(backup);
  const Scene reloaded = LoadScene(scene.string());
  const Camera& saved = reloaded.rigs[0].cameras[1];
  EXPECT_LT(
      (saved.world_from_camera.matrix() - m.rig().cameras[1].world_from_camera.matrix()).norm(),
      1e-6);
  EXPECT_GT((saved.center() - start).norm() +
                (saved.world_from_camera.linear() - Mat3::Identity()).norm(),
            0);

  // A camera's own view renders too; an output onto the scene file is refused.
  m.Run(ParseScript(R"([{"screenshot": ")" + (dir / "cam.png").string() + R"(", "camera": ")" + c +
                        R"("}])",
                    "s.json"),
        &cpu);
  EXPECT_TRUE(fs::exists(dir / "cam.png"));
  EXPECT_THROW(
      m.Run(ParseScript(R"([{"screenshot": ")" + scene.string() + R"("}])", "s.json"), &cpu),
      InputError);
  EXPECT_EQ(Read(scene), Read(scene));  // still readable
  EXPECT_THROW(m.Run(ParseScript(R"([{"select": ["nope"]}])", "s.json"), &cpu), InputError);
  EXPECT_THROW(m.Run(ParseScript(R"([{"accept": "all"}])", "s.json"), &cpu), InputError);
  // A suggestion that cannot improve (nothing may move) is refused, as `pandora accept` refuses it.
  m.Run(
      ParseScript(R"([{"suggest": [")" + c + R"("], "max_move": 0, "max_rotate": 0, "points": 100},
                        {"wait": "suggest"}])",
                  "s.json"),
      &cpu);
  ASSERT_TRUE(m.suggestion);
  EXPECT_FALSE(m.suggestion->improved);
  const std::int64_t version = m.session().rig().version();
  try {
    m.Run(ParseScript(R"([{"accept": "all"}])", "s.json"), &cpu);
    ADD_FAILURE() << "a suggestion without improvement was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("offers no improvement"), std::string::npos) << e.what();
  }
  EXPECT_EQ(m.session().rig().version(), version);
  EXPECT_THROW(m.Run(ParseScript(R"([{"slice": "resolution"}])", "s.json"), &cpu),
               InputError);  // not live
  EXPECT_THROW(m.Run(ParseScript(R"([{"mouse": "press", "x": 1, "y": 1}])", "s.json"), &cpu),
               InputError);
}

TEST(ViewerModel, ViewingStationsMoveAndTheirDisplayShowsTheScene) {
  ViewerOptions options;
  options.fields = {"coverage"};
  options.width = 160;
  options.height = 90;
  ViewerModel m(session::Study::Load("examples/trauma_room/viewing_station.json"), options);
  ASSERT_EQ(m.stations.count("remote consult"), 1u);
  const Vec3 eye = m.stations.at("remote consult").eye;
  m.Run(ParseScript(R"([{"station": "remote consult", "eye_at": [0.6, -1.3, 1.35]}])", "s.json"),
        nullptr);
  EXPECT_LT((m.stations.at("remote consult").eye - Vec3(0.6, -1.3, 1.35)).norm(), 1e-12);
  EXPECT_EQ(m.stations_version, 1);
  EXPECT_NE(eye, m.stations.at("remote consult").eye);
  // Behind the display (it faces -y), an unknown station: refused, nothing moves.
  EXPECT_THROW(
      m.Run(ParseScript(R"([{"station": "remote consult", "eye_at": [0.56, 0.5, 1.2]}])", "s.json"),
            nullptr),
      InputError);
  EXPECT_THROW(
      m.Run(ParseScript(R"([{"station": "lobby", "eye_at": [0, 0, 1]}])", "s.json"), nullptr),
      InputError);
  EXPECT_EQ(m.stations_version, 1);
  // The display's image is the scene through the display: its centre pixel shows what the eye's
  // ray through the display's centre hits first.
  const ViewingStation& st = m.stations.at("remote consult");
  Rig rig = m.rig();
  rig.cameras.push_back(DisplayCamera(st));
  RenderView view;
  view.camera = int(rig.cameras.size()) - 1;
  view.width = st.pixels_wide / 8;
  view.height = st.pixels_high / 8;
  RenderOptions o;
  const Image image = Render(m.session().study().prepared(), rig, view, o);
  const auto hit = m.session().study().caster().Intersect(
      Ray{st.eye, (st.display_center - st.eye).normalized(), 0.0, 1e30});
  ASSERT_TRUE(hit);
  const double depth = image.depth[std::size_t(view.height / 2) * view.width + view.width / 2];
  EXPECT_NEAR(depth, hit->t,
              0.02 * hit->t);  // the centre pixel is half a pixel off the exact centre
  m.session().WaitFields();
}

TEST(ViewerModel, SaveWritesMovedViewingStationsWithABackup) {
  const fs::path dir = fs::path(::testing::TempDir()) / "viewer_station_save";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file("examples/trauma_room/viewing_station.json", dir / "scene.json");
  const fs::path scene = dir / "scene.json";
  const std::string original = Read(scene);
  const Scene before = LoadScene(scene.string());
  const ViewingStation st0 = before.stations.at("remote consult");
  ViewerOptions options;
  options.fields = {"coverage"};
  options.width = 160;
  options.height = 90;
  ViewerModel m(session::Study::Load(scene.string()), options);
  const Vec3 center = st0.display_center + Vec3(0.25, 0.0, -0.1);
  m.Run(ParseScript(R"([{"station": "remote consult", "eye_at": [0.6, -1.3, 1.35]},
                        {"station": "remote consult", "display_at": [)" +
                        std::to_string(center.x()) + "," + std::to_string(center.y()) + "," +
                        std::to_string(center.z()) + R"(]}, {"save": 1}])",
                    "s.json"),
        nullptr);
  EXPECT_NE(m.status.find("saved 1 viewing station into"), std::string::npos) << m.status;
  // The file reloads with the moved eye and display, the display turned as before; a backup keeps
  // the original; the cameras are untouched.
  const Scene after = LoadScene(scene.string());
  const ViewingStation& st = after.stations.at("remote consult");
  EXPECT_LT((st.eye - Vec3(0.6, -1.3, 1.35)).norm(), 1e-9);
  EXPECT_LT((st.display_center - m.stations.at("remote consult").display_center).norm(), 1e-9);
  EXPECT_LT((st.display_normal - st0.display_normal).norm(), 1e-9);
  EXPECT_LT((st.display_up - st0.display_up).norm(), 1e-9);
  EXPECT_EQ(st.display_width, st0.display_width);
  for (std::size_t c = 0; c < before.rigs[0].cameras.size(); ++c)
    EXPECT_EQ(after.rigs[0].cameras[c].world_from_camera.matrix(),
              before.rigs[0].cameras[c].world_from_camera.matrix());
  bool backup = false;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path() != scene && Read(e.path()) == original) backup = true;
  EXPECT_TRUE(backup);
  // Nothing moved since: a second save writes nothing.
  m.Run(ParseScript(R"([{"save": 1}])", "s.json"), nullptr);
  EXPECT_EQ(m.status, "nothing to save");
  m.session().WaitFields();
}

TEST(ViewerModel, SuggestKeepsTheMountAndTheKeepOutBox) {
  const fs::path scene = CopyScene("mount");
  ViewerOptions options;
  options.fields = {"coverage"};
  ViewerModel m(session::Study::Load(scene.string()), options);
  const std::string c =
      m.rig().cameras[3].id;  // the ring's camera that looks away (suggest_ring.json)
  const Vec3 start = m.rig().cameras[3].center();
  m.Run(ParseScript(R"([{"suggest": [")" + c +
                        R"("], "objective": "coverage4", "max_move": 0.5, "max_rotate": 60,
                         "points": 200, "rail": [1, 0, 0], "keep_out": [[-10, -10, -10, -0.05, 10, 10]]},
                        {"wait": "suggest"}])",
                    "s.json"),
        nullptr);
  ASSERT_TRUE(m.suggestion);
  ASSERT_EQ(m.suggestion->cameras.size(), 1u);
  const Vec3 after = m.suggestion->cameras[0].after.translation();
  // On the rail through the start along x: y and z unchanged; never into the keep-out half-space.
  EXPECT_NEAR(after.y(), start.y(), 1e-9);
  EXPECT_NEAR(after.z(), start.z(), 1e-9);
  EXPECT_GT(after.x(), -0.05);
  m.session().WaitFields();
}

TEST(ViewerModel, GroupEditsAreOneUndoStep) {
  const fs::path scene = CopyScene("group");
  ViewerOptions options;
  options.fields = {"coverage"};
  ViewerModel m(session::Study::Load(scene.string()), options);
  const Rig original = m.rig();
  const std::string a = original.cameras[0].id, b = original.cameras[2].id;
  m.Run(ParseScript(R"([{"move": [")" + a + R"(", ")" + b + R"("], "by": [0, 0, 0.25]},
                        {"hfov": [")" +
                        a + R"("], "deg": 30}, {"disable": [")" + b + R"("]},
                        {"gamepad": ")" +
                        a + R"(", "left": [0, -1], "seconds": 1}])",
                    "s.json"),
        nullptr);
  EXPECT_NEAR(m.rig().cameras[2].center().z() - original.cameras[2].center().z(), 0.25, 1e-12);
  EXPECT_NEAR(HfovFromFocal(m.rig().cameras[0].model.intrinsics().fx,
                            m.rig().cameras[0].model.width(), LensModel::kPinhole) /
                  kRadPerDeg,
              30, 1e-9);
  EXPECT_FALSE(m.rig().cameras[2].enabled);
  // A drag of three steps on one camera is one undo step; a new drag starts a new one.
  m.Run(ParseScript(R"([{"move": ")" + b + R"(", "by": [0.1, 0, 0], "drag": true},
                        {"move": ")" +
                        b + R"(", "by": [0.1, 0, 0], "drag": true},
                        {"move": ")" +
                        b + R"(", "by": [0.1, 0, 0], "drag": true}])",
                    "s.json"),
        nullptr);
  EXPECT_NEAR(m.rig().cameras[2].center().x() - original.cameras[2].center().x(), 0.3, 1e-12);
  ASSERT_TRUE(m.session().rig().Undo());
  EXPECT_NEAR(m.rig().cameras[2].center().x() - original.cameras[2].center().x(), 0.0, 1e-12);
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(m.session().rig().Undo());
  EXPECT_FALSE(m.session().rig().Undo());
  for (std::size_t i = 0; i < original.cameras.size(); ++i)
    EXPECT_TRUE(SameCameraGeometry(m.rig().cameras[i], original.cameras[i])) << i;
  m.session().WaitFields();
}

// The Camera panel's edits: resolution (same field of view), lens model and coefficients, range,
// colour; each one undo step, refused clearly where the lens would fold back or the range is empty;
// saving names what it cannot write.
TEST(ViewerModel, CameraPanelEditsLensRangeColourAsOneUndoStepEach) {
  const fs::path scene = CopyScene("camera_panel");
  const std::string original_text = Read(scene);
  ViewerOptions options;
  options.fields = {"coverage"};
  ViewerModel m(session::Study::Load(scene.string()), options);
  const Rig original = m.rig();
  const std::string a = original.cameras[0].id, b = original.cameras[1].id;
  auto run = [&](const std::string& text) { m.Run(ParseScript(text, "s.json"), nullptr); };

  // Half the resolution: the same rays through the image's edges (and its corners), the pixel
  // centre of the principal point halved about the edge.
  run(R"([{"intrinsics": ")" + a + R"(", "resolution": [320, 240]}])");
  const Camera& half = m.rig().cameras[0];
  const Camera& full = original.cameras[0];
  EXPECT_EQ(half.model.width(), 320);
  EXPECT_EQ(half.model.height(), 240);
  EXPECT_EQ(m.StateJson()["undo"], "lens " + a);
  for (const Vec2& corner : {Vec2(-0.5, -0.5), Vec2(639.5, 479.5), Vec2(319.5, 0)}) {
    const Vec2 scaled((corner.x() + 0.5) * 0.5 - 0.5, (corner.y() + 0.5) * 0.5 - 0.5);
    EXPECT_LT((*half.model.Unproject(scaled) - *full.model.Unproject(corner)).norm(), 1e-12);
  }
  EXPECT_NEAR(HfovFromFocal(half.model.intrinsics().fx, 320, LensModel::kPinhole),
              HfovFromFocal(full.model.intrinsics().fx, 640, LensModel::kPinhole), 1e-12);

  // A Brown-Conrady lens on two cameras at once: one undo step.
  run(R"([{"intrinsics": [")" + a + R"(", ")" + b +
      R"("], "model": "brown_conrady", "k1": -0.1, "p1": 0.001}])");
  for (int c : {0, 1}) {
    const Intrinsics& k = m.rig().cameras[c].model.intrinsics();
    EXPECT_EQ(k.model, LensModel::kBrownConrady);
    EXPECT_EQ(k.k1, -0.1);
    EXPECT_EQ(k.p1, 0.001);
    EXPECT_EQ(k.k2, 0);
  }
  EXPECT_EQ(m.StateJson()["undo"], "lens 2 cameras");
  EXPECT_EQ(m.StateJson()["cameras"][1]["lens"]["model"], "brown_conrady");
  EXPECT_EQ(m.StateJson()["cameras"][1]["lens"]["k1"], -0.1);
  // A coefficient alone changes the lens model the camera has.
  run(R"([{"intrinsics": ")" + b + R"(", "k2": 0.02}])");
  EXPECT_EQ(m.rig().cameras[1].model.intrinsics().k2, 0.02);
  EXPECT_EQ(m.rig().cameras[1].model.intrinsics().k1, -0.1);

  const std::int64_t version = m.session().rig().version();
  const std::string undo = m.StateJson()["undo"];
  auto refused = [&](const std::string& text, const std::string& words) {
    try {
      run(text);
      ADD_FAILURE() << "expected a refusal: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
    EXPECT_EQ(m.session().rig().version(), version) << text;  // nothing applied
    EXPECT_EQ(m.StateJson()["undo"], undo);
  };
  // Barrel distortion so strong that the radial map turns inside the image: refused, nothing
  // changes.
  refused(R"([{"intrinsics": ")" + b + R"(", "k1": -1.5}])", "folds back inside the image");
  refused(R"([{"intrinsics": ")" + b + R"(", "k4": 0.1}])",
          "no coefficient k4");  // a Brown-Conrady lens
  refused(R"([{"intrinsics": ")" + original.cameras[2].id + R"(", "k1": 0.1}])", "pinhole lens");
  refused(R"([{"range": ")" + a + R"(", "near": 100}])", "must be greater than near");
  refused(R"([{"intrinsics": "nope", "k1": 0.1}])", "no camera 'nope'");

  // Fisheye keeps the nominal field of view; a 200 degree fisheye cannot become a pinhole.
  run(R"([{"intrinsics": ")" + b + R"(", "model": "fisheye", "k4": 0.001}])");
  const Intrinsics& f = m.rig().cameras[1].model.intrinsics();
  EXPECT_EQ(f.model, LensModel::kFisheye);
  EXPECT_EQ(f.k4, 0.001);
  EXPECT_NEAR(HfovFromFocal(f.fx, f.width, LensModel::kFisheye), 50 * kRadPerDeg, 1e-12);
  run(R"([{"hfov": ")" + b + R"(", "deg": 200}])");
  EXPECT_THROW(run(R"([{"intrinsics": ")" + b + R"(", "model": "pinhole"}])"), InputError);
  run(R"([{"undo": 1}, {"undo": 1}])");

  // The working range: the fields follow (a short far range sees less of the region).
  m.session().WaitFields();
  const double seen = m.StateJson()["fields"]["coverage_ge"][0];
  run(R"([{"range": [")" + a + R"(", ")" + b + R"(", ")" + original.cameras[2].id + R"(", ")" +
      original.cameras[3].id + R"("], "near": 0.5, "far": 2.5}, {"wait": "fields"}])");
  EXPECT_EQ(m.rig().cameras[0].near, 0.5);
  EXPECT_EQ(m.rig().cameras[3].far, 2.5);
  EXPECT_LT(m.StateJson()["fields"]["coverage_ge"][0].get<double>(), seen);
  run(R"([{"range": ")" + a + R"(", "far": null}])");
  EXPECT_TRUE(std::isinf(m.rig().cameras[0].far));
  EXPECT_EQ(m.rig().cameras[0].near, 0.5);
  EXPECT_TRUE(m.StateJson()["cameras"][0]["range"][1].is_null());

  // Colour: display only, one undo step.
  run(R"([{"color": ")" + a + R"(", "rgb": [1, 0, 0]}])");
  EXPECT_EQ(m.rig().cameras[0].color, Vec3(1, 0, 0));
  EXPECT_EQ(m.StateJson()["undo"], "colour " + a);

  // Saving writes poses and focal lengths only: the refusal names each camera's other changes.
  try {
    run(R"([{"save": 1}])");
    ADD_FAILURE() << "expected the save to be refused";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("not saved: saving writes poses and focal lengths only, not " + a +
                        "'s resolution, lens model, range, colour; "),
              std::string::npos)
        << what;
    EXPECT_NE(what.find(b + "'s lens model, range; "), std::string::npos) << what;
  }
  EXPECT_EQ(Read(scene), original_text);

  // Everything undoes, step by step, to the rig as loaded; then nothing is left to save.
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(m.session().rig().Undo()) << i;
  EXPECT_FALSE(m.session().rig().Undo());
  for (std::size_t i = 0; i < original.cameras.size(); ++i) {
    EXPECT_TRUE(SameCameraGeometry(m.rig().cameras[i], original.cameras[i])) << i;
    EXPECT_EQ(m.rig().cameras[i].color, original.cameras[i].color);
  }
  run(R"([{"save": 1}])");
  EXPECT_EQ(m.status, "nothing to save");
  m.session().WaitFields();
}

// The isosurface the window draws: the iso action picks a live field and value ("" hides it and
// keeps the value); FieldIsosurface gives the renderer's mesh of the live fields, inside the
// lattice.
TEST(ViewerModel, IsoActionAndTheLiveFieldsIsosurface) {
  const fs::path scene = CopyScene("iso");
  ViewerOptions options;
  options.fields = {"coverage"};
  ViewerModel m(session::Study::Load(scene.string()), options);
  m.Run(ParseScript(R"([{"wait": "fields"}, {"iso": "coverage", "value": 2.5}])", "s.json"),
        nullptr);
  EXPECT_EQ(m.display.overlays.iso_field, "coverage");
  EXPECT_EQ(m.display.overlays.iso_value, 2.5);
  m.session().ReadFields([&](const Fields& f, std::int64_t) {
    const TriangleMesh mesh = FieldIsosurface(f, "coverage", 2.5);
    ASSERT_GT(mesh.triangles.size(), 0u);
    const Vec3 lo = f.lattice.origin,
               hi = f.lattice.Center(f.lattice.dims.x() - 1, f.lattice.dims.y() - 1,
                                     f.lattice.dims.z() - 1);
    for (const Vec3& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(v[k], lo[k] - f.lattice.voxel_size);
        EXPECT_LE(v[k], hi[k] + f.lattice.voxel_size);
      }
    // A value no voxel passes gives no surface; a field that is not live is refused.
    EXPECT_EQ(FieldIsosurface(f, "coverage", 99.5).triangles.size(), 0u);
    EXPECT_THROW(FieldIsosurface(f, "sigma_max", 1.0), InputError);
  });
  m.Run(ParseScript(R"([{"iso": ""}])", "s.json"), nullptr);
  EXPECT_TRUE(m.display.overlays.iso_field.empty());
  EXPECT_EQ(m.display.overlays.iso_value, 2.5);
  EXPECT_THROW(m.Run(ParseScript(R"([{"iso": "sigma_max", "value": 1}])", "s.json"), nullptr),
               InputError);
}

// The Compare panel's numbers: the edited rig (its live fields) against the rig as saved, with the
// saved rig evaluated once (a full evaluation's numbers) and nothing evaluated while nothing
// differs.
TEST(ViewerModel, CompareTheEditedRigWithTheSavedOne) {
  const std::vector<Action> s =
      ParseScript(R"([{"compare": "saved"}, {"compare": ["saved", "grid4x2"]}])", "s.json");
  EXPECT_EQ(s[0].kind, Action::Kind::kCompare);
  EXPECT_EQ(s[1].cameras, (std::vector<std::string>{"saved", "grid4x2"}));
  ExpectScriptError(R"([{"compare": []}])", "$[0].compare");
  ExpectScriptError(R"([{"compare": 1}])", "$[0].compare");
  ExpectScriptError(R"([{"compare": ["saved", "saved"]}])", "$[0].compare[1]");
  ExpectScriptError(R"([{"compare": "saved", "rig": "x"}])", "$[0].rig");

  const fs::path scene = CopyScene("compare");
  ViewerOptions options;
  options.fields = {"coverage", "resolution", "sigma_max"};
  ViewerModel m(session::Study::Load(scene.string()), options);
  auto run = [&](const std::string& text) { m.Run(ParseScript(text, "s.json"), nullptr); };
  auto value = [&](const std::string& key, std::size_t rig) {
    const ComparisonRow* row = m.comparison->Find(key);
    EXPECT_TRUE(row) << key;
    return row && row->values[rig] ? *row->values[rig] : NAN;
  };
  // Nothing edited: both columns are the live fields' numbers.
  run(R"([{"compare": "saved"}])");
  ASSERT_TRUE(m.comparison);
  EXPECT_EQ(m.comparison->rigs, (std::vector<std::string>{"ring (edited)", "ring (saved)"}));
  EXPECT_GT(value("coverage_ge3", 0), 0);
  for (const char* key : {"coverage_ge1", "coverage_ge2", "coverage_ge3", "resolution_p50_px_per_m",
                          "sigma_max_p90_mm"})
    EXPECT_EQ(value(key, 0), value(key, 1)) << key;
  EXPECT_EQ(m.StateJson()["comparison"]["rigs"][1], "ring (saved)");

  // Turn a camera away: the edited column drops, the saved column is a full evaluation of the rig
  // as loaded; comparing again gives the same numbers (the saved rig's are kept).
  const Rig loaded = m.rig();
  const std::string c = loaded.cameras[1].id;
  run(R"([{"rotate": ")" + c + R"(", "axis": [0, 0, 1], "deg": 40}, {"compare": "saved"}])");
  EXPECT_EQ(m.comparison_rig_version, m.session().rig().version());
  EXPECT_LT(value("coverage_ge3", 0), value("coverage_ge3", 1));
  FieldOptions fo;
  fo.fields = options.fields;
  const Fields full = EvaluateFields(m.scene(), loaded, m.session().study().caster(), fo);
  const Summary expected = Summarize(m.scene(), loaded, full, options.fields, 1);
  EXPECT_EQ(value("coverage_ge3", 1), expected.coverage.ge3);
  EXPECT_EQ(value("resolution_p50_px_per_m", 1), *expected.resolution_px_per_m->p50);
  const double saved_ge3 = value("coverage_ge3", 1), edited_ge3 = value("coverage_ge3", 0);
  run(R"([{"compare": "saved"}])");
  EXPECT_EQ(value("coverage_ge3", 1), saved_ge3);
  EXPECT_EQ(value("coverage_ge3", 0), edited_ge3);
  // The best of a row is the higher coverage (the saved rig's here).
  EXPECT_TRUE(m.comparison->Find("coverage_ge3")->best[1]);
  // Undo: the edited rig is the saved one again.
  run(R"([{"undo": 1}, {"compare": "saved"}])");
  EXPECT_EQ(value("coverage_ge3", 0), saved_ge3);
  EXPECT_THROW(run(R"([{"compare": ["saved", "nope"]}])"), InputError);
}

}  // namespace
}  // namespace pandora::viewer

namespace pandora::viewer {
namespace {

// A PTZ camera in the viewer (docs/ptz.md, "In the viewer"): its script actions, the gizmo's turn
// becoming pan, presets, re-centre, save, and the traces lighting the main view.
TEST(ViewerModel, PtzCameraPanTiltRecentreSaveAndTraces) {
  // The script actions and their refusals with the JSON path.
  EXPECT_EQ(ParseScript(R"([{"ptz": "dome", "pan_deg": 63, "tilt_deg": -3, "hfov_deg": 40}])",
                        "s.json")[0]
                .pan_deg,
            63);
  EXPECT_EQ(ParseScript(R"([{"ptz": "dome", "preset": "window"}])", "s.json")[0].preset, "window");
  EXPECT_EQ(ParseScript(R"([{"trace": "all", "seconds": 1.5}])", "s.json")[0].number, 1.5);
  EXPECT_TRUE(std::isnan(ParseScript(R"([{"trace": "path"}])", "s.json")[0].number));
  for (const auto& [script, where] : std::vector<std::pair<std::string, std::string>>{
           {R"([{"ptz": "dome"}])", "s.json: $[0]: nothing to change"},
           {R"([{"ptz": "dome", "preset": "window", "pan_deg": 3}])", "s.json: $[0].preset"},
           {R"([{"ptz": "dome", "tilt_deg": 200}])", "s.json: $[0].tilt_deg"},
           {R"([{"trace": "sweep"}])", "s.json: $[0].trace: unknown value 'sweep'"},
           {R"([{"recentre": "dome", "x": 1}])", "s.json: $[0].x"}}) {
    try {
      ParseScript(script, "s.json");
      ADD_FAILURE() << script;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
    }
  }

  const fs::path dir = fs::path(::testing::TempDir()) / "viewer_ptz";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file("examples/ptz_home/scene.json", dir / "scene.json");
  const fs::path scene = dir / "scene.json";
  const std::string original = Read(scene);
  ViewerOptions options;
  options.fields = {"coverage"};
  options.width = 160;
  options.height = 100;
  ViewerModel m(session::Study::Load(scene.string()), options);
  CpuFrontend cpu;
  const PtzHead h0 = *m.rig().cameras[0].ptz;
  auto head = [&]() -> const PtzHead& { return *m.rig().cameras[0].ptz; };
  m.Run(
      ParseScript(
          R"([{"select": "dome"}, {"ptz": "dome", "pan_deg": 30, "tilt_deg": -10, "hfov_deg": 40}])",
          "s.json"),
      &cpu);
  EXPECT_EQ(head().current.pan_deg, 30);
  EXPECT_EQ(head().current.tilt_deg, -10);
  EXPECT_EQ(m.status, "dome (PTZ): pan 30.0, tilt -10.0, hfov 40.0 deg");
  EXPECT_EQ(m.rig().cameras[0].world_from_camera.matrix(), head().Pose(head().current).matrix());
  // The gizmo's turn of 15 degrees about +z (the pan axis) pans by 15; tilt stays.
  m.Run(ParseScript(R"([{"rotate": "dome", "axis": [0, 0, 1], "deg": 15}])", "s.json"), &cpu);
  EXPECT_NEAR(head().current.pan_deg, 45, 1e-9);
  EXPECT_NEAR(head().current.tilt_deg, -10, 1e-9);
  EXPECT_EQ(head().home.matrix(), h0.home.matrix());
  // A turn beyond the tilt range stops at it and says so.
  m.Run(ParseScript(R"([{"orient": "dome", "ypr_deg": [0, 40, 0]}])", "s.json"), &cpu);
  EXPECT_NEAR(head().current.tilt_deg, 10, 1e-12);
  EXPECT_NE(m.status.find("(limited by its ranges)"), std::string::npos) << m.status;
  // A move takes the pivot along.
  m.Run(ParseScript(R"([{"undo": 1}, {"move": "dome", "by": [0.2, 0, 0]}])", "s.json"), &cpu);
  EXPECT_LT((head().home.translation() - h0.home.translation() - Vec3(0.2, 0, 0)).norm(), 1e-15);
  EXPECT_NEAR(head().current.pan_deg, 45, 1e-9);
  // Presets; an unknown one is refused naming the presets.
  m.Run(ParseScript(R"([{"undo": 1}, {"ptz": "dome", "preset": "west_door"}])", "s.json"), &cpu);
  EXPECT_EQ(head().current.pan_deg, 63);
  EXPECT_EQ(head().current.tilt_deg, -3);
  try {
    m.Run(ParseScript(R"([{"ptz": "dome", "preset": "garage"}])", "s.json"), &cpu);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("presets: window, west_door, east_door"),
              std::string::npos)
        << e.what();
  }
  // A resolution or lens model change would leave the zoom range in the old pixels: refused.
  for (const char* script : {R"([{"intrinsics": "dome", "resolution": [640, 360]}])",
                             R"([{"intrinsics": "dome", "model": "fisheye"}])"}) {
    try {
      m.Run(ParseScript(script, "s.json"), &cpu);
      ADD_FAILURE() << script;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("is a PTZ camera: its zoom range is in pixels"),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_EQ(m.rig().cameras[0].model.width(), 1280);
  // Re-centre: the view stays, the west door preset is home now.
  const Eigen::Isometry3d pose = m.rig().cameras[0].world_from_camera;
  m.Run(ParseScript(R"([{"recentre": "dome"}])", "s.json"), &cpu);
  EXPECT_LT((m.rig().cameras[0].world_from_camera.matrix() - pose.matrix()).cwiseAbs().maxCoeff(),
            1e-12);
  EXPECT_NEAR(head().presets[1].state.pan_deg, 0, 1e-12);
  EXPECT_EQ(m.session().rig().undo_label(), "re-centre dome");
  m.Run(ParseScript(R"([{"ptz": "dome", "pan_deg": -20}])", "s.json"), &cpu);

  // Traces: path and all light parts of the room the current view does not (pixels brighter than
  // the single trace's by more than 0.05 in linear RGB summed).
  m.Run(ParseScript(R"([{"screenshot": ")" + (dir / "single.png").string() + R"("},
                        {"trace": "path"}, {"screenshot": ")" +
                        (dir / "path.png").string() + R"("},
                        {"trace": "all", "seconds": 1.5}, {"screenshot": ")" +
                        (dir / "all.png").string() + R"("}])",
                    "s.json"),
        &cpu);
  EXPECT_EQ(m.ptz_trace, "all");
  EXPECT_EQ(m.StateJson()["ptz_trace"], "all");
  const Image single = ReadPng((dir / "single.png").string());
  auto newly_lit = [&](const std::string& name) {
    const Image image = ReadPng((dir / name).string());
    int n = 0;
    for (int i = 0; i < image.width * image.height; ++i)
      n += image.rgb[3 * i] + image.rgb[3 * i + 1] + image.rgb[3 * i + 2] >
           single.rgb[3 * i] + single.rgb[3 * i + 1] + single.rgb[3 * i + 2] + 0.05;
    return double(n) / (image.width * image.height);
  };
  const double path = newly_lit("path.png"), all = newly_lit("all.png");
  EXPECT_GT(path, 0.02);
  EXPECT_GT(all, path);
  std::printf("newly lit: path %.3f, all %.3f of the pixels\n", path, all);

  // Save: the pivot, home and head go into the file, the original into a backup.
  m.Run(ParseScript(R"([{"save": 1}])", "s.json"), &cpu);
  EXPECT_NE(m.status.find("saved 1 camera into"), std::string::npos) << m.status;
  const Scene saved = LoadScene(scene.string());
  const Camera& back = saved.rigs[0].cameras[0];
  ASSERT_TRUE(back.ptz);
  EXPECT_NEAR(back.ptz->current.pan_deg, -20, 1e-9);
  EXPECT_NEAR(back.ptz->current.tilt_deg, 0, 1e-9);
  EXPECT_NEAR(back.ptz->presets[1].state.pan_deg, 0, 1e-9);
  EXPECT_LT((back.world_from_camera.matrix() - m.rig().cameras[0].world_from_camera.matrix())
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
  EXPECT_EQ(Read(dir / "scene.json.bak"), original);
  m.session().WaitFields();
}

}  // namespace
}  // namespace pandora::viewer

namespace pandora::viewer {
namespace {

// The Plan and Elevation views (docs/viewer.md, "Plans and elevations"): the main view is
// `pandora render --plan`'s PlanView with the same default cut; pan and dolly stay in it, orbit
// leaves it.
TEST(ViewerModel, PlanAndElevationViewsAreRenderPlansAndPanWithinThem) {
  ExpectScriptError(R"([{"view": "elevation"}])", "$[0]");
  ExpectScriptError(R"([{"view": "elevation", "side": "up"}])", "$[0].side");
  ExpectScriptError(R"([{"view": "plan", "side": "north"}])", "$[0].side");
  ViewerOptions options;
  options.fields = {"coverage"};
  options.width = 320;
  options.height = 180;
  ViewerModel m(session::Study::Load("examples/trauma_room/scene.json"), options);
  auto run = [&](const std::string& text) { m.Run(ParseScript(text, "s.json"), nullptr); };
  const Aabb bounds = m.scene().ContentBounds();
  const Aabb& region = m.scene().study.region.box;
  auto expect_view = [&](const RenderView& want) {
    const RenderView v = m.MainView();
    EXPECT_LT((v.from - want.from).norm(), 1e-9);
    EXPECT_LT((v.at - want.at).norm(), 1e-9);
    EXPECT_LT((v.up - want.up).norm(), 1e-12);
    EXPECT_NEAR(v.fov_deg, want.fov_deg, 1e-12);
    EXPECT_NEAR(v.clip_near, want.clip_near, 1e-9);
    EXPECT_EQ(v.width, 320);
  };
  run(R"([{"view": "plan"}])");
  EXPECT_EQ(m.plan, "plan");
  EXPECT_EQ(m.StateJson()["plan"], "plan");
  expect_view(*PlanView(bounds, "plan", 320, 180, region.max.z()));
  // The cut at the region's top: the eye's distance to the plane z = region top.
  EXPECT_NEAR(m.MainView().clip_near, m.MainView().from.z() - region.max.z(), 1e-9);
  run(R"([{"view": "elevation", "side": "south"}])");
  EXPECT_EQ(m.plan, "south");
  expect_view(*PlanView(bounds, "south", 320, 180, region.min.y()));
  EXPECT_NEAR(m.MainView().clip_near, region.min.y() - m.MainView().from.y(), 1e-9);

  // Pan: the point under the cursor (on the plane through the framed centre) follows it, to 1 um.
  run(R"([{"view": "plan"}])");
  auto on_plane = [&](double x, double y) {
    const RenderView v = m.MainView();
    const Ray r = *PixelRay(m.rig(), v, x, y);
    const double t = (bounds.center().z() - r.origin.z()) / r.direction.z();
    return Vec3(r.origin + t * r.direction);
  };
  const Vec3 before = on_plane(100, 60);
  run(R"([{"pan": [40, -25]}])");
  EXPECT_EQ(m.plan, "plan");
  EXPECT_LT((on_plane(140, 35) - before).norm(), 1e-6);
  EXPECT_NEAR(m.MainView().clip_near, m.MainView().from.z() - region.max.z(), 1e-9);  // cut kept
  // Dolly magnifies: the half field's tangent x 0.85^2, the eye and the cut stay.
  const RenderView panned = m.MainView();
  run(R"([{"dolly": 2}])");
  EXPECT_NEAR(std::tan(0.5 * m.MainView().fov_deg * kRadPerDeg),
              0.85 * 0.85 * std::tan(0.5 * panned.fov_deg * kRadPerDeg), 1e-12);
  EXPECT_LT((m.MainView().from - panned.from).norm(), 1e-9);
  // Orbit leaves the plan for a perspective view from above the panned centre, then turns.
  run(R"([{"orbit": [0, 0]}])");
  EXPECT_EQ(m.plan, "");
  EXPECT_EQ(m.MainView().clip_near, 0);
  EXPECT_GT(m.view.Forward().dot(-Vec3::UnitZ()), 0.999);
  EXPECT_LT((m.view.target.head<2>() - panned.at.head<2>()).norm(), 1e-9);
  // A named view leaves it too.
  run(R"([{"view": "plan"}, {"view": "overview"}])");
  EXPECT_EQ(m.plan, "");
}

}  // namespace
}  // namespace pandora::viewer
