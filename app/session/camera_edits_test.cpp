// The session's camera edits (app/session/camera_edits.h): the PTZ rule for every front end, and
// the typed edits' checks.
#include "app/session/camera_edits.h"

#include <gtest/gtest.h>

#include <cmath>

#include "analysis/geometry/camera.h"
#include "analysis/scene/ptz.h"
#include "analysis/util/error.h"
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

}  // namespace
}  // namespace pandora::session
