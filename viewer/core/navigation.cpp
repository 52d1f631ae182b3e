#include "viewer/core/navigation.h"

#include <algorithm>
#include <cmath>

#include "analysis/util/units.h"

namespace pandora::viewer {
namespace {

constexpr double kOrbitDegPerPixel = 0.3;

double ClampPitch(double p) { return std::clamp(p, -89.0, 89.0); }
double ClampDistance(double d) { return std::clamp(d, 1e-3, 1e5); }

}  // namespace

Vec3 OrbitView::Eye() const {
  const double y = yaw_deg * kRadPerDeg, p = pitch_deg * kRadPerDeg;
  return target +
         distance * Vec3(std::cos(p) * std::cos(y), std::cos(p) * std::sin(y), std::sin(p));
}

Vec3 OrbitView::Forward() const { return (target - Eye()).normalized(); }
Vec3 OrbitView::Right() const { return Forward().cross(Vec3::UnitZ()).normalized(); }
Vec3 OrbitView::Up() const { return Right().cross(Forward()); }

RenderView OrbitView::ToRenderView(int width, int height) const {
  RenderView v;
  v.from = Eye();
  v.at = target;
  v.up = Vec3::UnitZ();
  v.fov_deg = fov_deg;
  v.width = width;
  v.height = height;
  return v;
}

void OrbitView::Orbit(double dx_px, double dy_px) {
  yaw_deg = std::remainder(yaw_deg - kOrbitDegPerPixel * dx_px, 360.0);
  pitch_deg = ClampPitch(pitch_deg + kOrbitDegPerPixel * dy_px);
}

void OrbitView::Pan(double dx_px, double dy_px, int width_px) {
  const double metres_per_px =
      2 * distance * std::tan(0.5 * fov_deg * kRadPerDeg) / std::max(width_px, 1);
  target += metres_per_px * (-dx_px * Right() + dy_px * Up());
}

void OrbitView::Dolly(double steps) { distance = ClampDistance(distance * std::pow(0.85, steps)); }

void OrbitView::Fly(double right, double up, double forward) {
  target += right * Right() + up * Vec3::UnitZ() + forward * Forward();
}

void OrbitView::Look(double dyaw_deg, double dpitch_deg) {
  // The eye stays; the target swings round it: the view from the target's side turns by 180.
  const Vec3 eye = Eye();
  const double yaw = yaw_deg + 180.0 + dyaw_deg;  // direction eye -> target
  const double pitch = ClampPitch(-pitch_deg + dpitch_deg);
  const Vec3 d(std::cos(pitch * kRadPerDeg) * std::cos(yaw * kRadPerDeg),
               std::cos(pitch * kRadPerDeg) * std::sin(yaw * kRadPerDeg),
               std::sin(pitch * kRadPerDeg));
  target = eye + distance * d;
  yaw_deg = std::remainder(yaw - 180.0, 360.0);
  pitch_deg = -pitch;
}

OrbitView OrbitView::Framing(const Aabb& box, double fov_deg) {
  OrbitView v;
  v.fov_deg = fov_deg;
  v.target = box.center();
  const double radius = std::max(0.5 * box.diagonal(), 1e-3);
  // The sphere round the box fits the vertical field of view of a 16:9 image, with a margin.
  const double vfov = 2 * std::atan(std::tan(0.5 * fov_deg * kRadPerDeg) * 9.0 / 16.0);
  v.distance = ClampDistance(1.1 * radius / std::sin(0.5 * vfov));
  return v;
}

OrbitView OrbitView::FromLookAt(const Vec3& from, const Vec3& at, double fov_deg) {
  OrbitView v;
  v.fov_deg = fov_deg;
  v.target = at;
  const Vec3 d = from - at;
  v.distance = ClampDistance(d.norm());
  v.yaw_deg = std::atan2(d.y(), d.x()) / kRadPerDeg;
  v.pitch_deg =
      ClampPitch(std::asin(std::clamp(d.z() / std::max(d.norm(), 1e-300), -1.0, 1.0)) / kRadPerDeg);
  return v;
}

}  // namespace pandora::viewer
