// PTZ heads (issue 13): the file's pose is home, the camera is the current setting; move times are
// the closed form of every axis at once; reach times equal the closed form where one axis decides
// and a brute-force sweep of reachable poses everywhere; the offset moves the centre and the
// footprint as computed; bad ptz blocks are one-line input errors.
#include "analysis/scene/ptz.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

// An empty room: one PTZ at (0, 0, 3) looking along +y at home; `ptz` is the block's body.
Scene PtzScene(const std::string& ptz, const std::string& camera_extra = "") {
  const std::string text = R"({"pandora": 1, "objects": [],
    "rigs": [{"name": "r", "cameras": [{"id": "p", "position": [0, 0, 3], "look_at": [0, 5, 3],
      "resolution": [400, 300], "hfov_deg": 40)" +
                           camera_extra + R"(, "ptz": {)" + ptz + R"(}}]}],
    "study": {"region": {"box": {"min": [-5, -5, 0], "max": [5, 5, 3]}}, "voxel_size": 0.5}})";
  return ParseScene(text, "ptz.json");
}

TEST(Ptz, FilePoseIsHomeAndTheCameraIsTheCurrentSetting) {
  const Scene scene = PtzScene(R"("pan_deg": 90, "tilt_deg": -30, "zoom_hfov_deg": [60, 5])");
  const Camera& c = scene.rigs[0].cameras[0];
  ASSERT_TRUE(c.ptz);
  const PtzHead& h = *c.ptz;
  EXPECT_NEAR(h.HomeElevationDeg(), 0.0, 1e-12);
  EXPECT_TRUE(h.pan_axis.isApprox(Vec3::UnitZ(), 1e-15));
  // Pan +90 turns the view from +y to -x (counter-clockwise from above), tilt -30 looks down.
  const Vec3 axis = c.world_from_camera.linear().col(2);
  EXPECT_NEAR((axis - Vec3(-std::cos(Rad(30)), 0, -std::sin(Rad(30)))).norm(), 0, 1e-12);
  EXPECT_NEAR(c.world_from_camera.linear().col(0).z(), 0, 1e-12);  // level
  EXPECT_TRUE(c.center().isApprox(Vec3(0, 0, 3), 1e-15));
  EXPECT_NEAR(c.model.intrinsics().fx, FocalFromHfov(Rad(40), 400, LensModel::kPinhole), 1e-9);
  EXPECT_NEAR(h.focal_min, FocalFromHfov(Rad(60), 400, LensModel::kPinhole), 1e-9);
  EXPECT_NEAR(h.focal_max, FocalFromHfov(Rad(5), 400, LensModel::kPinhole), 1e-9);
  EXPECT_EQ(h.home_focal, h.focal_min);
  EXPECT_TRUE(h.Pose(h.Home()).isApprox(h.home, 1e-15));
}

TEST(Ptz, MoveTimeIsTheSlowestAxisAndAlongArrivesThen) {
  const Scene scene =
      PtzScene(R"("pan_speed_deg_s": 90, "tilt_speed_deg_s": 30, "zoom_hfov_deg": [60, 5],
                                  "zoom_speed_pct_s": 25)");
  const PtzHead& h = *scene.rigs[0].cameras[0].ptz;
  const PtzState a{0, 0, h.focal_min};
  // Pan 120 deg: 1.333 s; tilt -45 deg: 1.5 s; zoom to a quarter of the range: 1 s.
  const PtzState b{120, -45, h.focal_min + 0.25 * (h.focal_max - h.focal_min)};
  EXPECT_NEAR(h.MoveTime(a, b), 1.5, 1e-12);
  const PtzState mid = h.Along(a, b, 1.0);
  EXPECT_NEAR(mid.pan_deg, 90, 1e-12);
  EXPECT_NEAR(mid.tilt_deg, -30, 1e-12);
  EXPECT_NEAR(mid.focal, b.focal, 1e-9);
  const PtzState end = h.Along(a, b, 1.5);
  EXPECT_NEAR(end.pan_deg, 120, 1e-12);
  EXPECT_NEAR(end.tilt_deg, -45, 1e-12);
  // A continuous pan takes the shorter way round: 170 -> -170 is 20 degrees.
  EXPECT_NEAR(h.MoveTime({170, 0, h.focal_min}, {-170, 0, h.focal_min}), 20.0 / 90.0, 1e-12);
  EXPECT_NEAR(h.Along({170, 0, h.focal_min}, {-170, 0, h.focal_min}, 0.1).pan_deg, 179, 1e-12);
}

// One axis decides: a point on the horizon enters the image when the pan has turned to within half
// the horizontal field of view; a point straight ahead above enters when the tilt is within half
// the vertical one.
TEST(Ptz, ReachTimeEqualsTheClosedFormWhereOneAxisDecides) {
  const Scene scene = PtzScene(R"("pan_speed_deg_s": 50, "tilt_speed_deg_s": 20)");
  const Camera& c = scene.rigs[0].cameras[0];
  const PtzHead& h = *c.ptz;
  const PtzReach reach(c, h, h.Home());
  const Intrinsics k = c.model.intrinsics();
  const double half_h = std::atan((k.width - 1 - k.cx + 0.5) / k.fx) * 180 / kPi;  // InImage's edge
  const double half_v = std::atan((k.height - 1 - k.cy + 0.5) / k.fy) * 180 / kPi;
  for (double az : {30.0, 75.0, 130.0, -100.0}) {
    const Vec3 X = Vec3(0, 0, 3) + 4.0 * Vec3(-std::sin(Rad(az)), std::cos(Rad(az)), 0);
    const double expected = std::max(0.0, (std::abs(az) - half_h) / 50.0);
    EXPECT_NEAR(reach.ReachTime(X, nullptr, 1e-7), expected, 1e-5) << az;
  }
  for (double el : {-70.0, -40.0, 35.0}) {
    const Vec3 X = Vec3(0, 0, 3) + 4.0 * Vec3(0, std::cos(Rad(el)), std::sin(Rad(el)));
    const double expected = std::max(0.0, (std::abs(el) - half_v) / 20.0);
    EXPECT_NEAR(reach.ReachTime(X, nullptr, 1e-7), expected, 1e-5) << el;
  }
}

// Both axes move at once: a point off in azimuth and elevation is reached when the slower axis gets
// there, not after the sum. Pan deciding: the tilt (faster here) has put the point on the image's
// horizontal midline, tilt atan2(sin el, cos el cos d) for an azimuth residual d, and the point
// enters the image where that midline meets the edge, at d = asin(sin h / cos el) (h: the half
// angle of the image's horizontal edge). Tilt deciding: the pan has centred the azimuth, and the
// point enters at the vertical edge, el - tilt = v.
TEST(Ptz, ReachTimeEqualsTheClosedFormWithBothAxesMoving) {
  const auto point = [](double az, double el) -> Vec3 {
    return Vec3(0, 0, 3) + 4.0 * Vec3(-std::sin(Rad(az)) * std::cos(Rad(el)),
                                      std::cos(Rad(az)) * std::cos(Rad(el)), std::sin(Rad(el)));
  };
  {
    const Scene scene = PtzScene(R"("pan_speed_deg_s": 50, "tilt_speed_deg_s": 40)");
    const Camera& c = scene.rigs[0].cameras[0];
    const PtzReach reach(c, *c.ptz, c.ptz->Home());
    const Intrinsics k = c.model.intrinsics();
    const double h = std::atan((k.width - 1 - k.cx + 0.5) / k.fx);
    for (const auto& [az, el] : {std::pair{100.0, -35.0}, {-120.0, -50.0}, {70.0, 25.0}}) {
      const double d = std::asin(std::sin(h) / std::cos(Rad(el))) * 180 / kPi;
      const double expected = (std::abs(az) - d) / 50;
      const double tilt =
          std::atan2(std::sin(Rad(el)), std::cos(Rad(el)) * std::cos(Rad(d))) * 180 / kPi;
      ASSERT_LT(std::abs(tilt) / 40, expected - 0.1);  // the tilt is there first: the pan decides
      EXPECT_NEAR(reach.ReachTime(point(az, el), nullptr, 1e-7), expected, 1e-5) << az << " " << el;
      EXPECT_LT(expected, std::abs(az) / 50 + std::abs(tilt) / 40 - 0.5);  // not the sum
    }
  }
  {
    const Scene scene = PtzScene(R"("pan_speed_deg_s": 100, "tilt_speed_deg_s": 20)");
    const Camera& c = scene.rigs[0].cameras[0];
    const PtzReach reach(c, *c.ptz, c.ptz->Home());
    const Intrinsics k = c.model.intrinsics();
    const double v = std::atan((k.height - 1 - k.cy + 0.5) / k.fy) * 180 / kPi;
    for (const auto& [az, el] : {std::pair{30.0, -60.0}, {-75.0, -70.0}, {120.0, 55.0}}) {
      const double expected = (std::abs(el) - v) / 20;
      ASSERT_LT(std::abs(az) / 100, expected - 0.1);  // the pan is there first: the tilt decides
      EXPECT_NEAR(reach.ReachTime(point(az, el), nullptr, 1e-7), expected, 1e-5) << az << " " << el;
    }
  }
}

// A rig written back (viewer save, autosave, output metadata) keeps the head: the file pose is home
// at the pivot, the ptz block holds the current setting, and it reads back to the same camera.
TEST(Ptz, RigToJsonKeepsTheHeadAndReadsBack) {
  const Scene scene =
      PtzScene(R"("pan_deg": 63, "tilt_deg": -12, "zoom_hfov_deg": [60, 5], "home_hfov_deg": 30,
      "pan_range_deg": [-170, 170], "tilt_range_deg": [-80, 20], "pan_speed_deg_s": 45, "tilt_speed_deg_s": 30,
      "zoom_speed_pct_s": 35, "offset_m": [0.01, -0.02, 0.08], "trace_s": 4,
      "presets": [{"name": "door", "pan_deg": 40, "tilt_deg": -5, "hfov_deg": 20}, {"name": "win", "pan_deg": -90}],
      "tour": [{"preset": "door", "dwell_s": 5}, {"preset": "win", "dwell_s": 2}])",
               R"(, "up": [0, 0, 1])");
  const nlohmann::json written = RigToJson(scene.rigs[0]);
  const Rig again = ParseRigJson(written, "again.json", "$.rig");
  const Camera& a = scene.rigs[0].cameras[0];
  const Camera& b = again.cameras[0];
  ASSERT_TRUE(b.ptz);
  const PtzHead& h = *a.ptz;
  const PtzHead& g = *b.ptz;
  EXPECT_LE((a.world_from_camera.matrix() - b.world_from_camera.matrix()).cwiseAbs().maxCoeff(),
            1e-12);
  EXPECT_LE((h.home.matrix() - g.home.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(a.model.intrinsics().fx, b.model.intrinsics().fx, 1e-9);
  EXPECT_LE((h.pan_axis - g.pan_axis).norm(), 1e-15);
  EXPECT_LE((h.offset - g.offset).norm(), 1e-15);
  for (auto [x, y] : {std::pair{h.pan_min_deg, g.pan_min_deg},
                      {h.pan_max_deg, g.pan_max_deg},
                      {h.tilt_min_deg, g.tilt_min_deg},
                      {h.tilt_max_deg, g.tilt_max_deg},
                      {h.pan_speed_deg_s, g.pan_speed_deg_s},
                      {h.tilt_speed_deg_s, g.tilt_speed_deg_s},
                      {h.zoom_speed, g.zoom_speed},
                      {h.trace_s, g.trace_s},
                      {h.current.pan_deg, g.current.pan_deg},
                      {h.current.tilt_deg, g.current.tilt_deg}})
    EXPECT_NEAR(x, y, 1e-12);
  for (auto [x, y] : {std::pair{h.focal_min, g.focal_min},
                      {h.focal_max, g.focal_max},
                      {h.home_focal, g.home_focal},
                      {h.current.focal, g.current.focal}})
    EXPECT_NEAR(x, y, 1e-9 * x);
  ASSERT_EQ(g.presets.size(), 2u);
  EXPECT_EQ(g.presets[1].name, "win");
  EXPECT_NEAR(g.presets[0].state.focal, h.presets[0].state.focal, 1e-9 * h.presets[0].state.focal);
  EXPECT_NEAR(g.presets[1].state.pan_deg, -90, 1e-12);
  ASSERT_EQ(g.tour.size(), 2u);
  EXPECT_EQ(g.tour[1].preset, 1);
  EXPECT_EQ(g.tour[0].dwell_s, 5);
  // A fixed-focal head (no zoom range) reads back too.
  const Scene fixed = PtzScene(R"("pan_deg": -20, "presets": [{"name": "a", "pan_deg": 10}])");
  const Rig fixed_again = ParseRigJson(RigToJson(fixed.rigs[0]), "again.json", "$.rig");
  EXPECT_NEAR(fixed_again.cameras[0].ptz->current.pan_deg, -20, 1e-12);
  EXPECT_EQ(fixed_again.cameras[0].ptz->focal_min, fixed_again.cameras[0].ptz->focal_max);
}

// Everywhere: the reach time equals a brute-force sweep of the reachable settings (every pose on a
// fine pan x tilt lattice at the widest reachable zoom, tested with the visibility rules), to the
// sweep's step.
TEST(Ptz, ReachTimeEqualsABruteForceSweepOfReachablePoses) {
  for (const char* offset : {"[0, 0, 0]", "[0.02, -0.05, 0.12]"}) {
    const Scene scene = PtzScene(std::string(R"("pan_speed_deg_s": 60, "tilt_speed_deg_s": 40,
        "zoom_hfov_deg": [40, 8], "zoom_speed_pct_s": 40, "home_hfov_deg": 8, "tilt_range_deg": [-80, 30],
        "pan_range_deg": [-150, 150], "offset_m": )") +
                                 offset);
    const Camera& c = scene.rigs[0].cameras[0];
    const PtzHead& h = *c.ptz;
    const PtzReach reach(c, h, h.Home());
    const auto empty = MakeBruteForceRayCaster(TriangleMesh());
    // Seen from some lattice pose reachable within t?
    auto swept = [&](const Vec3& X, double t) {
      const double step = 0.25;
      const double f =
          std::max(h.focal_min, h.home_focal - h.zoom_speed * (h.focal_max - h.focal_min) * t);
      const double p0 = std::max(h.pan_min_deg, -60 * t), p1 = std::min(h.pan_max_deg, 60 * t);
      const double t0 = std::max(h.tilt_min_deg, -40 * t), t1 = std::min(h.tilt_max_deg, 40 * t);
      for (double p = p0; p <= p1 + 1e-12; p += step)
        for (double q = t0; q <= t1 + 1e-12; q += step) {
          const VisibilityTester tester({h.CameraAt(c, {p, q, f})}, *empty, 10.0);
          if (tester.TestGeometry(0, X) == ViewResult::kSeen) return true;
        }
      return false;
    };
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(-1, 1);
    int compared = 0;
    for (int i = 0; i < 40 && compared < 12; ++i) {
      const Vec3 X(4 * u(rng), 4 * u(rng), 1.5 + 1.5 * u(rng));
      const double t = reach.ReachTime(X, nullptr, 1e-6);
      if (!std::isfinite(t) || t < 0.05) continue;
      ++compared;
      // The sweep finds nothing slightly before and something slightly after (its step is 0.25
      // deg: 0.0063 s of tilt, plus the zoom's part).
      EXPECT_FALSE(swept(X, t - 0.03)) << offset << " point " << X.transpose() << " t " << t;
      EXPECT_TRUE(swept(X, t + 0.03)) << offset << " point " << X.transpose() << " t " << t;
    }
    EXPECT_GE(compared, 8);
  }
}

// The centre of projection sits `offset` from the pivot and turns with the head: straight down from
// a pivot 3 m up with the centre 0.2 m forward of it, the centre is 2.8 m up and the footprint on
// the floor shrinks to 2.8 / 3 of the one without an offset.
TEST(Ptz, OffsetMovesTheCentreAndTheFootprintAsComputed) {
  const Scene scene = PtzScene(R"("tilt_deg": -90, "offset_m": [0, 0, 0.2])");
  const Camera& c = scene.rigs[0].cameras[0];
  EXPECT_TRUE(c.center().isApprox(Vec3(0, 0, 2.8), 1e-12));
  const auto empty = MakeBruteForceRayCaster(TriangleMesh());
  const VisibilityTester tester({c}, *empty, 10.0);
  const Intrinsics k = c.model.intrinsics();
  const double half = (k.width - 1 - k.cx + 0.5) / k.fx;  // tan of the half field of view
  // Pan 0, straight down: the image x axis is world +x.
  EXPECT_EQ(tester.TestGeometry(0, Vec3(2.8 * half - 1e-6, 0, 0)), ViewResult::kSeen);
  EXPECT_NE(tester.TestGeometry(0, Vec3(2.8 * half + 1e-6, 0, 0)), ViewResult::kSeen);
  // Sideways offset: 0.1 m to the camera's right, at pan 90 that is world +y.
  const Scene side = PtzScene(R"("pan_deg": 90, "offset_m": [0.1, 0, 0])");
  EXPECT_TRUE(side.rigs[0].cameras[0].center().isApprox(Vec3(0, 0.1, 3), 1e-12));
}

TEST(Ptz, BadBlocksAreOneLineInputErrors) {
  auto error = [](const std::string& ptz, const std::string& extra = "") {
    try {
      PtzScene(ptz, extra);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(R"("pan_deg": 200, "pan_range_deg": [-170, 170])")
                .find("$.rigs[0].cameras[0].ptz.pan_deg"),
            std::string::npos);
  EXPECT_NE(error(R"("tilt_range_deg": [-120, 10])").find("ptz.tilt_range_deg"), std::string::npos);
  EXPECT_NE(error(R"("zoom_hfov_deg": [30, 5])").find("ptz.zoom_hfov_deg"), std::string::npos);
  EXPECT_NE(error(R"("pan_axis": [1, 0, 0])").find("ptz.pan_axis"), std::string::npos);
  EXPECT_NE(error(R"("pan_speed_deg_s": 0)").find("ptz.pan_speed_deg_s"), std::string::npos);
  EXPECT_NE(error(R"("presets": [{"name": "a"}], "tour": [{"preset": "b", "dwell_s": 2}])")
                .find("ptz.tour[0].preset"),
            std::string::npos);
  EXPECT_NE(error(R"("bogus": 1)").find("ptz.bogus"), std::string::npos);
  EXPECT_EQ(
      error(
          R"("presets": [{"name": "a", "pan_deg": 10}], "tour": [{"preset": "a", "dwell_s": 2}])"),
      "no error");
}

}  // namespace
}  // namespace pandora
