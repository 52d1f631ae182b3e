// Pan-tilt-zoom heads: poses, move times, and what a head can reach within a time budget.
#include "analysis/ptz.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/camera.h"

namespace pandora {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
double Rad(double deg) { return deg * kPi / 180.0; }
double Deg(double rad) { return rad * 180.0 / kPi; }

double Wrap180(double deg) {
  double a = std::fmod(deg + 180.0, 360.0);
  if (a < 0) a += 360.0;
  return a - 180.0;
}

double Toward(double a, double b, double step) {
  const double d = b - a;
  return std::abs(d) <= step ? b : a + (d > 0 ? step : -step);
}

}  // namespace

double PtzHead::HomeElevationDeg() const {
  return Deg(std::asin(std::clamp(home.linear().col(2).dot(pan_axis), -1.0, 1.0)));
}

double PtzHead::WrapPan(double deg) const {
  if (!ContinuousPan()) return deg;
  double a = Wrap180(deg);
  // Keep it inside [pan_min, pan_min + 360).
  while (a < pan_min_deg) a += 360.0;
  while (a >= pan_min_deg + 360.0) a -= 360.0;
  return a;
}

Eigen::Isometry3d PtzHead::Pose(const PtzState& s) const {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const Mat3 R = Eigen::AngleAxisd(Rad(s.pan_deg), pan_axis).toRotationMatrix() * home.linear() *
                 Eigen::AngleAxisd(Rad(s.tilt_deg), Vec3::UnitX()).toRotationMatrix();
  pose.linear() = R;
  pose.translation() = home.translation() + R * offset;
  return pose;
}

Camera PtzHead::CameraAt(const Camera& base, const PtzState& s) const {
  Camera c = base;
  c.world_from_camera = Pose(s);
  Intrinsics k = base.model.intrinsics();
  const double scale = s.focal / k.fx;
  if (scale != 1.0 && std::isfinite(scale) && scale > 0) {
    k.fx *= scale;
    k.fy *= scale;
    c.model = CameraModel(k);
  }
  return c;
}

double PtzHead::MoveTime(const PtzState& a, const PtzState& b) const {
  double dpan = b.pan_deg - a.pan_deg;
  if (ContinuousPan()) dpan = Wrap180(dpan);
  const double zoom_rate = zoom_speed * (focal_max - focal_min);
  double t = std::max(std::abs(dpan) / pan_speed_deg_s, std::abs(b.tilt_deg - a.tilt_deg) / tilt_speed_deg_s);
  const double df = std::abs(b.focal - a.focal);
  if (df > 0) t = std::max(t, zoom_rate > 0 ? df / zoom_rate : kInf);
  return t;
}

PtzState PtzHead::Along(const PtzState& a, const PtzState& b, double t) const {
  double target_pan = b.pan_deg;
  if (ContinuousPan()) target_pan = a.pan_deg + Wrap180(b.pan_deg - a.pan_deg);
  PtzState s;
  s.pan_deg = WrapPan(Toward(a.pan_deg, target_pan, pan_speed_deg_s * t));
  s.tilt_deg = Toward(a.tilt_deg, b.tilt_deg, tilt_speed_deg_s * t);
  s.focal = Toward(a.focal, b.focal, zoom_speed * (focal_max - focal_min) * t);
  return s;
}

std::vector<PtzState> PtzHead::Path(const PtzState& a, const PtzState& b) const {
  const double total = MoveTime(a, b);
  std::vector<PtzState> out{a};
  if (!(total > 0)) return out;
  for (int k = 1; k < total; ++k) out.push_back(Along(a, b, k));
  out.push_back(Along(a, b, total));
  return out;
}

PtzReach::PtzReach(const Camera& base, const PtzHead& head, const PtzState& from)
    : base_(base), head_(head), from_(from) {
  const double pan_span = head.ContinuousPan()
                              ? 180.0
                              : std::max(head.pan_max_deg - from.pan_deg, from.pan_deg - head.pan_min_deg);
  const double tilt_span = std::max(head.tilt_max_deg - from.tilt_deg, from.tilt_deg - head.tilt_min_deg);
  const double zoom_rate = head.zoom_speed * (head.focal_max - head.focal_min);
  max_time_ = std::max(pan_span / head.pan_speed_deg_s, tilt_span / head.tilt_speed_deg_s);
  if (zoom_rate > 0) max_time_ = std::max(max_time_, (from.focal - head.focal_min) / zoom_rate);
  max_time_ = std::max(max_time_, 0.0);
}

std::optional<PtzState> PtzReach::BestPose(const Vec3& X, double t) const {
  const PtzHead& h = head_;
  t = std::max(t, 0.0);
  // The reachable box: pan and tilt intervals, the widest reachable zoom.
  double pan_lo = from_.pan_deg - h.pan_speed_deg_s * t, pan_hi = from_.pan_deg + h.pan_speed_deg_s * t;
  const bool any_pan = h.ContinuousPan() && pan_hi - pan_lo >= 360.0;
  if (!h.ContinuousPan()) {
    pan_lo = std::max(pan_lo, h.pan_min_deg);
    pan_hi = std::min(pan_hi, h.pan_max_deg);
  }
  const double tilt_lo = std::max(from_.tilt_deg - h.tilt_speed_deg_s * t, h.tilt_min_deg);
  const double tilt_hi = std::min(from_.tilt_deg + h.tilt_speed_deg_s * t, h.tilt_max_deg);
  const double zoom_rate = h.zoom_speed * (h.focal_max - h.focal_min);
  PtzState s;
  s.focal = std::max(h.focal_min, from_.focal - zoom_rate * t);
  if (!(zoom_rate > 0)) s.focal = from_.focal;
  const double el0 = h.HomeElevationDeg();
  const Vec3 x_home = h.home.linear().col(0);
  const Vec3 forward0 = h.pan_axis.cross(x_home);  // horizontal forward at pan 0
  s.pan_deg = from_.pan_deg;
  s.tilt_deg = from_.tilt_deg;
  const int rounds = h.offset.isZero(0.0) ? 1 : 4;
  for (int round = 0; round < rounds; ++round) {
    const Vec3 C = round == 0 ? Vec3(h.home.translation()) : Vec3(h.Pose(s).translation());
    const Vec3 e = X - C;
    if (!(e.norm() > 0)) return std::nullopt;
    const double az = Deg(std::atan2(e.dot(-x_home), e.dot(forward0)));
    const double horizontal = std::hypot(e.dot(-x_home), e.dot(forward0));
    // Pan: the reachable angle nearest to the point's azimuth (any turn of 360 considered).
    double pan = az;
    if (!any_pan) {
      double best = kInf;
      for (int k = -2; k <= 2; ++k) {
        const double a = az + 360.0 * k;
        const double c = std::clamp(a, pan_lo, pan_hi);
        if (std::abs(c - a) < best) {
          best = std::abs(c - a);
          pan = c;
        }
      }
    }
    // Tilt: the elevation that puts the point on the image's horizontal midline for that pan,
    // atan2(up, horizontal * cos(dpan)), clamped to the reachable elevations.
    const double dpan = Rad(pan - az);
    const double el = Deg(std::atan2(e.dot(h.pan_axis), horizontal * std::cos(dpan)));
    s.pan_deg = h.WrapPan(pan);
    s.tilt_deg = std::clamp(el - el0, tilt_lo, tilt_hi);
  }
  return s;
}

bool PtzReach::Reachable(const Vec3& X, double t, const Vec3* normal, Ray* segment, double epsilon) const {
  const std::optional<PtzState> s = BestPose(X, t);
  if (!s) return false;
  const Eigen::Isometry3d pose = head_.Pose(*s);
  const Vec3 to_point = X - pose.translation();
  const double distance = to_point.norm();
  if (distance < base_.near || distance > base_.far) return false;
  const Vec3 p_camera = pose.linear().transpose() * to_point;
  Intrinsics k = base_.model.intrinsics();
  const double scale = s->focal / k.fx;
  std::optional<Vec2> pixel = base_.model.Project(p_camera);
  if (!pixel) return false;
  // The zoom scales the pixels about the principal point (the lens's domain is unchanged).
  const Vec2 pp(k.cx, k.cy);
  *pixel = pp + scale * (*pixel - pp);
  if (!base_.model.InImage(*pixel)) return false;
  if (normal && normal->dot(-to_point) <= 0.0) return false;
  if (segment) {
    segment->origin = pose.translation();
    segment->direction = to_point / distance;
    segment->t_near = epsilon;
    segment->t_far = std::max(epsilon, distance - epsilon);
  }
  return true;
}

double PtzReach::ReachTime(const Vec3& X, const Vec3* normal, double tolerance_s) const {
  if (Reachable(X, 0.0, normal)) return 0.0;
  if (!Reachable(X, max_time_, normal)) return kInf;
  double lo = 0.0, hi = max_time_;
  while (hi - lo > tolerance_s) {
    const double mid = 0.5 * (lo + hi);
    (Reachable(X, mid, normal) ? hi : lo) = mid;
  }
  return hi;
}

}  // namespace pandora
