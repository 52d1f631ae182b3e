// Pan-tilt-zoom heads: poses, move times, and what a head can reach within a time budget.
#include "analysis/scene/ptz.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/surface_distance.h"
#include "analysis/geometry/visibility.h"  // PixelDensity
#include "analysis/util/units.h"

namespace pandora {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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
  double t = std::max(std::abs(dpan) / pan_speed_deg_s,
                      std::abs(b.tilt_deg - a.tilt_deg) / tilt_speed_deg_s);
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
  const double vfov =
      Deg(2.0 * std::atan(0.5 * k.height / (f * k.fy / k.fx)));  // pinhole's (a step, not a bound)
  const double angle = 0.25 * std::min(hfov, vfov);
  return angle / std::max(pan_speed_deg_s, tilt_speed_deg_s);
}

std::optional<std::vector<std::pair<double, double>>> PtzMoveChanges(
    const PtzHead& head, const Camera& base, const PtzState& from, const PtzState& to,
    double move_s, const PtzTarget& target, double resolution_s, int max_evaluations) {
  const Intrinsics& k = base.model.intrinsics();
  const bool undistorted =
      k.model == LensModel::kPinhole || (k.model == LensModel::kBrownConrady && k.k1 == 0 &&
                                         k.k2 == 0 && k.k3 == 0 && k.p1 == 0 && k.p2 == 0);
  if (!undistorted || !(k.fx > 0) || !(k.fy > 0)) return std::nullopt;
  std::vector<std::pair<double, double>> spans;
  if (!(move_s > 0)) return spans;
  // When each axis stops (Along: every axis at its speed until it arrives), and the rates before.
  double dpan = to.pan_deg - from.pan_deg;
  if (head.ContinuousPan()) dpan = Wrap180(dpan);
  const double t_pan = std::abs(dpan) / head.pan_speed_deg_s;
  const double t_tilt = std::abs(to.tilt_deg - from.tilt_deg) / head.tilt_speed_deg_s;
  const double zoom_rate = head.zoom_speed * (head.focal_max - head.focal_min);
  const double t_zoom =
      to.focal != from.focal && zoom_rate > 0 ? std::abs(to.focal - from.focal) / zoom_rate : 0.0;
  const double offset = head.offset.norm();
  const double fy_fx = k.fy / k.fx;
  // The image in the plane z = 1 at focal f (fx): its farthest corner is R_c / f from the axis.
  double corner = 0;
  for (double u : {-0.5, k.width - 0.5})
    for (double v : {-0.5, k.height - 0.5})
      corner = std::max(corner, std::hypot(u - k.cx, (v - k.cy) / fy_fx));
  const Vec3& X = target.X;
  const double normal_length = target.normal ? target.normal->norm() : 0.0;
  // +1: the margin keeps g > 0 over the piece, -1: g < 0 throughout, 0: either.
  auto sign = [](double g, double change) { return g > change ? 1 : g < -change ? -1 : 0; };
  // Whether the test's answer is constant on [a, b].
  auto constant = [&](double a, double b) {
    const double m = 0.5 * (a + b), h = 0.5 * (b - a);
    const PtzState s = head.Along(from, to, m);
    const double turn =
        Rad((a < t_pan ? head.pan_speed_deg_s : 0.0) + (a < t_tilt ? head.tilt_speed_deg_s : 0.0));
    const double zoom = a < t_zoom ? zoom_rate : 0.0;
    const Eigen::Isometry3d pose = head.Pose(s);
    const Vec3 e = X - pose.translation();
    const double D = e.norm();
    const double centre_speed = turn * offset;
    const double moved = centre_speed * h;  // how far the centre can move within the piece
    bool all = true;
    auto margin = [&](double g, double change) {  // false: fails throughout (the answer is false)
      const int r = sign(g, change);
      all = all && r > 0;
      return r >= 0;
    };
    if (!margin(D - base.near, moved)) return true;
    if (std::isfinite(base.far) && !margin(base.far - D, moved)) return true;
    if (target.normal && !margin(target.normal->dot(-e) / normal_length, moved)) return true;
    const double D_lo = D - moved;
    if (!(D_lo > 0)) return false;
    const double w = turn + centre_speed / D_lo;  // the direction's turn rate in the camera frame
    const Vec3 p = pose.linear().transpose() * e;
    const double theta = std::atan2(std::hypot(p.x(), p.y()), p.z());
    const double f_lo = s.focal - zoom * h, f_hi = s.focal + zoom * h;
    if (!(f_lo > 0)) return false;
    // Outside the widest view of the piece throughout.
    if (theta - w * h > std::atan(corner / f_lo)) return true;
    const double theta_hi = theta + w * h;
    if (!(theta_hi < 0.5 * kPi - 1e-6)) return false;
    const double rho = std::tan(theta_hi);  // |(x/z, y/z)| within the piece
    // A unit direction turning at w moves (x/z, y/z) at most (1 + rho^2) w (the gnomonic map's
    // largest stretch, sec^2); the pixel moves with it times the focal, and with the zoom.
    const double du = zoom * rho + f_hi * (1.0 + rho * rho) * w;
    const double dv = fy_fx * du;
    const double u = k.cx + s.focal * p.x() / p.z();
    const double v = k.cy + s.focal * fy_fx * p.y() / p.z();
    if (!margin(u + 0.5, du * h) || !margin(k.width - 0.5 - u, du * h) ||
        !margin(v + 0.5, dv * h) || !margin(k.height - 0.5 - v, dv * h))
      return true;
    if (target.min_px_per_m > 0) {
      // PixelDensity of the pinhole, zoomed: f sqrt(fy/fx) / D * sec^1.5(theta); its logarithm
      // changes at most by the zoom's, the distance's and 1.5 tan(theta) times the turn rate.
      const double q2 = (p.x() * p.x() + p.y() * p.y()) / (p.z() * p.z());
      const double density = s.focal * std::sqrt(fy_fx) / p.z() * std::pow(1.0 + q2, 0.25);
      const double rate = zoom / f_lo + centre_speed / D_lo + 1.5 * rho * w;
      if (!margin(std::log(density / target.min_px_per_m), rate * h)) return true;
    }
    return all;
  };
  std::vector<std::pair<double, double>> stack{{0.0, move_s}};
  int evaluations = 0;
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (++evaluations > max_evaluations) return std::nullopt;
    if (constant(a, b)) continue;
    if (b - a <= resolution_s) {
      if (!spans.empty() && spans.back().second >= a)
        spans.back().second = b;
      else
        spans.emplace_back(a, b);
      continue;
    }
    const double m = 0.5 * (a + b);
    stack.emplace_back(m, b);
    stack.emplace_back(a, m);
  }
  return spans;
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

bool PtzSees(const Camera& base, const PtzHead& head, const PtzState& s, const Vec3& X,
             double min_px_per_m, const Vec3* normal, Ray* segment, double epsilon) {
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

double PtzHead::CentreSpeedBound() const {
  return offset.norm() * Rad(pan_speed_deg_s + tilt_speed_deg_s);
}

namespace {

// Whether the occlusion segment from `centre` to X is clear (PtzSegmentOccluded); false when they
// coincide.
bool SegmentClear(const VisibilityTester& tester, int camera, const Vec3& centre, const Vec3& X) {
  const Vec3 e = X - centre;
  Ray segment;
  segment.origin = centre;
  segment.t_far = e.norm();
  if (!(segment.t_far > 0)) return false;
  segment.direction = e / segment.t_far;
  return !PtzSegmentOccluded(tester, camera, segment, nullptr);
}

}  // namespace

int PtzSweptOcclusion(const VisibilityTester& tester, int camera, const Vec3& centre, double r,
                      const Vec3& X) {
  const SurfaceDistance* surfaces = tester.surfaces();
  if (!surfaces || !(r >= 0)) return 0;
  const double D = (X - centre).norm();
  if (!(D > 0)) return 0;
  // Only the answer the middle segment has can hold for all: its ray decides which to try (a
  // clearance march towards a surface it would cross ends only near it, many steps in).
  // PtzSegmentOccluded trims each segment by its own tolerance, which grows with its length in
  // [D - r, D + r]: the clearance covers the most a segment keeps, the crossing must lie inside the
  // least.
  if (SegmentClear(tester, camera, centre, X))
    return surfaces->ConeClear(centre, r, X, tester.Tolerance(camera, std::max(0.0, D - r))) ? 1
                                                                                             : 0;
  return surfaces->ConeBlocked(centre, r, X, tester.Tolerance(camera, D + r)) ? -1 : 0;
}

std::optional<std::vector<std::pair<double, double>>> PtzMoveClearWindows(
    const PtzHead& head, const PtzState& from, const PtzState& to, double t_begin, double t_end,
    const PtzTarget& target, int max_certificates) {
  if (!target.tester || !target.tester->surfaces() || target.camera < 0) return std::nullopt;
  const VisibilityTester& tester = *target.tester;
  const int camera = target.camera;
  const Vec3& X = target.X;
  const double speed = head.CentreSpeedBound();
  auto centre = [&](double t) -> Vec3 {
    const Eigen::Isometry3d pose = head.Pose(head.Along(from, to, t));
    return pose.translation();
  };
  auto clear_at = [&](double t) { return SegmentClear(tester, camera, centre(t), X); };
  std::vector<std::pair<double, double>> found;
  auto add = [&found](double a, double b) {
    if (!(b > a)) return;
    if (!found.empty() && found.back().second >= a)
      found.back().second = std::max(found.back().second, b);
    else
      found.emplace_back(a, b);
  };
  std::vector<std::pair<double, double>> stack{
      {t_begin, t_end}};  // in order: the last is the earliest
  int certificates = 0;
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (!(b > a)) continue;
    if (++certificates > max_certificates) return std::nullopt;
    const double m = 0.5 * (a + b);
    const double r = speed * 0.5 * (b - a);
    const Vec3 c = centre(m);
    const int answer = PtzSweptOcclusion(tester, camera, c, r, X);
    if (answer > 0) add(a, b);
    if (answer != 0) continue;
    if (b - a <= 1e-6 || r <= tester.Tolerance(camera, (X - c).norm())) {
      // Below the tolerance: the ends decide, a change between them bisected.
      const bool ca = clear_at(a);
      const bool cb = clear_at(b);
      if (ca == cb) {
        if (ca) add(a, b);
        continue;
      }
      double lo = a, hi = b;  // clear_at(lo) == ca, clear_at(hi) == cb
      while (hi - lo > 1e-6) {
        const double mid = 0.5 * (lo + hi);
        (clear_at(mid) == ca ? lo : hi) = mid;
      }
      const double change = 0.5 * (lo + hi);
      if (ca)
        add(a, change);
      else
        add(change, b);
      continue;
    }
    stack.emplace_back(m, b);
    stack.emplace_back(a, m);
  }
  return found;
}

bool PtzSegmentOccluded(const VisibilityTester& tester, int camera, Ray segment,
                        std::int64_t* rays) {
  const double distance = segment.t_far;
  const double eps = tester.Tolerance(camera, distance);
  segment.t_near = eps;
  segment.t_far = distance - eps;
  if (!(segment.t_far > segment.t_near)) return false;  // too short to hold an occluder
  if (rays) ++*rays;
  return tester.caster().Occluded(segment);
}

namespace {

// The pans and tilts a search looks over: those within the view's half diagonal (a quarter more for
// distortion) of centring the point, pan widened towards the pan axis, where a pan moves the image
// less; `pan_c` and `tilt_c` centre it. Empty when it misses the allowed pans or tilts.
struct Window {
  double p0 = 0, p1 = 0, q0 = 0, q1 = 0, pan_c = 0, tilt_c = 0;
  bool empty() const { return !(p1 >= p0) || !(q1 >= q0); }
};

// The window for X seen from `head` at `from` with focal `focal` (the widest the search allows).
// Pans: with `clamp_pan`, the turn of X's azimuth nearest to [pan_lo, pan_hi] and the window cut to
// it; otherwise centred on the turn `free_turn` gives (the azimuth -> its turn), uncut. Tilts cut
// to [tilt_lo, tilt_hi]. Nothing when X is at the centre.
template <typename FreeTurn>
std::optional<Window> SearchWindow(const PtzHead& h, const Intrinsics& k, const PtzState& from,
                                   const Vec3& X, double focal, bool clamp_pan, double pan_lo,
                                   double pan_hi, double tilt_lo, double tilt_hi,
                                   FreeTurn&& free_turn) {
  const Vec3 e = X - h.Pose(from).translation();
  if (!(e.norm() > 0)) return std::nullopt;
  const Vec3 x_home = h.home.linear().col(0);
  const Vec3 forward0 = h.pan_axis.cross(x_home);
  const double az = Deg(std::atan2(e.dot(-x_home), e.dot(forward0)));
  const double el = Deg(std::atan2(e.dot(h.pan_axis), std::hypot(e.dot(-x_home), e.dot(forward0))));
  const double corner = std::hypot(std::max(k.cx + 0.5, k.width - 0.5 - k.cx),
                                   std::max(k.cy + 0.5, k.height - 0.5 - k.cy));
  const double half = k.model == LensModel::kFisheye
                          ? 180.0
                          : std::min(180.0, 1.25 * Deg(std::atan(corner / focal)) + 0.5);
  const double pan_half = std::min(180.0, half / std::max(std::cos(Rad(el)), 0.02));
  Window w;
  w.pan_c = free_turn(az);
  if (clamp_pan) {
    double best = kInf;
    for (int q = -2; q <= 2; ++q) {
      const double a = az + 360.0 * q;
      const double gap = std::abs(std::clamp(a, pan_lo, pan_hi) - a);
      if (gap < best) best = gap, w.pan_c = a;
    }
  }
  w.p0 = w.pan_c - pan_half;
  w.p1 = w.pan_c + pan_half;
  if (clamp_pan) w.p0 = std::max(w.p0, pan_lo), w.p1 = std::min(w.p1, pan_hi);
  w.tilt_c = el - h.HomeElevationDeg();
  w.q0 = std::max(tilt_lo, w.tilt_c - half);
  w.q1 = std::min(tilt_hi, w.tilt_c + half);
  return w;
}

// Minimises `score(pan, tilt)` (any ordered type) over the window: a 9 x 9 lattice (stopped as soon
// as `enough(best)`), then from its best point a pattern search of the 8 neighbours, steps halved
// down to 1e-7 degrees, at most `max_evals` evaluations, while `refine(best)`. Returns the best
// score and its pan and tilt.
template <typename Score, typename Eval, typename Enough, typename Refine>
Score MinimiseOverWindow(const Window& w, Score worst, Eval&& score, Enough&& enough,
                         Refine&& refine, int max_evals, double* best_p, double* best_q) {
  constexpr int kLattice = 9;
  Score best = worst;
  *best_p = w.pan_c;
  *best_q = w.tilt_c;
  for (int i = 0; i < kLattice && !enough(best); ++i)
    for (int j = 0; j < kLattice && !enough(best); ++j) {
      const double p = w.p0 + (w.p1 - w.p0) * i / (kLattice - 1),
                   q = w.q0 + (w.q1 - w.q0) * j / (kLattice - 1);
      const Score sc = score(p, q);
      if (sc < best) best = sc, *best_p = p, *best_q = q;
    }
  if (!(best < worst)) return best;
  double dp = 0.5 * (w.p1 - w.p0) / (kLattice - 1), dq = 0.5 * (w.q1 - w.q0) / (kLattice - 1);
  for (int evals = 0; refine(best) && evals < max_evals && (dp > 1e-7 || dq > 1e-7);) {
    bool moved = false;
    for (const auto& [sp, sq] :
         {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, -1}, {1, -1}, {-1, 1}}) {
      const double p = std::clamp(*best_p + sp * dp, w.p0, w.p1),
                   q = std::clamp(*best_q + sq * dq, w.q0, w.q1);
      const Score sc = score(p, q);
      ++evals;
      if (sc < best) {
        best = sc, *best_p = p, *best_q = q;
        moved = true;
        break;
      }
    }
    if (!moved) dp *= 0.5, dq *= 0.5;
  }
  return best;
}

// The largest zoom scale (focal over the lens's own) at which `pixel` (at the lens's own focal)
// stays inside the image: the zoom scales pixels about the principal point. +inf at that point.
double MaxZoomScale(const Intrinsics& k, const Vec2& pixel) {
  const double dx = pixel.x() - k.cx, dy = pixel.y() - k.cy;
  double scale = kInf;
  if (dx > 0) scale = std::min(scale, (k.width - 0.5 - k.cx) / dx);
  if (dx < 0) scale = std::min(scale, (-0.5 - k.cx) / dx);
  if (dy > 0) scale = std::min(scale, (k.height - 0.5 - k.cy) / dy);
  if (dy < 0) scale = std::min(scale, (-0.5 - k.cy) / dy);
  return scale;
}

}  // namespace

bool PtzReach::ZoomInterval(const Vec3& X, double pan, double tilt, const Vec3* normal,
                            double target, double f_lo, double f_hi, double* lo, double* hi) const {
  const PtzHead& h = head_;
  const Intrinsics& k = base_.model.intrinsics();
  PtzState s;
  s.pan_deg = h.WrapPan(pan);
  s.tilt_deg = tilt;
  s.focal = k.fx;
  const Eigen::Isometry3d pose = h.Pose(s);
  const Vec3 to_point = X - pose.translation();
  const double distance = to_point.norm();
  if (!(distance >= base_.near) || distance > base_.far) return false;
  if (normal && normal->dot(-to_point) <= 0.0) return false;
  Mat23 J;
  const std::optional<Vec2> pixel =
      base_.model.Project(pose.linear().transpose() * to_point, target > 0 ? &J : nullptr);
  if (!pixel) return false;
  *lo = f_lo;
  *hi = std::min(f_hi, k.fx * MaxZoomScale(k, *pixel));
  if (target > 0) {
    const double density = PixelDensity(J);
    if (!(density > 0)) return false;
    *lo = std::max(*lo, k.fx * target / density);
  }
  return true;
}

PtzReach::Box PtzReach::ReachableBox(double t) const {
  const PtzHead& h = head_;
  t = std::max(t, 0.0);
  Box b;
  b.pan_lo = from_.pan_deg - h.pan_speed_deg_s * t;
  b.pan_hi = from_.pan_deg + h.pan_speed_deg_s * t;
  b.any_pan = h.ContinuousPan() && b.pan_hi - b.pan_lo >= 360.0;
  if (!h.ContinuousPan()) {
    b.pan_lo = std::max(b.pan_lo, h.pan_min_deg);
    b.pan_hi = std::min(b.pan_hi, h.pan_max_deg);
  }
  b.tilt_lo = std::max(from_.tilt_deg - h.tilt_speed_deg_s * t, h.tilt_min_deg);
  b.tilt_hi = std::min(from_.tilt_deg + h.tilt_speed_deg_s * t, h.tilt_max_deg);
  b.zoom_rate = h.zoom_speed * (h.focal_max - h.focal_min);
  b.f_lo = b.zoom_rate > 0 ? std::max(h.focal_min, from_.focal - b.zoom_rate * t) : from_.focal;
  b.f_hi = b.zoom_rate > 0 ? std::min(h.focal_max, from_.focal + b.zoom_rate * t) : from_.focal;
  return b;
}

PtzReach::PtzReach(const Camera& base, const PtzHead& head, const PtzState& from,
                   double min_px_per_m)
    : base_(base), head_(head), from_(from), min_px_per_m_(min_px_per_m) {
  const double pan_span = head.ContinuousPan() ? 180.0
                                               : std::max(head.pan_max_deg - from.pan_deg,
                                                          from.pan_deg - head.pan_min_deg);
  const double tilt_span =
      std::max(head.tilt_max_deg - from.tilt_deg, from.tilt_deg - head.tilt_min_deg);
  const double zoom_rate = head.zoom_speed * (head.focal_max - head.focal_min);
  max_time_ = std::max(pan_span / head.pan_speed_deg_s, tilt_span / head.tilt_speed_deg_s);
  if (zoom_rate > 0) max_time_ = std::max(max_time_, (from.focal - head.focal_min) / zoom_rate);
  // With a density target the head may have to zoom in as far as it goes.
  if (zoom_rate > 0 && min_px_per_m > 0)
    max_time_ = std::max(max_time_, (head.focal_max - from.focal) / zoom_rate);
  max_time_ = std::max(max_time_, 0.0);
  // The largest pixel density over the image relative to the axis' at the same distance (a
  // pinhole's cos^-1.5 at the corners), on a 33 x 33 lattice of pixels, with 2 % to spare for the
  // lattice and the pivot offset.
  const Intrinsics& k = base.model.intrinsics();
  Mat23 J;
  if (!base.model.Project(Vec3(0, 0, 1), &J)) return;
  const double axis = PixelDensity(J);
  double gain = 1.0;
  for (int i = 0; i <= 32; ++i)
    for (int j = 0; j <= 32; ++j) {
      const Vec2 px(-0.5 + k.width * i / 32.0, -0.5 + k.height * j / 32.0);
      const std::optional<Vec3> ray = base.model.Unproject(px);
      if (!ray || !(ray->norm() > 0)) continue;
      if (base.model.Project(ray->normalized(), &J)) gain = std::max(gain, PixelDensity(J) / axis);
    }
  boost_ = 1.02 * gain;
}

std::optional<PtzState> PtzReach::CentredPose(const Vec3& X, double t, double* needed_focal,
                                              bool* clamped) const {
  if (needed_focal) *needed_focal = 0;
  if (clamped) *clamped = false;
  const PtzHead& h = head_;
  t = std::max(t, 0.0);
  // The reachable box: pan and tilt intervals, the widest reachable zoom.
  const Box b = ReachableBox(t);
  const double pan_lo = b.pan_lo, pan_hi = b.pan_hi, tilt_lo = b.tilt_lo, tilt_hi = b.tilt_hi;
  const bool any_pan = b.any_pan;
  const double zoom_rate = b.zoom_rate;
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
    if (clamped)
      *clamped = std::abs(Wrap180(pan - az)) > 1e-9 || std::abs(s.tilt_deg - (el - el0)) > 1e-9;
  }
  if (min_px_per_m_ > 0) {
    // The density scales with the focal length: the zoom that meets the target exactly at this
    // pose, then the widest reachable one at or above it.
    const Eigen::Isometry3d pose = h.Pose(s);
    Mat23 J;
    if (!base_.model.Project(pose.linear().transpose() * (X - pose.translation()), &J))
      return std::nullopt;
    const double density = PixelDensity(J);  // at the camera's own focal
    if (!(density > 0)) return std::nullopt;
    const double needed = base_.model.intrinsics().fx * min_px_per_m_ / density;
    if (needed_focal) *needed_focal = needed;
    const double f_hi =
        zoom_rate > 0 ? std::min(h.focal_max, from_.focal + zoom_rate * t) : from_.focal;
    s.focal = std::max(s.focal, needed);
    if (s.focal > f_hi) return std::nullopt;
  }
  return s;
}

std::optional<PtzState> PtzReach::BestPose(const Vec3& X, double t) const {
  // The point centred (closed form): the pose of choice whenever it sees X.
  double needed = 0;
  bool clamped = false;
  const std::optional<PtzState> centred = CentredPose(X, t, &needed, &clamped);
  if (centred &&
      PtzSees(base_, head_, *centred, X, min_px_per_m_ > 0 ? min_px_per_m_ * (1 - 1e-12) : 0.0))
    return centred;
  // Centring was not limited by the reachable angles: off-centre settings can only help the
  // density, by at most the lens's largest density gain over its image (boost_).
  if (!clamped) {
    if (!(min_px_per_m_ > 0) || !(needed > 0)) return centred;
    if (needed > ReachableBox(t).f_hi * boost_) return centred;
  }
  // Otherwise an off-centre setting may: with a density target the point's density grows towards
  // the image's edges (a pinhole's as cos^-1.5 of the angle off the axis), and a clamped pan or
  // tilt can leave the point inside the image's corner but not its midline.
  if (const std::optional<PtzState> off = SearchPose(X, t)) return off;
  return centred;
}

std::optional<PtzState> PtzReach::SearchPose(const Vec3& X, double t) const {
  const PtzHead& h = head_;
  t = std::max(t, 0.0);
  const Intrinsics& k = base_.model.intrinsics();
  // The reachable box at t.
  const Box b = ReachableBox(t);
  const double pan_lo = b.pan_lo, pan_hi = b.pan_hi, tilt_lo = b.tilt_lo, tilt_hi = b.tilt_hi;
  const bool any_pan = b.any_pan;
  const double f_lo = b.f_lo, f_hi = b.f_hi;
  // The margin of a pan and tilt: the focal lengths that keep X inside the image are (0, f_in]
  // (the zoom scales the pixel about the principal point), those meeting the density [needed, inf);
  // the setting is feasible when [max(needed, f_lo), min(f_in, f_hi)] is not empty. Relative to
  // f_hi, negated for the minimiser; the focal is the widest that meets the density.
  auto focal_at = [&](double pan, double tilt, double* focal) {
    double lo = 0, hi = 0;
    if (!ZoomInterval(X, pan, tilt, nullptr, min_px_per_m_, f_lo, f_hi, &lo, &hi)) return -kInf;
    *focal = lo;
    return (hi - lo) / f_hi;
  };
  const std::optional<Window> w = SearchWindow(h, k, from_, X, f_lo, !any_pan, pan_lo, pan_hi,
                                               tilt_lo, tilt_hi, [](double az) { return az; });
  if (!w || w->empty()) return std::nullopt;
  // A feasible setting is enough for reach; only a lattice point within kNear of feasible is
  // refined (the margin changes by less than that between lattice points).
  constexpr double kNear = 0.1;
  double best_p = 0, best_q = 0, best_f = f_lo;
  const double shortfall = MinimiseOverWindow(
      *w, kInf,
      [&](double p, double q) {
        double f;
        return -focal_at(p, q, &f);
      },
      [](double v) { return v <= 0; }, [&](double v) { return v > 0 && v < kNear; }, 400, &best_p,
      &best_q);
  if (!(shortfall <= 0)) return std::nullopt;
  focal_at(best_p, best_q, &best_f);
  PtzState s;
  s.pan_deg = h.WrapPan(best_p);
  s.tilt_deg = best_q;
  s.focal = best_f;
  return s;
}

bool PtzReach::Reachable(const Vec3& X, double t, const Vec3* normal, Ray* segment,
                         double epsilon) const {
  const std::optional<PtzState> s = BestPose(X, t);
  if (!s) return false;
  // The density was met when BestPose chose the zoom (up to rounding: not tested twice).
  return PtzSees(base_, head_, *s, X, 0.0, normal, segment, epsilon);
}

double PtzReach::ReachTime(const Vec3& X, const Vec3* normal, double tolerance_s,
                           PtzState* pose) const {
  const double target = min_px_per_m_ > 0 ? min_px_per_m_ * (1 - 1e-12) : 0.0;
  // The centred pose's reach (closed form per time, bisection over time): an upper bound.
  auto centred = [&](double t, PtzState* s) {
    const std::optional<PtzState> c = CentredPose(X, t);
    if (!c || !PtzSees(base_, head_, *c, X, target, normal)) return false;
    if (s) *s = *c;
    return true;
  };
  PtzState best;
  double t_c = kInf;
  if (centred(0.0, &best)) {
    t_c = 0.0;
  } else if (centred(max_time_, nullptr)) {
    double lo = 0.0, hi = max_time_;
    while (hi - lo > tolerance_s) {
      const double mid = 0.5 * (lo + hi);
      (centred(mid, nullptr) ? hi : lo) = mid;
    }
    t_c = hi;
    centred(hi, &best);
  }
  // Off-centre settings: the least move time over every setting that sees X. Skipped when the
  // zoom alone needs nearly t_c: off the axis the density grows by at most boost_.
  bool search = t_c > 0;
  if (search && std::isfinite(t_c) && min_px_per_m_ > 0) {
    double needed = 0;
    bool clamped = false;
    CentredPose(X, t_c, &needed, &clamped);
    const double zoom_rate = head_.zoom_speed * (head_.focal_max - head_.focal_min);
    if (!clamped && zoom_rate > 0 &&
        (needed / boost_ - from_.focal) / zoom_rate >= t_c - tolerance_s)
      search = false;
  }
  if (search) {
    PtzState off;
    const double t_s = FastestSetting(X, normal, t_c, &off);
    if (t_s < t_c) t_c = t_s, best = off;
  }
  if (pose && std::isfinite(t_c)) *pose = best;
  return t_c;
}

double PtzReach::FastestSetting(const Vec3& X, const Vec3* normal, double bound,
                                PtzState* pose) const {
  const PtzHead& h = head_;
  const Intrinsics& k = base_.model.intrinsics();
  const double zoom_rate = h.zoom_speed * (h.focal_max - h.focal_min);
  const double target = min_px_per_m_ > 0 ? min_px_per_m_ * (1 - 1e-12) : 0.0;
  // A pan and tilt's score: (shortfall, time). Shortfall 0: the setting shows X, and time is the
  // move to it and the zoom into the interval of focal lengths that keep X inside the image
  // (0, f_in] (the zoom scales the pixel about the principal point) and meet the density
  // [needed, inf), nearest the current zoom. Otherwise how far that interval is from existing
  // (relative focal length), so that the search climbs towards settings that show X.
  using Score = std::pair<double, double>;
  const Score kNone{kInf, kInf};
  const double f_lo = zoom_rate > 0 ? h.focal_min : from_.focal,
               f_hi = zoom_rate > 0 ? h.focal_max : from_.focal;
  auto score = [&](double pan, double tilt, PtzState* out) -> Score {
    double lo = 0, hi = 0;
    if (!ZoomInterval(X, pan, tilt, normal, target, f_lo, f_hi, &lo, &hi)) return kNone;
    if (lo > hi) return {(lo - hi) / std::max(h.focal_max, from_.focal), kInf};
    PtzState s;
    s.pan_deg = h.WrapPan(pan);
    s.tilt_deg = tilt;
    s.focal = std::clamp(from_.focal, lo, hi);
    if (out) *out = s;
    return {0.0, h.MoveTime(from_, s)};
  };

  // The window around centring X at the widest zoom; a continuous pan centred on the turn of the
  // azimuth nearest the current pan.
  const double widest = std::min(h.focal_min > 0 ? h.focal_min : k.fx, k.fx);
  const std::optional<Window> w = SearchWindow(
      h, k, from_, X, widest, !h.ContinuousPan(), h.pan_min_deg, h.pan_max_deg, h.tilt_min_deg,
      h.tilt_max_deg, [&](double az) { return from_.pan_deg + Wrap180(az - from_.pan_deg); });
  if (!w || w->empty()) return kInf;
  // The least time, to the pattern search's resolution.
  double best_p = 0, best_q = 0;
  const Score best = MinimiseOverWindow(
      *w, kNone, [&](double p, double q) { return score(p, q, nullptr); },
      [](const Score&) { return false; }, [](const Score&) { return true; }, 600, &best_p, &best_q);
  const double best_t = best.first == 0.0 ? best.second : kInf;
  if (!(best_t < bound)) return kInf;
  PtzState s;
  if (score(best_p, best_q, &s).first != 0.0) return kInf;
  // Checked by the one-setting test (and its density, up to rounding).
  if (!PtzSees(base_, head_, s, X, target * (1 - 1e-9), normal)) return kInf;
  if (pose) *pose = s;
  return best_t;
}

}  // namespace pandora
