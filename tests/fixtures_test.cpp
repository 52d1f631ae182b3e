// The shared test fixtures (tests/fixtures.h) are what they say: cameras aimed where asked, a ring
// of cameras around its centre, a box room whose walls face inward.
#include "tests/fixtures.h"

#include <gtest/gtest.h>

#include "analysis/geometry/ray_caster.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

TEST(Fixtures, TestCameraLooksAtItsTargetThroughThePrincipalPoint) {
  const Camera c = testing::TestCamera("a", Vec3(3, 1, 2), Vec3(0, 0, 0.5), 70, 800, 600);
  EXPECT_EQ(c.id, "a");
  const auto px = c.Project(Vec3(0, 0, 0.5));
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x(), 399.5, 1e-9);
  EXPECT_NEAR(px->y(), 299.5, 1e-9);
  EXPECT_NEAR(c.model.intrinsics().fx, 400.0 / std::tan(35 * kPi / 180), 1e-9);
  // Straight down: DefaultUp switches to +Y, LookAt succeeds.
  const Camera down = testing::TestCamera("d", Vec3(0, 0, 3), Vec3(0, 0, 0));
  EXPECT_TRUE(down.world_from_camera.linear().col(2).isApprox(Vec3(0, 0, -1)));
}

TEST(Fixtures, RingRigSurroundsItsCentre) {
  const Vec3 centre(1, 2, 0.5);
  const Rig rig = testing::RingRig(6, 3.0, 1.0, centre);
  ASSERT_EQ(rig.cameras.size(), 6u);
  for (int i = 0; i < 6; ++i) {
    const Camera& c = rig.cameras[i];
    EXPECT_EQ(c.id, "c" + std::to_string(i));
    EXPECT_NEAR(c.center().z(), 1.5, 1e-12);
    EXPECT_NEAR((c.center() - centre).head<2>().norm(), 3.0, 1e-12);
    const auto px = c.Project(centre);
    ASSERT_TRUE(px);
    EXPECT_NEAR(px->x(), 319.5, 1e-9);
    EXPECT_NEAR(px->y(), 239.5, 1e-9);
  }
  EXPECT_NEAR(rig.cameras[0].center().x(), 4.0, 1e-12);  // camera 0 on the +X side
}

TEST(Fixtures, BoxRoomWallsFaceInward) {
  const Scene room = testing::BoxRoom(Vec3(4, 6, 2.5));
  ASSERT_EQ(room.objects.size(), 5u);
  const auto caster = MakeBruteForceRayCaster(room.AllTriangles());
  const Vec3 centre(0, 0, 1);
  for (const Vec3& d :
       {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, -1)}) {
    const auto hit = caster->Intersect({centre, d, 0, 100});
    ASSERT_TRUE(hit) << d.transpose();
    EXPECT_NEAR(hit->t, d.z() < 0 ? 1.0 : (d.x() != 0 ? 2.0 : 3.0), 1e-12) << d.transpose();
    EXPECT_LT(hit->normal.dot(d), -0.999) << d.transpose();  // front face toward the centre
  }
  EXPECT_FALSE(caster->Intersect({centre, Vec3(0, 0, 1), 0, 100}));  // no ceiling
  EXPECT_EQ(room.study.region.box.min, Vec3(-0.5, -0.5, 0));
}

}  // namespace
}  // namespace pandora
