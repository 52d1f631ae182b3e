// The session's camera edits (app/session/camera_edits.h): the PTZ rule for every front end, and
// the typed edits' checks.
#include "app/session/camera_edits.h"

#include <gtest/gtest.h>

#include <cmath>

#include "analysis/geometry/camera.h"
#include "analysis/scene/ptz.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "app/session/study.h"

namespace pandora::session {
namespace {

Vec3 Axis(const Camera& cam) { return cam.world_from_camera.linear().col(2); }

TEST(CameraEdits, AimedPtzCameraTurnsItsHeadToFaceTheTarget) {
  const auto study = Study::Load("tests/data/ptz_min.json");
  const Rig& rig = study->scene().rigs[0];
  ASSERT_TRUE(rig.cameras[0].ptz);
  // Within the head's ranges (tilt -60..20 from home): the centre moves (no offset), the optical
  // axis faces the target exactly, no roll, nothing clamped.
  const Vec3 position(0.5, -1.5, 2.5), target(1.5, 1.0, 1.2);
  const CameraEditResult r = MakeEdit(rig, AimEdit{0, position, target, Vec3::UnitZ()});
  ASSERT_EQ(r.edit.changes.size(), 1u);
  const Camera& after = r.edit.changes[0].after;
  EXPECT_EQ(r.edit.label, "move dome");
  EXPECT_EQ(r.ptz_camera, 0);
  EXPECT_FALSE(r.clamped);
  EXPECT_LT((after.center() - position).norm(), 1e-12);
  EXPECT_LT((Axis(after) - (target - position).normalized()).norm(), 1e-9);
  // The image's x axis stays level: a PTZ head has no roll.
  EXPECT_LT(std::abs(after.world_from_camera.linear().col(0).z()), 1e-9);
}

TEST(CameraEdits, PtzCameraAskedBeyondItsTiltRangeStopsAtIt) {
  const auto study = Study::Load("tests/data/ptz_min.json");
  const Rig& rig = study->scene().rigs[0];
  const Camera& home = rig.cameras[0];
  // Straight down is beyond tilt -60 from home: clamped, the head at the end of its range.
  const CameraEditResult r =
      MakeEdit(rig, AimEdit{0, home.center(), home.center() - Vec3(0, 0.01, 3)});
  EXPECT_TRUE(r.clamped);
  const Camera& after = r.edit.changes[0].after;
  EXPECT_NEAR(after.ptz->current.tilt_deg, -60.0, 1e-9);
  EXPECT_GT(Axis(after).z(), -0.999);  // not straight down
}

TEST(CameraEdits, FixedCameraTakesThePoseAsGiven) {
  const auto study = Study::Load("tests/data/minimal.json");
  const Rig& rig = study->scene().rigs[0];
  Mat3 rotation;
  rotation << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical axis +x, image x -y, image y -z
  const CameraEditResult r = MakeEdit(rig, PoseEdit{0, Vec3(0.1, 0.2, 0.3), rotation});
  EXPECT_EQ(r.ptz_camera, -1);
  const Camera& after = r.edit.changes[0].after;
  EXPECT_EQ(after.world_from_camera.linear(), rotation);
  EXPECT_EQ(after.center(), Vec3(0.1, 0.2, 0.3));
}

TEST(CameraEdits, TypedEditsNameTheFieldAtFault) {
  const auto study = Study::Load("tests/data/minimal.json");
  const Rig& rig = study->scene().rigs[0];
  auto file_of = [](auto&& make) {
    try {
      make();
    } catch (const InputError& e) {
      return e.file();
    }
    return std::string("no error");
  };
  const double nan = std::nan("");
  EXPECT_EQ(file_of([&] {
              MakeEdit(rig, AimEdit{0, Vec3(nan, 0, 0), Vec3::Zero()});
            }),
            "{position}");
  EXPECT_EQ(file_of([&] { MakeEdit(rig, AimEdit{0, Vec3(1, 1, 1), Vec3(1, 1, 1)}); }), "{look_at}");
  EXPECT_EQ(file_of([&] {
              MakeEdit(rig, PoseEdit{0, Vec3::Zero(), 2 * Mat3::Identity()});
            }),
            "{rotation}");
  Mat3 mirror = Mat3::Identity();
  mirror(2, 2) = -1;
  EXPECT_EQ(file_of([&] { MakeEdit(rig, PoseEdit{0, Vec3::Zero(), mirror}); }), "{rotation}");
}

// The file part of the InputError `make` throws ("{field}", "" for a camera's problem).
template <class Make>
std::string FileOf(Make make) {
  try {
    make();
  } catch (const InputError& e) {
    return e.file();
  }
  return "no error";
}

TEST(CameraEdits, ZoomAndLensFollowTheirClosedForms) {
  const auto study = Study::Load("tests/data/minimal.json");
  const Rig& rig = study->scene().rigs[0];
  const Intrinsics k0 = rig.cameras[0].model.intrinsics();  // 640 x 480, hfov 60
  // Zoom: fx = (w / 2) / tan(hfov / 2), fy / fx kept.
  const Camera zoomed = MakeEdit(rig, ZoomEdit{{0, 1}, 90}).edit.changes[1].after;
  EXPECT_NEAR(zoomed.model.intrinsics().fx, 320.0, 1e-9);
  EXPECT_NEAR(zoomed.model.intrinsics().fy / zoomed.model.intrinsics().fx, k0.fy / k0.fx, 1e-15);
  EXPECT_EQ(MakeEdit(rig, ZoomEdit{{0, 1}, 90}).edit.label, "zoom 2 cameras");
  // Half the resolution: the same rays through the image's edges (pixel edge -0.5 maps to -0.5).
  LensEdit half;
  half.cameras = {0};
  half.width = 320;
  half.height = 240;
  const Intrinsics k1 = MakeEdit(rig, half).edit.changes[0].after.model.intrinsics();
  EXPECT_NEAR(k1.fx, k0.fx / 2, 1e-12);
  EXPECT_NEAR((-0.5 - k1.cx) / k1.fx, (-0.5 - k0.cx) / k0.fx, 1e-15);
  EXPECT_NEAR((k1.width - 0.5 - k1.cx) / k1.fx, (k0.width - 0.5 - k0.cx) / k0.fx, 1e-15);
  // Pinhole to fisheye keeps the nominal field of view: fx = (w / 2) / (hfov / 2).
  LensEdit fisheye;
  fisheye.cameras = {0};
  fisheye.model = LensModel::kFisheye;
  fisheye.coefficients[0] = 0.01;
  const Intrinsics k2 = MakeEdit(rig, fisheye).edit.changes[0].after.model.intrinsics();
  EXPECT_NEAR(k2.fx, 320.0 / (kPi / 6), 1e-9);
  EXPECT_EQ(k2.k1, 0.01);
}

TEST(CameraEdits, RangeColourAndOrientCheckTheirValues) {
  const auto study = Study::Load("tests/data/minimal.json");
  const Rig& rig = study->scene().rigs[0];
  const Camera ranged = MakeEdit(rig, RangeEdit{{0}, 0.5, INFINITY}).edit.changes[0].after;
  EXPECT_EQ(ranged.near, 0.5);
  EXPECT_EQ(ranged.far, INFINITY);
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, RangeEdit{{0}, 2.0, 1.0}); }), "{far}");
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, RangeEdit{{0}, -1.0, NAN}); }), "{near}");
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, ColorEdit{{0}, Vec3(1.5, 0, 0)}); }), "{color}");
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, OrientEdit{0, Vec3(0, 91, 0)}); }), "{ypr_deg}");
  // Yaw 90: the base looks along +x, yaw turns it left, to +y.
  const Camera turned = MakeEdit(rig, OrientEdit{0, Vec3(90, 0, 0)}).edit.changes[0].after;
  EXPECT_LT((Axis(turned) - Vec3::UnitY()).norm(), 1e-12);
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, ZoomEdit{{0}, 180}); }), "{hfov_deg}");
  LensEdit pinhole_k4;
  pinhole_k4.cameras = {0};
  pinhole_k4.coefficients[5] = 0.1;
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, pinhole_k4); }), "{k4}");
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, LensEdit{{0}}); }), "");  // nothing to change
}

TEST(CameraEdits, PtzEditClampsToTheHeadAndRefusesWhatTheLensCannotSee) {
  const auto study = Study::Load("tests/data/ptz_min.json");
  const Rig& rig = study->scene().rigs[0];
  // Tilt -500 is beyond the range: clamped and said so.
  const CameraEditResult r = MakeEdit(rig, PtzEdit{0, "", 10, -500, NAN});
  EXPECT_TRUE(r.clamped);
  EXPECT_EQ(r.ptz_camera, 0);
  const PtzHead& head = *r.edit.changes[0].after.ptz;
  EXPECT_NEAR(head.current.tilt_deg, head.tilt_min_deg, 1e-9);
  EXPECT_NEAR(head.current.pan_deg, 10, 1e-9);
  // A pinhole dome cannot see 200 degrees: refused, not a negative focal length clamped.
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, PtzEdit{0, "", NAN, NAN, 200}); }), "{hfov_deg}");
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, PtzEdit{0, "nowhere"}); }), "{preset}");
  // Its lens and resolution are the head's zoom range's units: refused as the camera's problem.
  LensEdit resize;
  resize.cameras = {0};
  resize.width = 320;
  resize.height = 180;
  EXPECT_EQ(FileOf([&] { MakeEdit(rig, resize); }), "");
  // A fixed camera has no head.
  const auto fixed = Study::Load("tests/data/minimal.json");
  EXPECT_EQ(FileOf([&] { MakeEdit(fixed->scene().rigs[0], PtzEdit{0, "", 1}); }), "");
}

}  // namespace
}  // namespace pandora::session
