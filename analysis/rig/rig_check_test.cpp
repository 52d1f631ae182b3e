// Rig plausibility checks (analysis/rig/rig_check.h): the lens's effective field of view and
// unreachable share against closed forms, and each warning on a lab built to trigger exactly one
// per camera.
#include "analysis/rig/rig_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

Intrinsics Lens(int w, int h, double f, LensModel model = LensModel::kPinhole) {
  Intrinsics k;
  k.width = w;
  k.height = h;
  k.fx = k.fy = f;
  k.cx = 0.5 * (w - 1);
  k.cy = 0.5 * (h - 1);
  k.model = model;
  return k;
}

TEST(LensCoverage, PinholeEffectiveEqualsNominal) {
  const CameraModel m(Lens(1280, 720, 900));
  const LensCoverage c = ComputeLensCoverage(m);
  const double h = 2 * std::atan(640.0 / 900) * kDegPerRad,
               v = 2 * std::atan(360.0 / 900) * kDegPerRad;
  EXPECT_NEAR(c.nominal_hfov_deg, h, 1e-9);
  EXPECT_NEAR(c.nominal_vfov_deg, v, 1e-9);
  EXPECT_NEAR(c.hfov_deg, h, 1e-9);
  EXPECT_NEAR(c.vfov_deg, v, 1e-9);
  EXPECT_EQ(c.unreachable_fraction, 0.0);
  EXPECT_FALSE(c.domain_ends_inside_image);
}

// Radial Brown-Conrady with k1 < 0 only: r_d = r (1 + k1 r^2) turns at r* = 1 / sqrt(-3 k1), where
// r_d* = (2/3) r*. With fx = fy = f and a centred principal point the reachable pixels are the disc
// of radius f r_d* around the centre, so the unreachable share is 1 - area(disc ∩ image) / area.
TEST(LensCoverage, BarrelDomainEndsInsideTheImageClosedForm) {
  const double k1 = -0.2, f = 500;
  Intrinsics k = Lens(1000, 800, f, LensModel::kBrownConrady);
  k.k1 = k1;
  const CameraModel m(k);
  const double r_star = 1 / std::sqrt(-3 * k1), R = f * (2.0 / 3.0) * r_star;  // 430.3 px
  ASSERT_LT(R, 500.0);
  ASSERT_GT(R, 400.0);  // the disc is cut by the top and bottom edges only
  const double d = 400.0;
  const double segment = R * R * std::acos(d / R) - d * std::sqrt(R * R - d * d);
  const double inside = kPi * R * R - 2 * segment;
  const double expected = 1 - inside / (1000.0 * 800.0);
  const LensCoverage c = ComputeLensCoverage(m);
  EXPECT_TRUE(c.domain_ends_inside_image);
  EXPECT_NEAR(c.unreachable_fraction, expected, 5e-4) << "expected " << expected;
  // Horizontally the domain ends first: the last ray is at r*, so the FOV is 2 atan(r*).
  EXPECT_NEAR(c.hfov_deg, 2 * std::atan(r_star) * kDegPerRad, 1e-3);
  // Vertically the edge (r_d = 0.8) is reachable: r (1 + k1 r^2) = 0.8 on [0, r*].
  double lo = 0, hi = r_star;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mid * (1 + k1 * mid * mid) < 0.8 ? lo : hi) = mid;
  }
  EXPECT_NEAR(c.vfov_deg, 2 * std::atan(lo) * kDegPerRad, 1e-6);
  EXPECT_NEAR(c.nominal_hfov_deg, 90.0, 1e-9);
}

TEST(LensCoverage, FisheyeOver180DegreesIsReportedAsSuch) {
  // An equidistant fisheye (no distortion coefficients): theta = r_d, 200 degrees across.
  const int w = 1000;
  const double f = FocalFromHfov(200.0 / kDegPerRad, w, LensModel::kFisheye);
  const LensCoverage c = ComputeLensCoverage(CameraModel(Lens(w, w, f, LensModel::kFisheye)));
  EXPECT_NEAR(c.nominal_hfov_deg, 200.0, 1e-9);
  EXPECT_NEAR(c.hfov_deg, 200.0, 1e-6);
  EXPECT_NEAR(c.vfov_deg, 200.0, 1e-6);
  // The corners lie at theta = sqrt(2) * 100 = 141 degrees, within the model's domain (180).
  EXPECT_FALSE(c.domain_ends_inside_image);
}

// A 7 x 5 x 3 m lab with no ceiling: four one-sided walls facing in (planes), a floor slab reaching
// 2 m beyond the north wall (so a camera just outside that wall is still inside the geometry's
// bounds), a solid cabinet, and a solid screen that hides the region from a corner ("niche").
std::string Lab() {
  return R"({
  "objects": [
    {"name": "floor", "box": {"size": [7, 7, 0.1]}, "position": [0, 1, -0.05], "solid": true},
    {"name": "wall_s", "plane": {"size": [7, 3]}, "position": [0, -2.5, 1.5], "rotation_deg": [-90, 0, 0]},
    {"name": "wall_w", "plane": {"size": [3, 5]}, "position": [-3.5, 0, 1.5], "rotation_deg": [0, 90, 0]},
    {"name": "wall_e", "plane": {"size": [3, 5]}, "position": [3.5, 0, 1.5], "rotation_deg": [0, -90, 0]},
    {"name": "wall_n", "plane": {"size": [7, 3]}, "position": [0, 2.5, 1.5], "rotation_deg": [90, 0, 0]},
    {"name": "cabinet", "box": {"size": [0.6, 0.5, 2.0]}, "position": [3.0, -2.0, 1.0], "solid": true},
    {"name": "screen", "box": {"size": [0.5, 1.2, 3.0]}, "position": [-2.8, 1.8, 1.5], "solid": true}
  ],
  "rigs": [{"name": "lab", "cameras": [
    {"id": "ok", "position": [-3, -2, 2.5], "look_at": [0, 0, 1], "resolution": [1280, 800], "hfov_deg": 80},
    {"id": "in_box", "position": [3.0, -2.0, 1.5], "look_at": [0, 0, 1], "resolution": [1280, 800], "hfov_deg": 80},
    {"id": "outside", "position": [0, -6, 2], "look_at": [0, 0, 1], "resolution": [1280, 800], "hfov_deg": 80},
    {"id": "behind", "position": [0, 3.0, 2], "look_at": [0, 0, 1], "resolution": [1280, 800], "hfov_deg": 80},
    {"id": "away", "position": [3, 2, 2.5], "look_at": [3, 2, 6], "up": [0, 1, 0], "resolution": [1280, 800], "hfov_deg": 60},
    {"id": "barrel", "position": [3, 2, 2.5], "look_at": [0, 0, 1], "resolution": [1280, 800], "focal_px": 500,
     "distortion": {"model": "brown_conrady", "k1": -0.2}},
    {"id": "niche", "position": [-3.3, 2.3, 1.0], "look_at": [0, 0, 1], "resolution": [1280, 800], "hfov_deg": 80},
    {"id": "off", "enabled": false, "position": [3.0, -2.0, 1.5], "look_at": [0, 0, 1], "resolution": [640, 480], "hfov_deg": 60}
  ]}],
  "study": {"region": {"box": {"min": [-1, -1, 0.2], "max": [1, 1, 2]}}, "voxel_size": 0.1}
})";
}

std::map<std::string, std::vector<Warning::Kind>> ByCamera(const std::vector<Warning>& ws) {
  std::map<std::string, std::vector<Warning::Kind>> m;
  for (const Warning& w : ws) m[w.camera].push_back(w.kind);
  return m;
}

TEST(CheckRig, EachNonsenseCameraGetsItsOneWarning) {
  const Scene scene = ParseScene(Lab(), "lab.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<Warning> ws = CheckRig(scene, scene.rigs[0], *caster);
  auto by = ByCamera(ws);
  using K = Warning::Kind;
  EXPECT_EQ(by.count("ok"), 0u);
  EXPECT_EQ(by["in_box"], std::vector<K>{K::kInsideSolid});
  EXPECT_EQ(by["outside"], std::vector<K>{K::kOutsideRoom});
  EXPECT_EQ(by["behind"], std::vector<K>{K::kOutsideRoom});
  EXPECT_EQ(by["away"], std::vector<K>{K::kSeesNoRegion});
  EXPECT_EQ(by["barrel"], std::vector<K>{K::kLensDomain});
  // Behind the screen inside the room: the room's walls are behind it, so it is not "outside".
  EXPECT_EQ(by["niche"], std::vector<K>{K::kSeesNoRegion});
  EXPECT_EQ(by.count("off"), 0u) << "a disabled camera is not checked";
  for (const Warning& w : ws) {
    SCOPED_TRACE(w.reason);
    EXPECT_EQ(w.reason.find('\n'), std::string::npos);
    EXPECT_NE(w.reason.find("'" + w.camera + "'"), std::string::npos);
    EXPECT_EQ(w.json_path.rfind("$.rigs[0].cameras[", 0), 0u);
  }
  for (const Warning& w : ws) {
    if (w.camera == "in_box") {
      EXPECT_EQ(w.json_path, "$.rigs[0].cameras[1].position");
      EXPECT_NE(w.reason.find("'cabinet'"), std::string::npos);
    }
    if (w.camera == "behind") {
      EXPECT_NE(w.reason.find("'wall_n'"), std::string::npos);
    }
    if (w.camera == "away") {
      EXPECT_EQ(w.json_path, "$.rigs[0].cameras[4]");
      EXPECT_NE(w.reason.find("the region is behind it"),
                std::string::npos);  // it looks at the ceiling
    }
    if (w.camera == "niche") {
      EXPECT_NE(w.reason.find("its view is blocked by 'screen'"), std::string::npos);
    }
    if (w.camera == "barrel") {
      EXPECT_EQ(w.json_path, "$.rigs[0].cameras[5].distortion");
      // 1280 x 800 at f = 500: the reachable disc has radius 430.3 px, cut top and bottom.
      const double R = 500 * (2.0 / 3.0) / std::sqrt(0.6), d = 400.0;
      const double inside =
          kPi * R * R - 2 * (R * R * std::acos(d / R) - d * std::sqrt(R * R - d * d));
      char expected[32];
      std::snprintf(expected, sizeof expected, "%.1f%%", 100 * (1 - inside / (1280.0 * 800.0)));
      EXPECT_NE(w.reason.find(expected), std::string::npos) << expected;
    }
  }
  EXPECT_EQ(FormatWarning("lab.json", ws[0]), "lab.json: " + ws[0].json_path + ": " + ws[0].reason);
}

// A study's point-in-solid trees (RigCheckOptions::object_tree) are used instead of trees of its
// own, with the same warnings word for word.
TEST(CheckRig, GivenSolidTreesGiveTheSameWarnings) {
  const Scene scene = ParseScene(Lab(), "lab.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<Warning> own = CheckRig(scene, scene.rigs[0], *caster);
  std::vector<std::unique_ptr<InsideMesh>> trees(scene.objects.size());
  int asked = 0;
  RigCheckOptions o;
  o.object_tree = [&](std::size_t object) -> const InsideMesh* {
    ++asked;
    if (!trees.at(object)) trees[object] = std::make_unique<InsideMesh>(scene.objects[object].mesh);
    return trees[object].get();
  };
  const std::vector<Warning> given = CheckRig(scene, scene.rigs[0], *caster, o);
  EXPECT_GT(asked, 0);
  ASSERT_EQ(given.size(), own.size());
  for (std::size_t i = 0; i < own.size(); ++i) {
    EXPECT_EQ(given[i].kind, own[i].kind);
    EXPECT_EQ(given[i].camera, own[i].camera);
    EXPECT_EQ(given[i].json_path, own[i].json_path);
    EXPECT_EQ(given[i].reason, own[i].reason);
  }
}

TEST(CheckRig, VoxelCountsDecideWhatACameraSees) {
  const Scene scene = ParseScene(Lab(), "lab.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  RigCheckOptions o;
  o.visible_voxels = {0, 0, 0, 0, 5, 3, 7, 0};  // "ok" sees nothing by the fields, "away" sees some
  auto by = ByCamera(CheckRig(scene, scene.rigs[0], *caster, o));
  using K = Warning::Kind;
  EXPECT_EQ(by["ok"], std::vector<K>{K::kSeesNoRegion});
  EXPECT_EQ(by.count("away"), 0u);
  // The placement warnings stay the most specific ones.
  EXPECT_EQ(by["in_box"], std::vector<K>{K::kInsideSolid});
  EXPECT_EQ(by["outside"], std::vector<K>{K::kOutsideRoom});
}

// Without walls around the region there is no inside or outside: cameras on stands around an
// object, far outside the geometry's bounds, are fine. A centre on a solid's surface is not inside.
TEST(CheckRig, NoRoomMeansNoOutside) {
  const Scene scene = ParseScene(R"({
  "objects": [{"name": "block", "box": {"size": [0.4, 0.4, 0.4]}, "position": [0, 0, 0.2], "solid": true}],
  "rigs": [{"name": "stands", "cameras": [
    {"id": "far", "position": [6, 0, 1], "look_at": [0, 0, 0.3], "resolution": [640, 480], "hfov_deg": 30},
    {"id": "on_face", "position": [0.2, 0, 0.2], "look_at": [1, 0, 0.2], "resolution": [640, 480], "hfov_deg": 60},
    {"id": "in_block", "position": [0.1, 0, 0.2], "look_at": [1, 0, 0.2], "resolution": [640, 480], "hfov_deg": 60}
  ]}],
  "study": {"region": {"box": {"min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0.6]}}, "voxel_size": 0.05}
})",
                                 "stands.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  auto by = ByCamera(CheckRig(scene, scene.rigs[0], *caster));
  using K = Warning::Kind;
  EXPECT_EQ(by.count("far"), 0u);
  // It looks away from most of the region, yet sees the part beside the block in front of it; not
  // inside the block, but on its face: warned about as such (its centre's side decides, issue 27).
  EXPECT_EQ(by["on_face"], std::vector<K>{K::kOnSurface});
  EXPECT_EQ(by["in_block"], std::vector<K>{K::kInsideSolid});
}

// Valid values that are almost surely mistakes, each named by its JSON path: a file in metres read
// as centimetres, a field of view in radians, a named region outside the study region, a 14 m
// marker.
TEST(CheckRig, ImplausibleValuesAreWarnedAboutByPath) {
  const std::string text = R"({
  "units": "cm",
  "objects": [{"name": "block", "box": {"size": [0.4, 0.4, 0.4]}, "position": [0, 0, 0.2], "solid": true}],
  "rigs": [{"name": "r", "cameras": [
    {"id": "a", "position": [6, 0, 1], "look_at": [0, 0, 0.3], "resolution": [640, 480], "hfov_deg": 60},
    {"id": "rad", "position": [0, 6, 1], "look_at": [0, 0, 0.3], "resolution": [640, 480], "hfov_deg": 1.4}
  ]}],
  "study": {"region": {"box": {"min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0.6]}}, "voxel_size": 0.05,
            "fields": ["coverage", "cameras"],
            "regions": {"elsewhere": {"box": {"min": [5, 5, 0], "max": [6, 6, 1]}}},
            "pixel_targets": [{"name": "marker", "size_m": 1400, "min_px": 4}]}
})";
  const Scene scene = ParseScene(text, "cm.json");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  std::map<std::string, std::string> by_path;
  for (const Warning& w : CheckRig(scene, scene.rigs[0], *caster))
    if (w.kind == Warning::Kind::kImplausible) by_path[w.json_path] = w.reason;
  ASSERT_EQ(by_path.size(), 4u);
  EXPECT_NE(by_path["$.units"].find("spans 0.065 m"), std::string::npos) << by_path["$.units"];
  EXPECT_NE(by_path["$.rigs[0].cameras[1].hfov_deg"].find("80.21 degrees"), std::string::npos);
  EXPECT_NE(by_path["$.study.regions.elsewhere"].find("outside the study region"),
            std::string::npos);
  EXPECT_NE(by_path["$.study.pixel_targets[0]"].find("14 m across"), std::string::npos);
  // A person keyframed through a wall, and a cart moved out of the room (metres this time).
  const Scene moving = ParseScene(R"({
  "objects": [{"name": "floor", "box": {"size": [6, 6, 0.1]}, "position": [0, 0, -0.05], "solid": true},
              {"name": "wall", "box": {"size": [0.1, 6, 3]}, "position": [1, 0, 1.5], "solid": true},
              {"name": "body", "group": "walker", "capsule": {"radius": 0.2, "length": 1.4}, "position": [0, 0, 0.9], "solid": true},
              {"name": "cart", "box": {"size": [0.5, 0.5, 0.5]}, "position": [-1, -1, 0.25], "solid": true}],
  "motions": {"walker": {"keyframes": [{"t": 0}, {"t": 2, "move": [2, 0, 0]}]},
              "cart": {"keyframes": [{"t": 0}, {"t": 2, "move": [0, -30, 0]}]}},
  "rigs": [{"name": "r", "cameras": [
    {"id": "a", "position": [-2.5, -2.5, 2.5], "look_at": [0, 0, 1], "resolution": [640, 480], "hfov_deg": 70}]}],
  "study": {"region": {"box": {"min": [-2.5, -2.5, 0], "max": [2.5, 2.5, 2.5]}}, "voxel_size": 0.25,
            "time": {"times": [0, 1, 2]}}
})",
                                  "moving.json");
  const auto moving_caster = MakeEmbreeRayCaster(moving.AllTriangles());
  std::map<std::string, std::string> moves;
  for (const Warning& w : CheckRig(moving, moving.rigs[0], *moving_caster))
    if (w.kind == Warning::Kind::kImplausible) moves[w.json_path] = w.reason;
  ASSERT_EQ(moves.size(), 2u);
  EXPECT_NE(moves["$.motions.walker"].find("passes through a solid object between t=0 s and t=1 s"),
            std::string::npos)
      << moves["$.motions.walker"];
  EXPECT_NE(moves["$.motions.cart"].find("entirely outside the study region at t=1 s"),
            std::string::npos)
      << moves["$.motions.cart"];
  // The same file in metres, with sensible values: no such warning.
  std::string fixed = text;
  fixed.replace(fixed.find("\"units\": \"cm\""), 13, "\"units\": \"m\"");
  fixed.replace(fixed.find("\"hfov_deg\": 1.4"), 15, "\"hfov_deg\": 80");
  fixed.replace(fixed.find("[5, 5, 0]"), 9, "[0, 0, 0]");
  fixed.replace(fixed.find("\"size_m\": 1400"), 14, "\"size_m\": 0.014");
  const Scene good = ParseScene(fixed, "m.json");
  const auto good_caster = MakeEmbreeRayCaster(good.AllTriangles());
  for (const Warning& w : CheckRig(good, good.rigs[0], *good_caster))
    EXPECT_NE(w.kind, Warning::Kind::kImplausible) << w.json_path << ": " << w.reason;
}

}  // namespace
}  // namespace pandora
