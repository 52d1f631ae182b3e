// The Euler-angle convention (analysis/geometry/pose.h): its base, the sense of each angle, the
// round trip, the gimbal lock, and the scene loader's "euler_deg" giving the very same rotation.
#include "analysis/geometry/pose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "analysis/geometry/camera.h"
#include "analysis/scene/scene.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

TEST(Euler, BaseLooksAlongPlusXWithImageRightMinusYAndDownMinusZ) {
  const Mat3 base = RotationFromYawPitchRollDeg(Vec3::Zero());
  EXPECT_EQ(base, EulerBaseRotation());
  EXPECT_EQ(base.col(0), Vec3(0, -1, 0));
  EXPECT_EQ(base.col(1), Vec3(0, 0, -1));
  EXPECT_EQ(base.col(2), Vec3(1, 0, 0));
  EXPECT_NEAR(base.determinant(), 1.0, 1e-15);
  // The same as LookAt along +X with Z up.
  EXPECT_TRUE(base.isApprox(LookAt(Vec3::Zero(), Vec3(5, 0, 0), Vec3::UnitZ())->linear(), 1e-15));
}

TEST(Euler, EachAngleTurnsTheWayTheSceneFormatSays) {
  // Yaw 90: looks along +Y. Pitch 30: the optical axis rises 30 degrees. Roll 90: image right
  // points down.
  EXPECT_TRUE(RotationFromYawPitchRollDeg(Vec3(90, 0, 0)).col(2).isApprox(Vec3(0, 1, 0), 1e-12));
  EXPECT_TRUE(RotationFromYawPitchRollDeg(Vec3(0, 30, 0))
                  .col(2)
                  .isApprox(Vec3(std::cos(kPi / 6), 0, std::sin(kPi / 6)), 1e-12));
  EXPECT_TRUE(RotationFromYawPitchRollDeg(Vec3(0, 0, 90)).col(0).isApprox(Vec3(0, 0, -1), 1e-12));
  EXPECT_GT(RotationFromYawPitchRollDeg(Vec3(10, 0, 0)).col(2).y(), 0.1);
  EXPECT_GT(RotationFromYawPitchRollDeg(Vec3(0, 10, 0)).col(2).z(), 0.1);
}

TEST(Euler, RoundTrip) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-170, 170), p(-85, 85);
  for (int i = 0; i < 200; ++i) {
    const Vec3 ypr(u(rng), p(rng), u(rng));
    const Mat3 R = RotationFromYawPitchRollDeg(ypr);
    EXPECT_NEAR((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff(), 0, 4e-15);
    EXPECT_TRUE(YawPitchRollDeg(R).isApprox(ypr, 1e-9)) << ypr.transpose();
    EXPECT_TRUE(RotationFromYawPitchRollDeg(YawPitchRollDeg(R)).isApprox(R, 1e-12));
  }
}

TEST(Euler, GimbalLockFoldsRollIntoYaw) {
  // Looking straight up: yaw and roll turn about the same axis; the angles come back with roll 0
  // and give the same rotation.
  const Mat3 R = RotationFromYawPitchRollDeg(Vec3(30, 90, 20));
  const Vec3 ypr = YawPitchRollDeg(R);
  EXPECT_NEAR(ypr.y(), 90, 1e-6);
  EXPECT_EQ(ypr.z(), 0);
  EXPECT_TRUE(RotationFromYawPitchRollDeg(ypr).isApprox(R, 1e-6));
}

TEST(Euler, SceneLoaderUsesThisConvention) {
  const std::string text = R"({
    "rigs": [{"name": "main", "cameras": [
      {"id": "c0", "position": [0, 0, 1], "euler_deg": {"yaw": 33, "pitch": -21, "roll": 4},
       "resolution": [640, 480], "hfov_deg": 60}
    ]}],
    "study": {"region": {"box": {"min": [-1, -1, 0], "max": [1, 1, 2]}}}
  })";
  const Scene scene = ParseScene(text, "pose_test.json");
  const Mat3 loaded = scene.rigs[0].cameras[0].world_from_camera.linear();
  // Bit for bit the radians form with the loader's degree (pi / 180).
  const double degree = kPi / 180.0;
  EXPECT_EQ(loaded, RotationFromYawPitchRoll(33 * degree, -21 * degree, 4 * degree));
  EXPECT_TRUE(loaded.isApprox(RotationFromYawPitchRollDeg(Vec3(33, -21, 4)), 1e-15));
  EXPECT_TRUE(YawPitchRollDeg(loaded).isApprox(Vec3(33, -21, 4), 1e-12));
}

}  // namespace
}  // namespace pandora
