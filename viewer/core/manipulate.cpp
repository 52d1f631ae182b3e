#include "viewer/core/manipulate.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/util/units.h"

namespace pandora::viewer {

std::optional<double> AxisParameter(const Ray& ray, const Vec3& origin, const Vec3& axis) {
  // Closest points of the lines origin + t a and o + s d (a, d unit).
  const Vec3 a = axis.normalized(), d = ray.direction.normalized();
  const Vec3 w = origin - ray.origin;
  const double b = a.dot(d);
  const double denom = 1.0 - b * b;
  if (!(denom > 1e-18)) return std::nullopt;
  return (b * d.dot(w) - a.dot(w)) / denom;
}

std::optional<double> SweptAngle(const Ray& from, const Ray& to, const Vec3& origin,
                                 const Vec3& axis) {
  const Vec3 n = axis.normalized();
  auto hit = [&](const Ray& r) -> std::optional<Vec3> {
    const double dn = r.direction.dot(n);
    if (std::abs(dn) < 1e-12) return std::nullopt;
    const double t = (origin - r.origin).dot(n) / dn;
    if (!(t > 0) || !std::isfinite(t)) return std::nullopt;
    const Vec3 v = r.origin + t * r.direction - origin;
    if (!(v.norm() > 0)) return std::nullopt;
    return v;
  };
  const auto a = hit(from), b = hit(to);
  if (!a || !b) return std::nullopt;
  return std::atan2(n.dot(a->cross(*b)), a->dot(*b));
}

double Snap(double value, double step) {
  return step > 0 ? step * std::round(value / step) : value;
}

std::vector<Eigen::Isometry3d> MoveRigidly(const std::vector<Eigen::Isometry3d>& poses,
                                           const Vec3& pivot, const Vec3& move,
                                           const Mat3& rotation) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = rotation;
  t.translation() = pivot + move - rotation * pivot;
  std::vector<Eigen::Isometry3d> out;
  out.reserve(poses.size());
  for (const Eigen::Isometry3d& p : poses) out.push_back(t * p);
  return out;
}

int PickCamera(const Rig& rig, const Ray& ray, double radius) {
  const Vec3 d = ray.direction.normalized();
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  for (int c = 0; c < int(rig.cameras.size()); ++c) {
    const Vec3 oc = rig.cameras[c].center() - ray.origin;
    const double t = oc.dot(d);
    const double miss2 = oc.squaredNorm() - t * t;
    if (miss2 > radius * radius) continue;
    const double t_hit = t - std::sqrt(std::max(0.0, radius * radius - miss2));
    if (t_hit < -radius || t_hit >= best_t) continue;  // behind the eye
    best_t = t_hit;
    best = c;
  }
  return best;
}

double StickCurve(double x, double deadzone) {
  x = std::clamp(x, -1.0, 1.0);
  const double travel = std::abs(x) - deadzone;
  if (!(travel > 0)) return 0.0;
  const double u = travel / (1.0 - deadzone);
  return std::copysign(u * u * u * u, x);
}

Eigen::Isometry3d GamepadMove(const Eigen::Isometry3d& world_from_camera, const GamepadAxes& axes,
                              double dt, double metres_per_second, double degrees_per_second) {
  const Mat3 R = world_from_camera.linear();
  // Horizontal forward and right of the camera (its z and x axes projected on the floor).
  Vec3 forward = R.col(2);
  forward.z() = 0;
  Vec3 right = R.col(0);
  right.z() = 0;
  if (forward.norm() > 1e-9) forward.normalize();
  if (right.norm() > 1e-9) right.normalize();
  const double step = metres_per_second * dt;
  const double lift = 0.5 * (StickCurve(axes.right_trigger * 0.5 + 0.5, 0.05) -
                             StickCurve(axes.left_trigger * 0.5 + 0.5, 0.05));
  const Vec3 move = step * (StickCurve(axes.left_x) * right - StickCurve(axes.left_y) * forward +
                            lift * Vec3::UnitZ());
  const double turn = degrees_per_second * dt * kPi / 180.0;
  const Mat3 yaw =
      Eigen::AngleAxisd(-turn * StickCurve(axes.right_x), Vec3::UnitZ()).toRotationMatrix();
  const Mat3 pitch =
      Eigen::AngleAxisd(-turn * StickCurve(axes.right_y), R.col(0)).toRotationMatrix();
  Eigen::Isometry3d out = world_from_camera;
  out.linear() = yaw * pitch * R;
  out.translation() += move;
  return out;
}

}  // namespace pandora::viewer
