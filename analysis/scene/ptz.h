#pragma once
/// \file ptz.h
/// Pan-tilt-zoom cameras (the Pandora paper's section 6; docs/ptz.md). A PTZ camera is a camera of
/// a rig with a "ptz" block: its file pose is the **home** pose (the neutral orientation at the
/// pivot, the point where the pan and tilt axes meet); pan turns about the pan axis (fixed to the
/// base, a world direction), tilt about the camera's image x axis after the pan, zoom scales the
/// focal lengths about the principal point. The centre of projection may sit `offset` from the
/// pivot (camera frame), as it does in real domes; the paper assumed none.
///
/// Everything else in Pandora sees a PTZ camera at its **current** pan, tilt and zoom (Camera's
/// pose and intrinsics are those); the head here gives the poses it can reach and how long that
/// takes: each axis moves at its own constant speed, all at once, so a move takes the longest of
/// the three axis times.
///
/// Light header (Eigen only).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/geometry/ray_caster.h"  // Ray

namespace pandora {

struct Camera;
class RayCaster;
class VisibilityTester;

/// A pan / tilt / zoom setting. Angles in degrees relative to home; `focal` in pixels (fx; fy
/// scales with it).
struct PtzState {
  double pan_deg = 0, tilt_deg = 0, focal = 0;
};

/// A named setting (a preset of the camera's controller).
struct PtzPreset {
  std::string name;
  PtzState state;
};

/// One stop of a tour: a preset and how long the camera stays there.
struct PtzTourStop {
  int preset = 0;  ///< Index into PtzHead::presets.
  double dwell_s = 0;
};

/// The mechanics of a PTZ camera.
struct PtzHead {
  Eigen::Isometry3d home = Eigen::Isometry3d::Identity();  ///< world_from_camera at pan = tilt = 0.
  Vec3 pan_axis = Vec3::UnitZ();  ///< World, unit; the home image x axis is perpendicular to it.
  Vec3 offset = Vec3::Zero();     ///< Centre of projection from the pivot, camera frame, metres.
  double pan_min_deg = -180, pan_max_deg = 180;  ///< A span of 360 or more: continuous pan.
  double tilt_min_deg = -90, tilt_max_deg = 90;  ///< Relative to home (positive: up).
  double focal_min = 0, focal_max = 0;           ///< Zoom range, pixels (wide to tele).
  double pan_speed_deg_s = 90, tilt_speed_deg_s = 60;
  double zoom_speed =
      0.5;  ///< Fraction of [focal_min, focal_max] per second (the paper's %/s / 100).
  double home_focal = 0;  ///< The zoom at home (default: the widest, focal_min).
  double trace_s = 3;     ///< The default time budget of the traces, seconds.
  PtzState current;       ///< The setting the camera is at (its Camera pose and intrinsics).
  std::vector<PtzPreset> presets;
  std::vector<PtzTourStop> tour;

  /// Home elevation of the optical axis above the plane perpendicular to the pan axis, degrees.
  double HomeElevationDeg() const;
  bool ContinuousPan() const { return pan_max_deg - pan_min_deg >= 360.0; }
  PtzState Home() const { return {0.0, 0.0, home_focal}; }

  /// world_from_camera at `s` (rotation and the centre moved by the offset).
  Eigen::Isometry3d Pose(const PtzState& s) const;
  /// `base` (the camera as the file describes it, any current state) at setting `s`: its pose, and
  /// its focal lengths scaled to s.focal about the principal point.
  Camera CameraAt(const Camera& base, const PtzState& s) const;

  /// Seconds to move from `a` to `b`, every axis at once at its speed: max(|dpan| / pan speed,
  /// |dtilt| / tilt speed, |dfocal| / zoom speed). A continuous pan takes the shorter way round.
  double MoveTime(const PtzState& a, const PtzState& b) const;
  /// The setting `t` seconds into the move from `a` to `b` (each axis moving at its speed until it
  /// arrives; b itself from MoveTime(a, b) on).
  PtzState Along(const PtzState& a, const PtzState& b, double t) const;
  /// Pan `deg` wrapped to the pan range when continuous (else unchanged).
  double WrapPan(double deg) const;
  /// The paper's "path": the settings from `a` to `b` one per second (a at 0 s, then 1 s, 2 s, ...)
  /// and b itself last (at MoveTime(a, b)); just {a} when a == b.
  std::vector<PtzState> Path(const PtzState& a, const PtzState& b) const;

  /// One leg of a tour: the move from the previous stop's preset to this stop's, then the dwell.
  struct TourLeg {
    double start = 0;   ///< Seconds into the period when the move begins.
    double move_s = 0;  ///< MoveTime(from, to).
    double dwell_s = 0;
    PtzState from, to;
    int stop = 0;  ///< Index into `tour`.
    double end() const { return start + move_s + dwell_s; }
  };
  /// The tour's legs in `order` (indices into `tour`, each once; empty: the file's order): time 0
  /// is when the move into the first stop begins (from the last stop's preset), so the period is
  /// the sum of every move and dwell. Empty without a tour.
  std::vector<TourLeg> TourLegs(const std::vector<int>& order = {}) const;
  /// The setting `t` seconds into the tour of `legs` (t taken modulo the period).
  PtzState TourState(const std::vector<TourLeg>& legs, double t) const;
  /// A step (seconds) for sampling a move from `a` to `b` so that the view turns by at most a
  /// quarter of the narrower field of view along it (the narrowest zoom the move passes through).
  double SampleStep(const Camera& base, const PtzState& a, const PtzState& b) const;
  /// The fastest the centre of projection moves (m/s): it turns about the pivot at |offset| with an
  /// angular velocity of at most pan + tilt speed (the zoom does not move it).
  double CentreSpeedBound() const;
  /// Whether a tour moves the centre of projection: an offset and at least two stops (a move).
  bool TourMovesCentre() const { return !offset.isZero(0.0) && tour.size() >= 2; }
};

/// Whether `base` at setting `s` of `head` sees X geometrically: inside the image (lens and
/// distortion), within range, facing `normal` when given, and at a pixel density of at least
/// `min_px_per_m` (0: any). Occlusion is not tested: on success `segment` (when given) receives the
/// segment from the setting's centre to X, `epsilon` short of both ends.
bool PtzSees(const Camera& base, const PtzHead& head, const PtzState& s, const Vec3& X,
             double min_px_per_m = 0, const Vec3* normal = nullptr, Ray* segment = nullptr,
             double epsilon = 0);

/// Whether `segment` (from PtzSees, untrimmed) is blocked, with the occlusion tolerance of rig
/// camera `camera` at both ends (VisibilityTester::Tolerance); `rays` (when given) counts the cast.
bool PtzSegmentOccluded(const VisibilityTester& tester, int camera, Ray segment,
                        std::int64_t* rays = nullptr);

/// What PtzSees's geometric test of a point depends on besides the setting.
struct PtzTarget {
  Vec3 X = Vec3::Zero();
  double min_px_per_m = 0;
  const Vec3* normal = nullptr;
  /// For a head whose centre moves: the tester (and its camera) whose occlusion `sees` tests; when
  /// it holds the scene's triangles (VisibilityTester::surfaces()), WatchTour certifies the
  /// occlusion along each move with PtzSweptOcclusion instead of sampling it.
  const VisibilityTester* tester = nullptr;
  int camera = -1;
};

/// For a head whose centre moves (an offset): whether the occlusion segments (PtzSegmentOccluded)
/// of camera `camera` from every centre within `r` of `centre` to X all miss the scene (+1) or all
/// cross it (-1), certified in double precision on tester.surfaces() (SurfaceDistance::ConeClear,
/// with the tolerance of the shortest segment; ConeBlocked, with the longest's); 0 when neither
/// holds or the tester has no triangles.
int PtzSweptOcclusion(const VisibilityTester& tester, int camera, const Vec3& centre, double r,
                      const Vec3& X);

/// Where, in [t_begin, t_end] of the move from `from` to `to` (PtzHead::Along times), the
/// occlusion segment (PtzSegmentOccluded) from the moving centre to target.X is clear: the span is
/// cut in halves until PtzSweptOcclusion certifies each piece (the centre within
/// CentreSpeedBound() x half its length of the piece's middle). A piece left uncertain once the
/// centre moves less than the occlusion tolerance within it (the segment within the tolerance of
/// an edge throughout) or once it is 1 us long takes the occlusion test at its ends, a change
/// between them bisected to 1 us: a visibility shorter than that much motion of the centre is below
/// the tolerance. Clear intervals in order, merged; nullopt when more than `max_certificates`
/// certificates would be needed or target.tester holds no triangles. The geometry (PtzSees) is not
/// tested: the caller knows it sees X throughout.
std::optional<std::vector<std::pair<double, double>>> PtzMoveClearWindows(
    const PtzHead& head, const PtzState& from, const PtzState& to, double t_begin, double t_end,
    const PtzTarget& target, int max_certificates = 4096);

/// Where along the move from `from` to `to` (PtzHead::Along, t in [0, move_s]) the answer of
/// PtzSees(base, head, setting, target...) can change, found without sampling: [0, move_s] is
/// subdivided until each piece is certified, from bounds on how fast every margin of the test can
/// change (range and facing with the centre's speed, the four image edges and the density with the
/// view's turn rate, at most pan + tilt speed, and the zoom's rate; docs/ptz.md), to keep its sign,
/// or to fail one condition throughout. Returns the pieces left uncertain, each at most
/// `resolution_s` long, adjacent ones merged, in order: between two of them the answer is constant,
/// and every change lies inside one. nullopt for a lens with distortion (the bounds are the
/// pinhole's) or when more than `max_evaluations` tests would be needed.
std::optional<std::vector<std::pair<double, double>>> PtzMoveChanges(
    const PtzHead& head, const Camera& base, const PtzState& from, const PtzState& to,
    double move_s, const PtzTarget& target, double resolution_s = 1e-6,
    int max_evaluations = 200000);

/// The intervals of a tour's period during which a point is watched: `sees` (a setting -> bool
/// test, e.g. PtzSees plus occlusion) is evaluated once per dwell and, along each move, once per
/// piece of constant geometry that PtzMoveChanges certifies when `target` is given (the point and
/// density `sees` tests) and the lens is undistorted: then every window is found, however short,
/// its ends to PtzMoveChanges's resolution (1 us). With a zero offset (the centre fixed, so the
/// occlusion constant along a move) the answer is exact. With an offset and target->tester holding
/// the scene's triangles, each piece where the geometry sees X is cut further until the occlusion
/// of every centre in a piece is certified (PtzMoveClearWindows): exact too, each change to 1 us,
/// but for visibilities shorter than the centre's move across the occlusion tolerance. Otherwise (a
/// lens with distortion, no target, no triangles, or more than 4096 certificates in one piece),
/// along each move every PtzHead::SampleStep, each change refined by bisection to `tolerance_s`:
/// there a visibility shorter than the step may be missed (docs/ptz.md).
struct PtzWatch {
  double period = 0;
  std::vector<std::pair<double, double>> intervals;  ///< Sorted, disjoint, within [0, period].
  double watched_s() const;
  /// The longest stretch without watching, the tour repeating (period when never watched, 0 when
  /// always).
  double longest_gap_s() const;
};
template <typename Sees>
PtzWatch WatchTour(const PtzHead& head, const Camera& base,
                   const std::vector<PtzHead::TourLeg>& legs, Sees&& sees,
                   const PtzTarget* target = nullptr, double tolerance_s = 1e-3);

/// The sweep of the traces: what a PTZ camera can see from `from` within a time budget. With a
/// zero offset the answer for a point depends only on its direction from the pivot, and the pose
/// that best shows it is found in closed form (docs/ptz.md): the reachable pan nearest to the
/// point's azimuth, then the tilt that puts it on the image's horizontal midline (clamped to the
/// reachable tilts); with an offset the pose is refined by a fixed point (the centre moves with the
/// pose), which is exact to O(offset / distance)^2.
class PtzReach {
 public:
  /// `base` is the camera (its lens, range and current state); `head` its mechanics. With
  /// `min_px_per_m` > 0 a point counts as seen only at a pixel density of at least that: the zoom
  /// is the widest reachable one that meets it there.
  PtzReach(const Camera& base, const PtzHead& head, const PtzState& from, double min_px_per_m = 0);

  /// The best pose for seeing `X` among the settings reachable within `t` seconds from `from`
  /// (widest reachable zoom, or with a density target the widest reachable one meeting it); nullopt
  /// when X lies behind every such pose or no reachable zoom meets the density target.
  /// The point centred when that sees it (pan towards its azimuth, tilt to the image's midline,
  /// the zoom as above); otherwise an off-centre setting that does, if any (SearchPose), since a
  /// point's density grows towards the image's edges and a clamped pan or tilt may still leave it
  /// in a corner.
  std::optional<PtzState> BestPose(const Vec3& X, double t) const;
  /// The centred pose alone (the closed form above), whether or not it sees X.
  /// `needed_focal` (when given) receives the focal length the density target needs at that pose
  /// (0 without a target), `clamped` whether the reachable pan or tilt kept X off the centre.
  std::optional<PtzState> CentredPose(const Vec3& X, double t, double* needed_focal = nullptr,
                                      bool* clamped = nullptr) const;
  /// Some setting reachable within `t` that sees X (inside the image, within range, at the density
  /// target), found by maximising the feasible zoom interval's width over pan and tilt (a 9 x 9
  /// lattice over the angles within the widest reachable view's half diagonal of centring X, then a
  /// pattern search to 1e-7 degrees); nullopt when none is found.
  std::optional<PtzState> SearchPose(const Vec3& X, double t) const;
  /// True when some setting reachable within `t` sees X geometrically: inside the image (lens and
  /// distortion), within range, and facing `normal` when given. Occlusion is not tested: the
  /// segment from the centre at BestPose to X is returned in `segment` (t_near / t_far with the
  /// visibility tolerance of `epsilon`) for the caller to cast.
  bool Reachable(const Vec3& X, double t, const Vec3* normal = nullptr, Ray* segment = nullptr,
                 double epsilon = 0) const;
  /// The shortest time after which X is geometrically reachable by any setting, off-centre ones
  /// included (bisection to `tolerance_s` on Reachable, which is monotone in t: the reachable box
  /// only grows); +inf when X is not reachable at all.
  /// `pose` (when given and the time is finite) receives a setting that sees X at that time.
  /// The centred pose's reach time (bisection) bounds it; FastestSetting then looks for a faster
  /// off-centre setting (docs/ptz.md; tested against a brute-force lattice).
  double ReachTime(const Vec3& X, const Vec3* normal = nullptr, double tolerance_s = 1e-4,
                   PtzState* pose = nullptr) const;
  /// The least move time from `from` to any setting that sees X (inside the image, within range,
  /// facing `normal`, at the density target), when below `bound`; +inf otherwise. A 9 x 9 lattice
  /// over the pans and tilts within the widest view's half diagonal (a quarter more) of centring X,
  /// then a pattern search to 1e-7 degrees; each pan and tilt takes the zoom nearest the current
  /// one that keeps X inside the image and meets the density.
  double FastestSetting(const Vec3& X, const Vec3* normal, double bound,
                        PtzState* pose = nullptr) const;
  /// The longest move from `from` to any setting (the budget beyond which nothing new is reached).
  double MaxTime() const { return max_time_; }

 private:
  const Camera& base_;
  const PtzHead& head_;
  PtzState from_;
  double min_px_per_m_ = 0;
  double max_time_ = 0;
  // The settings reachable within t: pan (any, when a continuous pan can turn a full turn), tilt
  // and focal intervals, and the zoom rate (pixels per second; 0 without zoom).
  struct Box {
    double pan_lo = 0, pan_hi = 0, tilt_lo = 0, tilt_hi = 0, f_lo = 0, f_hi = 0, zoom_rate = 0;
    bool any_pan = false;
  };
  Box ReachableBox(double t) const;
  // The focal lengths [lo, hi] within [f_lo, f_hi] at which the setting (pan, tilt) shows X: inside
  // the image (hi: the zoom scales the pixel about the principal point), at `target` px/m (lo);
  // lo > hi when none does. False when X is out of range, faces away from `normal` or does not
  // project at all.
  bool ZoomInterval(const Vec3& X, double pan, double tilt, const Vec3* normal, double target,
                    double f_lo, double f_hi, double* lo, double* hi) const;
  double boost_ = 1.02;  // the lens's largest density gain off the axis (constructor), with 2 %
};

// ---- implementation of WatchTour ----

template <typename Sees>
PtzWatch WatchTour(const PtzHead& head, const Camera& base,
                   const std::vector<PtzHead::TourLeg>& legs, Sees&& sees, const PtzTarget* target,
                   double tolerance_s) {
  PtzWatch w;
  if (legs.empty()) return w;
  w.period = legs.back().end();
  auto add = [&w](double a, double b) {
    if (!(b > a)) return;
    if (!w.intervals.empty() && a <= w.intervals.back().second + 1e-12)
      w.intervals.back().second = std::max(w.intervals.back().second, b);
    else
      w.intervals.emplace_back(a, b);
  };
  const bool fixed_centre = head.offset.isZero(0.0);
  for (const PtzHead::TourLeg& leg : legs) {
    auto at = [&](double t) { return sees(head.Along(leg.from, leg.to, t)); };
    // [t_begin, t_end] of the move sampled every step, each change bisected.
    auto scan = [&](double t_begin, double t_end) {
      const double length = t_end - t_begin;
      if (!(length > 0)) return;
      const double step = std::min(head.SampleStep(base, leg.from, leg.to), length);
      const int n = std::max(1, static_cast<int>(std::ceil(length / step - 1e-9)));
      double t0 = t_begin;
      bool s0 = at(t0);
      double open = s0 ? t0 : -1.0;
      for (int i = 1; i <= n; ++i) {
        const double t1 = i == n ? t_end : t_begin + i * step;
        const bool s1 = at(t1);
        if (s1 != s0) {
          double lo = t0, hi = t1;  // sees(lo) == s0, sees(hi) == s1
          while (hi - lo > tolerance_s) {
            const double mid = 0.5 * (lo + hi);
            (at(mid) == s0 ? lo : hi) = mid;
          }
          const double change = 0.5 * (lo + hi);
          if (s1) {
            open = change;
          } else {
            add(leg.start + open, leg.start + change);
            open = -1.0;
          }
        }
        t0 = t1;
        s0 = s1;
      }
      if (open >= 0) add(leg.start + open, leg.start + t_end);
    };
    if (leg.move_s > 0) {
      std::optional<std::vector<std::pair<double, double>>> changes;
      if (target) changes = PtzMoveChanges(head, base, leg.from, leg.to, leg.move_s, *target);
      if (!changes) {
        scan(0.0, leg.move_s);
      } else {
        // Pieces of constant geometry between the uncertain spans; a change inside a span (at most
        // 1 us) is put at its middle. Spans merged longer than 1 ms (a margin staying at zero) are
        // scanned.
        double begin = 0.0;      // where the current piece starts (a span's middle)
        double certified = 0.0;  // where its certified part starts
        auto piece = [&](double end, double certified_end) {
          if (!(end > begin)) return;
          const PtzState mid = head.Along(leg.from, leg.to, 0.5 * (certified + certified_end));
          if (fixed_centre) {
            if (sees(mid)) add(leg.start + begin, leg.start + end);
          } else if (PtzSees(base, head, mid, target->X, target->min_px_per_m, target->normal)) {
            // The geometry sees X throughout; the moving centre's occlusion certified, else
            // sampled.
            const std::optional<std::vector<std::pair<double, double>>> clear =
                PtzMoveClearWindows(head, leg.from, leg.to, begin, end, *target);
            if (!clear)
              scan(begin, end);
            else
              for (const auto& [a, b] : *clear) add(leg.start + a, leg.start + b);
          }
        };
        for (const auto& [lo, hi] : *changes) {
          if (hi - lo > 1e-3) {
            piece(lo, lo);
            scan(lo, hi);
            begin = certified = hi;
            continue;
          }
          const double middle = 0.5 * (lo + hi);
          piece(middle, lo);
          begin = middle;
          certified = hi;
        }
        piece(leg.move_s, leg.move_s);
      }
    }
    if (leg.dwell_s > 0 && sees(leg.to)) add(leg.start + leg.move_s, leg.end());
  }
  return w;
}

}  // namespace pandora
