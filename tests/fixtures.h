#pragma once
// Shared synthetic test fixtures: cameras aimed with LookAt, a ring rig, a box room. Use these
// instead of a camera helper per *_test.cpp; a test that needs something special (an off-centre
// principal point, distortion) sets the fields of what these return.

#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/geometry.h"
#include "analysis/geometry/primitives.h"
#include "analysis/scene/scene.h"
#include "analysis/util/units.h"

namespace pandora::testing {

/// +Z, or +Y when the view from `position` to `target` is within about 8 degrees of vertical
/// (where +Z is nearly parallel to it and LookAt would fail or turn the image arbitrarily).
inline Vec3 DefaultUp(const Vec3& position, const Vec3& target) {
  return std::abs((target - position).normalized().z()) > 0.99 ? Vec3(0, 1, 0) : Vec3(0, 0, 1);
}

/// A camera at `position` looking at `target` with `up` up (zero: DefaultUp), `width` x `height`
/// pixels with the principal point at the image centre ((w - 1) / 2, (h - 1) / 2), focal length
/// from the horizontal field of view `hfov_deg` for `lens` (FocalFromHfov), no distortion
/// coefficients, working range [0, inf), enabled, the study's pixel sigma. Throws
/// std::bad_optional_access when LookAt fails.
inline Camera TestCamera(const std::string& id, const Vec3& position, const Vec3& target,
                         double hfov_deg = 60, int width = 640, int height = 480,
                         LensModel lens = LensModel::kPinhole, const Vec3& up = Vec3::Zero()) {
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.model = lens;
  k.fx = k.fy = FocalFromHfov(hfov_deg * kPi / 180.0, width, lens);
  k.cx = (width - 1) / 2.0;
  k.cy = (height - 1) / 2.0;
  Camera camera;
  camera.id = id;
  camera.name = id;
  camera.model = CameraModel(k);
  camera.world_from_camera =
      LookAt(position, target, up.isZero() ? DefaultUp(position, target) : up).value();
  return camera;
}

/// `camera` with its intrinsics changed by `edit` (a callable taking Intrinsics&), e.g. to add
/// distortion coefficients or move the principal point.
template <class Edit>
Camera WithIntrinsics(Camera camera, Edit&& edit) {
  Intrinsics k = camera.model.intrinsics();
  edit(k);
  camera.model = CameraModel(k);
  return camera;
}

/// `n` cameras "c0" ... on a horizontal circle of `radius` around `centre` (camera i at angle
/// 2 pi i / n from +X, counter-clockwise seen from above) at height centre.z() + `height`, each
/// looking at `centre`.
inline Rig RingRig(int n, double radius, double height, const Vec3& centre = Vec3::Zero(),
                   double hfov_deg = 60, int width = 640, int height_px = 480,
                   const std::string& name = "ring") {
  Rig rig;
  rig.name = name;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    const Vec3 position = centre + Vec3(radius * std::cos(a), radius * std::sin(a), height);
    rig.cameras.push_back(
        TestCamera("c" + std::to_string(i), position, centre, hfov_deg, width, height_px));
  }
  return rig;
}

/// A scene object made of `mesh` moved by `offset` (world frame).
inline SceneObject TestObject(const std::string& name, TriangleMesh mesh,
                              const Vec3& offset = Vec3::Zero(), bool solid = false) {
  for (Vec3& v : mesh.vertices) v += offset;
  SceneObject object;
  object.name = name;
  object.source = "test";
  object.mesh = std::move(mesh);
  object.solid = solid;
  return object;
}

/// A room of `size` (x, y, z metres) with its floor centred on the origin at z = 0: a floor plane
/// (normal +z) and four walls facing inward, no ceiling, so cameras above see in. The study region
/// is the box `region_min` .. `region_max` (default: the middle of the room, 1 m wide, 0 to 1 m
/// high) at `voxel_size`; no rig (add one, e.g. RingRig).
inline Scene BoxRoom(const Vec3& size = Vec3(4, 4, 2.5), double voxel_size = 0.1,
                     const Vec3& region_min = Vec3(-0.5, -0.5, 0),
                     const Vec3& region_max = Vec3(0.5, 0.5, 1)) {
  Scene scene;
  scene.path = "box_room.json";
  scene.objects.push_back(TestObject("floor", MakePlane(Vec2(size.x(), size.y()))));
  // Walls: the plane (normal +z) turned to face the room's centre.
  struct Wall {
    const char* name;
    Vec3 normal;
    double half;  // distance from the centre
    Vec2 extent;  // along the wall, and up
  };
  const Wall walls[] = {{"wall_east", Vec3(-1, 0, 0), size.x() / 2, Vec2(size.y(), size.z())},
                        {"wall_west", Vec3(1, 0, 0), size.x() / 2, Vec2(size.y(), size.z())},
                        {"wall_north", Vec3(0, -1, 0), size.y() / 2, Vec2(size.x(), size.z())},
                        {"wall_south", Vec3(0, 1, 0), size.y() / 2, Vec2(size.x(), size.z())}};
  for (const Wall& w : walls) {
    TriangleMesh mesh = MakePlane(w.extent);
    // The plane's x along the wall, its y up, its normal +z onto the wall's inward normal.
    const Vec3 along = Vec3::UnitZ().cross(w.normal);
    Mat3 R;
    R.col(0) = along;
    R.col(1) = Vec3::UnitZ();
    R.col(2) = w.normal;
    for (Vec3& v : mesh.vertices) v = R * v;
    scene.objects.push_back(
        TestObject(w.name, std::move(mesh), -w.half * w.normal + Vec3(0, 0, size.z() / 2)));
  }
  scene.study.region.kind = Region::Kind::kBox;
  scene.study.region.box.min = region_min;
  scene.study.region.box.max = region_max;
  scene.study.voxel_size = voxel_size;
  return scene;
}

}  // namespace pandora::testing
