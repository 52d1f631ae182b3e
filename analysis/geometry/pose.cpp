// The Euler-angle convention of camera orientations (analysis/geometry/pose.h).
#include "analysis/geometry/pose.h"

#include <algorithm>
#include <cmath>

#include "analysis/util/units.h"

namespace pandora {
namespace {}  // namespace

Mat3 EulerBaseRotation() {
  Mat3 b;
  b.col(0) = Vec3(0, -1, 0);
  b.col(1) = Vec3(0, 0, -1);
  b.col(2) = Vec3(1, 0, 0);
  return b;
}

Mat3 RotationFromYawPitchRoll(double yaw, double pitch, double roll) {
  const Mat3 M = (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(-pitch, Vec3::UnitY()) *
                  Eigen::AngleAxisd(roll, Vec3::UnitX()))
                     .toRotationMatrix();
  return M * EulerBaseRotation();
}

Mat3 RotationFromYawPitchRollDeg(const Vec3& ypr) {
  return RotationFromYawPitchRoll(Rad(ypr.x()), Rad(ypr.y()), Rad(ypr.z()));
}

Vec3 YawPitchRollDeg(const Mat3& R) {
  const Mat3 M = R * EulerBaseRotation().transpose();  // Rz(yaw) Ry(b) Rx(roll), b = -pitch
  const double sb = std::clamp(-M(2, 0), -1.0, 1.0);
  const double b = std::asin(sb);
  double yaw, roll;
  if (std::abs(sb) > 1.0 - 1e-12) {  // gimbal lock: roll folded into yaw
    roll = 0;
    yaw = std::atan2(-M(0, 1), M(1, 1));
  } else {
    yaw = std::atan2(M(1, 0), M(0, 0));
    roll = std::atan2(M(2, 1), M(2, 2));
  }
  return Vec3(Deg(yaw), Deg(-b), Deg(roll));
}

}  // namespace pandora
