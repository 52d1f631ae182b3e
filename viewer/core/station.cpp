#include "viewer/core/station.h"

#include <cmath>

#include "analysis/util/units.h"

namespace pandora::viewer {

std::array<Vec3, 4> DisplayCorners(const ViewingStation& s) {
  // Right as the viewer (looking along -normal, up `display_up`) sees it.
  const Vec3 right = s.display_up.cross(s.display_normal);
  const Vec3 h = 0.5 * s.display_width * right, v = 0.5 * s.display_height * s.display_up;
  return {s.display_center - h + v, s.display_center + h + v, s.display_center + h - v,
          s.display_center - h - v};
}

Camera DisplayCamera(const ViewingStation& s) {
  // Camera frame: z = -normal (through the display), y = -up (image rows down), x = y cross z.
  Mat3 R;
  R.col(2) = -s.display_normal;
  R.col(1) = -s.display_up;
  R.col(0) = R.col(1).cross(R.col(2));
  Camera cam;
  cam.id = cam.name = "display";
  cam.enabled = false;
  cam.world_from_camera.linear() = R;
  cam.world_from_camera.translation() = s.eye;
  // The display's top-left corner in the camera frame, at depth d.
  const Vec3 top_left = R.transpose() * (DisplayCorners(s)[0] - s.eye);
  const double d = top_left.z();
  Intrinsics k;
  k.width = s.pixels_wide;
  k.height = s.pixels_high;
  k.fx = s.pixels_wide * d / s.display_width;
  k.fy = s.pixels_high * d / s.display_height;
  // u = cx + fx x / z: the left edge (x = top_left.x) at -0.5, the top edge at -0.5.
  k.cx = -0.5 - k.fx * top_left.x() / d;
  k.cy = -0.5 - k.fy * top_left.y() / d;
  cam.model = CameraModel(k);
  return cam;
}

std::array<Vec3, 8> TrackerCorners(const ViewingStation& s) {
  std::array<Vec3, 8> out;
  const double tx = std::tan(0.5 * s.tracker_hfov_deg * kPi / 180.0);
  const double ty = std::tan(0.5 * s.tracker_vfov_deg * kPi / 180.0);
  const double signs[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};  // image y down: top first
  for (int plane = 0; plane < 2; ++plane) {
    const double z = plane == 0 ? s.tracker_near : s.tracker_far;
    for (int i = 0; i < 4; ++i)
      out[4 * plane + i] = s.tracker_pose * Vec3(signs[i][0] * tx * z, signs[i][1] * ty * z, z);
  }
  return out;
}

}  // namespace pandora::viewer
