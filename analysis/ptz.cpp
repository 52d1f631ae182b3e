// Pan-tilt-zoom heads: poses, move times, and what a head can reach within a time budget.
#include "analysis/ptz.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/camera.h"
#include "analysis/visibility.h"  // PixelDensity

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

std::vector<PtzHead::TourLeg> PtzHead::TourLegs(const std::vector<int>& order) const {
  std::vector<int> stops = order;
  if (stops.empty())
    for (int i = 0; i < static_cast<int>(tour.size()); ++i) stops.push_back(i);
  std::vector<TourLeg> legs;
  double t = 0;
  for (std::size_t i = 0; i < stops.size(); ++i) {
    TourLeg leg;
    leg.stop = stops[i];
    leg.from = presets[tour[stops[(i + stops.size() - 1) % stops.size()]].preset].state;
    leg.to = presets[tour[stops[i]].preset].state;
    leg.start = t;
    leg.move_s = MoveTime(leg.from, leg.to);
    leg.dwell_s = tour[stops[i]].dwell_s;
    t = leg.end();
    legs.push_back(leg);
  }
  return legs;
}

PtzState PtzHead::TourState(const std::vector<TourLeg>& legs, double t) const {
  if (legs.empty()) return current;
  const double period = legs.back().end();
  if (period > 0) {
    t = std::fmod(t, period);
    if (t < 0) t += period;
  }
  for (const TourLeg& leg : legs)
    if (t < leg.end()) return Along(leg.from, leg.to, t - leg.start);
  return legs.back().to;
}

double PtzHead::SampleStep(const Camera& base, const PtzState& a, const PtzState& b) const {
  const Intrinsics k = base.model.intrinsics();
  // The narrowest zoom along the move is at one of its ends (the focal moves monotonically).
  const double f = std::max({a.focal, b.focal, 1e-12});
  const double hfov = Deg(HfovFromFocal(f, k.width, k.model));
  const double vfov = Deg(2.0 * std::atan(0.5 * k.height / (f * k.fy / k.fx)));  // pinhole's (a step, not a bound)
  const double angle = 0.25 * std::min(hfov, vfov);
  return angle / std::max(pan_speed_deg_s, tilt_speed_deg_s);
}

double PtzWatch::watched_s() const {
  double sum = 0;
  for (const auto& [a, b] : intervals) sum += b - a;
  return sum;
}

double PtzWatch::longest_gap_s() const {
  if (intervals.empty()) return period;
  double gap = 0;
  for (std::size_t i = 1; i < intervals.size(); ++i)
    gap = std::max(gap, intervals[i].first - intervals[i - 1].second);
  // Around the end of the period into the next.
  gap = std::max(gap, period - intervals.back().second + intervals.front().first);
  return std::max(gap, 0.0);
}

bool PtzSees(const Camera& base, const PtzHead& head, const PtzState& s, const Vec3& X, double min_px_per_m,
             const Vec3* normal, Ray* segment, double epsilon) {
  const Eigen::Isometry3d pose = head.Pose(s);
  const Vec3 to_point = X - pose.translation();
  const double distance = to_point.norm();
  if (!(distance >= base.near) || distance > base.far) return false;
  const Vec3 p_camera = pose.linear().transpose() * to_point;
  const Intrinsics& k = base.model.intrinsics();
  const double scale = s.focal / k.fx;
  Mat23 J;
  std::optional<Vec2> pixel = base.model.Project(p_camera, min_px_per_m > 0 ? &J : nullptr);
  if (!pixel) return false;
  // The zoom scales the pixels about the principal point (the lens's domain is unchanged), and
  // with them the pixel density.
  const Vec2 pp(k.cx, k.cy);
  *pixel = pp + scale * (*pixel - pp);
  if (!base.model.InImage(*pixel)) return false;
  if (normal && normal->dot(-to_point) <= 0.0) return false;
  if (min_px_per_m > 0 && !(scale * PixelDensity(J) >= min_px_per_m)) return false;
  if (segment) {
    segment->origin = pose.translation();
    segment->direction = to_point / distance;
    segment->t_near = epsilon;
    segment->t_far = std::max(epsilon, distance - epsilon);
  }
  return true;
}

bool PtzSegmentOccluded(const VisibilityTester& tester, int camera, Ray segment, std::int64_t* rays) {
  const double distance = segment.t_far;
  const double eps = tester.Tolerance(camera, distance);
  segment.t_near = eps;
  segment.t_far = distance - eps;
  if (!(segment.t_far > segment.t_near)) return false;  // too short to hold an occluder
  if (rays) ++*rays;
  return tester.caster().Occluded(segment);
}

PtzReach::PtzReach(const Camera& base, const PtzHead& head, const PtzState& from, double min_px_per_m)
    : base_(base), head_(head), from_(from), min_px_per_m_(min_px_per_m) {
  const double pan_span = head.ContinuousPan()
                              ? 180.0
                              : std::max(head.pan_max_deg - from.pan_deg, from.pan_deg - head.pan_min_deg);
  const double tilt_span = std::max(head.tilt_max_deg - from.tilt_deg, from.tilt_deg - head.tilt_min_deg);
  const double zoom_rate = head.zoom_speed * (head.focal_max - head.focal_min);
  max_time_ = std::max(pan_span / head.pan_speed_deg_s, tilt_span / head.tilt_speed_deg_s);
  if (zoom_rate > 0) max_time_ = std::max(max_time_, (from.focal - head.focal_min) / zoom_rate);
  // With a density target the head may have to zoom in as far as it goes.
  if (zoom_rate > 0 && min_px_per_m > 0) max_time_ = std::max(max_time_, (head.focal_max - from.focal) / zoom_rate);
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
  if (min_px_per_m_ > 0) {
    // The density scales with the focal length: the zoom that meets the target exactly at this
    // pose, then the widest reachable one at or above it.
    const Eigen::Isometry3d pose = h.Pose(s);
    Mat23 J;
    if (!base_.model.Project(pose.linear().transpose() * (X - pose.translation()), &J)) return std::nullopt;
    const double density = PixelDensity(J);  // at the camera's own focal
    if (!(density > 0)) return std::nullopt;
    const double needed = base_.model.intrinsics().fx * min_px_per_m_ / density;
    const double f_hi = zoom_rate > 0 ? std::min(h.focal_max, from_.focal + zoom_rate * t) : from_.focal;
    s.focal = std::max(s.focal, needed);
    if (s.focal > f_hi) return std::nullopt;
  }
  return s;
}

bool PtzReach::Reachable(const Vec3& X, double t, const Vec3* normal, Ray* segment, double epsilon) const {
  const std::optional<PtzState> s = BestPose(X, t);
  if (!s) return false;
  // The density was met when BestPose chose the zoom (up to rounding: not tested twice).
  return PtzSees(base_, head_, *s, X, 0.0, normal, segment, epsilon);
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
