// Plan and elevation views (issue 14 point 5): the plan frames the bounds at the stated scale and
// is orthographic to 1 / kPlanDistance (a point's pixel does not depend on its height beyond
// that); primary rays start on the cut plane, so a ceiling above the cut does not hide the lit
// floor; the camera labels are drawn beside the cameras only.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "render/render.h"
#include "render/test_options.h"

namespace pandora {
namespace {

// A 6 x 4 m room: a floor, a ceiling slab at 2.9-3 m, one camera 2.5 m up looking straight down.
Scene Room() {
  return ParseScene(R"({"pandora": 1, "objects": [
      {"name": "floor", "box": {"size": [6, 4, 0.1]}, "position": [0, 0, -0.05]},
      {"name": "ceiling", "box": {"size": [6, 4, 0.1]}, "position": [0, 0, 2.95]}],
    "rigs": [{"name": "r", "cameras": [{"id": "down", "position": [0.5, 0.2, 2.5], "look_at": [0.5, 0.2, 0],
      "up": [0, 1, 0], "resolution": [320, 240], "hfov_deg": 90}]}],
    "study": {"region": {"box": {"min": [-3, -2, 0], "max": [3, 2, 2.2]}}, "voxel_size": 0.5}})",
                    "room.json");
}

// Where the ray through pixel (x, y) meets the plane z = h.
Vec3 OnPlaneZ(const Rig& rig, const RenderView& v, double x, double y, double h) {
  const Ray r = *PixelRay(rig, v, x, y);
  return r.origin + (h - r.origin.z()) / r.direction.z() * r.direction;
}

TEST(PlanView, FramesTheBoundsAtItsScaleAndIsOrthographic) {
  const Scene scene = Room();
  const Aabb bounds = scene.ContentBounds();
  double mpp = 0;
  const RenderView v = *PlanView(bounds, "plan", 600, 400, std::nan(""), &mpp);
  // 6 x 4.1 m (the slabs' 4 m plus nothing wider) into 600 x 400: the width decides, 5 % margin.
  const double half = 1.05 * std::max(0.5 * bounds.size().x(), 0.5 * bounds.size().y() * 600 / 400);
  EXPECT_NEAR(mpp, 2 * half / 600, 1e-12);
  const Vec3 c = bounds.center();
  for (double h : {0.0, 1.5, 3.0})
    for (const auto& [x, y] : {std::pair{0.0, 0.0}, {599.0, 0.0}, {300.0, 399.0}, {17.0, 211.0}}) {
      const Vec3 X = OnPlaneZ(scene.rigs[0], v, x, y, h);
      // Image x is +x, image down is -y (north up), the same at every height to 1 / 500 of the
      // offset from the centre.
      const double ex = c.x() + (x - 299.5) * mpp, ey = c.y() - (y - 199.5) * mpp;
      EXPECT_NEAR(X.x(), ex, 2.0 / kPlanDistance * std::abs(X.x() - c.x()) + 1e-9) << h;
      EXPECT_NEAR(X.y(), ey, 2.0 / kPlanDistance * std::abs(X.y() - c.y()) + 1e-9) << h;
    }
  // Elevations look along their axis with +z up.
  const Ray south =
      *PixelRay(scene.rigs[0], *PlanView(bounds, "south", 600, 400, std::nan("")), 299.5, 199.5);
  EXPECT_NEAR(south.direction.y(), 1.0, 1e-12);
  const Ray west =
      *PixelRay(scene.rigs[0], *PlanView(bounds, "west", 600, 400, std::nan("")), 299.5, 0);
  EXPECT_GT(west.direction.x(), 0.99);
  EXPECT_GT(west.direction.z(), 0.0);  // the top row looks up: +z is up
  EXPECT_FALSE(PlanView(bounds, "up", 600, 400, 0.0));
}

TEST(PlanView, RaysStartOnTheCutSoTheCeilingDoesNotHideTheFloor) {
  const Scene scene = Room();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Rig& rig = scene.rigs[0];
  const Aabb bounds = scene.ContentBounds();
  const RenderView cut = *PlanView(bounds, "plan", 300, 200, 2.2);
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {150.0, 100.0}, {299.0, 199.0}}) {
    const Ray r = *PixelRay(rig, cut, x, y);
    EXPECT_NEAR((r.origin + r.t_near * r.direction).z(), 2.2, 1e-6);
  }
  RenderOptions o = LightOnlyOptions();
  o.brightness = 1.0;
  // The camera's footprint on the floor around (0.5, 0.2): lit through the cut, hidden by the
  // ceiling's top without it.
  const Image a = Render(scene, rig, *caster, cut, o);
  const Image b = Render(scene, rig, *caster, *PlanView(bounds, "plan", 300, 200, std::nan("")), o);
  int lit_a = 0, lit_b = 0;
  for (std::size_t i = 0; i < a.coverage.size(); ++i) {
    lit_a += a.coverage[i] > 0;
    lit_b += b.coverage[i] > 0;
  }
  // The 90 deg camera 2.5 m up lights a 5 x 3.75 m patch, clipped by the 6 x 4 m floor to 5 x 3.75:
  // about 18.75 / (6.3 x 4.2) of the frame.
  const double expected =
      5.0 * 3.75 / (2 * 1.05 * 3.0 * 2 * 1.05 * 3.0 * 200 / 300) * a.coverage.size();
  EXPECT_NEAR(lit_a, expected, 0.03 * expected);
  EXPECT_EQ(lit_b, 0);
}

TEST(PlanView, LabelsAreDrawnBesideTheCamerasOnly) {
  const Scene scene = Room();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Rig& rig = scene.rigs[0];
  const RenderView v = *PlanView(scene.ContentBounds(), "plan", 600, 400, 2.2);
  RenderOptions o;
  o.overlays.key = false;
  const Image plain = Render(scene, rig, *caster, v, o);
  o.overlays.labels = true;
  const Image labelled = Render(scene, rig, *caster, v, o);
  // The camera's pixel: (0.5, 0.2) on the plan.
  double mpp = 0;
  PlanView(scene.ContentBounds(), "plan", 600, 400, 2.2, &mpp);
  const Vec3 c = scene.ContentBounds().center();
  const double px = 299.5 + (0.5 - c.x()) / mpp, py = 199.5 - (0.2 - c.y()) / mpp;
  int changed = 0, far = 0;
  for (int y = 0; y < 400; ++y)
    for (int x = 0; x < 600; ++x) {
      const std::size_t i = 3 * (std::size_t(y) * 600 + x);
      if (plain.rgb[i] == labelled.rgb[i] && plain.rgb[i + 1] == labelled.rgb[i + 1] &&
          plain.rgb[i + 2] == labelled.rgb[i + 2])
        continue;
      ++changed;
      far += std::abs(y - py) > 20 || x < px - 5 || x > px + 120;
    }
  EXPECT_GT(changed, 50);
  EXPECT_EQ(far, 0);
}

}  // namespace
}  // namespace pandora
