#pragma once
// Scenes the GPU renderer is measured on besides the examples (viewer test and bench): a room
// lit by distorted cameras of every lens model the shaders implement.

#include <cmath>
#include <string>

#include "analysis/geometry/primitives.h"
#include "analysis/util/palette.h"
#include "analysis/util/units.h"
#include "tests/fixtures.h"

namespace pandora::testing {

/// A 6 x 6 x 3 m box room (BoxRoom) with a box, a sphere and a post for shadows, lit by rig
/// "lenses": two strong Brown-Conrady cameras with tangential terms and k3 (one perspective map
/// each), a 100-degree fisheye (field ~60 degrees off axis: one perspective map), two
/// 160-degree fisheyes (a cube of maps) and a 220-degree fisheye on the ceiling looking down (a
/// cube including the face behind it). View "room": from a corner, looking at the middle.
inline Scene LensRoom() {
  Scene scene = BoxRoom(Vec3(6, 6, 3));
  scene.path = "lens_room";
  scene.materials.push_back(Material{"grey", Vec3(0.7, 0.7, 0.7), "", nullptr});
  scene.materials.push_back(Material{"warm", Vec3(0.8, 0.6, 0.4), "", nullptr});
  for (SceneObject& o : scene.objects) o.material = 0;
  SceneObject box = TestObject("box", MakeBox(Vec3(0.8, 0.6, 1.0)), Vec3(0.3, -0.2, 0.5), true);
  box.material = 1;
  SceneObject ball = TestObject("ball", MakeSphere(0.35, 32), Vec3(-0.9, 0.6, 0.9), true);
  ball.material = 1;
  SceneObject post = TestObject("post", MakeCylinder(0.08, 2.0, 16), Vec3(1.2, 1.3, 1.0), true);
  scene.objects.push_back(box);
  scene.objects.push_back(ball);
  scene.objects.push_back(post);

  Rig rig;
  rig.name = "lenses";
  const Vec3 middle(0, 0, 0.6);
  auto add = [&](Camera c) {
    c.color = CameraPaletteColor(int(rig.cameras.size()));
    rig.cameras.push_back(c);
  };
  add(WithIntrinsics(
      TestCamera("bc1", Vec3(2.7, -2.6, 2.6), middle, 75, 1280, 960, LensModel::kBrownConrady),
      [](Intrinsics& k) {
        k.k1 = -0.32;
        k.k2 = 0.09;
        k.k3 = -0.01;
        k.p1 = 0.002;
        k.p2 = -0.003;
        k.cx += 20;
      }));
  add(WithIntrinsics(
      TestCamera("bc2", Vec3(-2.7, 2.6, 2.2), middle, 70, 1024, 768, LensModel::kBrownConrady),
      [](Intrinsics& k) {
        k.k1 = 0.12;
        k.k2 = -0.05;
        k.p1 = -0.004;
      }));
  add(WithIntrinsics(
      TestCamera("fe100", Vec3(-2.8, -2.7, 2.5), middle, 100, 1024, 768, LensModel::kFisheye),
      [](Intrinsics& k) {
        k.k1 = -0.02;
        k.k2 = 0.004;
      }));
  add(WithIntrinsics(
      TestCamera("fe160a", Vec3(2.8, 2.0, 2.0), middle, 160, 1280, 1024, LensModel::kFisheye),
      [](Intrinsics& k) {
        k.k1 = 0.03;
        k.k2 = -0.01;
        k.k3 = 0.001;
      }));
  add(TestCamera("fe160b", Vec3(0.0, -2.85, 1.2), Vec3(0, 0, 1.0), 160, 1280, 1024,
                 LensModel::kFisheye));
  add(WithIntrinsics(TestCamera("fe220", Vec3(0.4, 0.3, 2.9), Vec3(0.4, 0.3, 0.0), 220, 1024, 1024,
                                LensModel::kFisheye, Vec3(0, 1, 0)),
                     [](Intrinsics& k) { k.k1 = 0.01; }));
  for (Camera& c : rig.cameras) c.far = 12.0;
  rig.cameras[0].near = 0.3;
  scene.rigs.push_back(rig);
  View view;
  view.from = Vec3(-2.6, -2.2, 2.7);
  view.at = Vec3(0.3, 0.4, 0.5);
  view.fov_deg = 80;
  scene.views["room"] = view;
  return scene;
}

/// `rig` grown to `n` cameras, for rigs of hundreds of cameras (the GPU bench's 200-camera case):
/// camera c is the rig's camera c % m (m cameras) turned about the vertical through `centre` by
/// (c / m) golden angles (137.5 degrees: no copy coincides with another), id "<id>_<c / m>" for
/// the copies, colours from the palette by index.
inline Rig TurnedCopies(const Rig& rig, int n, const Vec3& centre) {
  Rig out = rig;
  out.cameras.clear();
  const int m = int(rig.cameras.size());
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int c = 0; m > 0 && c < n; ++c) {
    Camera cam = rig.cameras[std::size_t(c % m)];
    const int copy = c / m;
    if (copy > 0) {
      const Eigen::Isometry3d turn = Eigen::Translation3d(centre) *
                                     Eigen::AngleAxisd(copy * golden, Vec3::UnitZ()) *
                                     Eigen::Translation3d(-centre);
      cam.world_from_camera = turn * cam.world_from_camera;
      cam.id += "_" + std::to_string(copy);
      cam.name = cam.id;
    }
    cam.color = CameraPaletteColor(c);
    out.cameras.push_back(cam);
  }
  return out;
}

}  // namespace pandora::testing
