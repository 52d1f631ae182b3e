#pragma once
/// \file suggest_internal.h
/// Shared by suggest.cpp, suggest_search.cpp and suggest_ceres.cpp (not installed, no Ceres): the
/// exact evaluator with the fixed cameras' contributions precomputed, and the pose parameterisation
/// of a selected camera.

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "analysis/geometry/surface_distance.h"
#include "analysis/geometry/visibility.h"
#include "analysis/rig/calibration.h"
#include "suggest/suggest.h"

namespace pandora::suggest_detail {

/// Per target point: what the fixed (unselected, enabled) cameras contribute, exactly.
struct FixedContribution {
  std::vector<int> count;    ///< Cameras that see the point.
  std::vector<Mat3> J;       ///< Information sum A^T A / sigma^2, 1/m^2.
  std::vector<double> dmax;  ///< Best pixel density, px/m (0 when none sees it).
  std::vector<double> dpow;  ///< Sum over seeing cameras of (d / density_scale)^kSoftMaxPower.
  /// N-1 objective only: per point the fixed cameras (indices into the fixed list) that see it.
  std::vector<std::vector<int>> seen_by;
};

inline constexpr double kSoftMaxPower = 8.0;

/// What one selected camera at one pose sees of the target points, exactly (the visibility rules of
/// ExactEvaluator::Evaluate): lets a search that moves one camera at a time reuse the others'
/// views.
struct CameraView {
  std::vector<std::uint8_t> seen;  ///< 1 where the camera sees the point.
  std::vector<Mat3> info;          ///< A^T A / sigma^2 where seen (zero elsewhere), 1/m^2.
  std::vector<double> density;     ///< Pixel density where seen, px/m (0 elsewhere).
  /// Calibration objective only: bit p set where the camera observes calibration pose p.
  std::vector<std::uint64_t> calib;
};

/// Exact evaluation with the fixed cameras precomputed: only the selected cameras are tested again
/// at each candidate pose.
class ExactEvaluator {
 public:
  ExactEvaluator(const Scene& scene, const Rig& rig, const RayCaster& caster,
                 const std::vector<TargetPoint>& targets, const Objective& objective,
                 const std::vector<int>& selected,
                 const std::vector<const RayCaster*>& sample_casters = {});

  /// Metrics with the selected cameras at `poses` (world_from_camera, one per selected camera) and,
  /// when given, their focal lengths scaled by `focal_scales`.
  Metrics Evaluate(const std::vector<Eigen::Isometry3d>& poses,
                   const std::vector<double>& focal_scales = {}) const;
  /// The view of selected camera `c` at `pose` (focal lengths scaled by `focal_scale`). Not counted
  /// as an evaluation: Combine counts.
  CameraView View(int c, const Eigen::Isometry3d& pose, double focal_scale = 1.0) const;
  /// Metrics with the selected cameras seeing what `views` say (one per selected camera): equal to
  /// Evaluate at the poses the views were made at. Counts one evaluation. With `objective_only` and
  /// a coverage objective only `objective` and `coverage_k` are set (no covariances: faster); the
  /// other objectives always get the full metrics.
  Metrics Combine(const std::vector<const CameraView*>& views, bool objective_only = false) const;
  /// The full metrics of a combination already evaluated with Combine (not counted again).
  Metrics Summary(const std::vector<const CameraView*>& views) const;
  /// Higher is better; -inf for an infinite sigma percentile.
  double Score(const Metrics& m) const;
  /// The mix objective is relative to the start: call once with the start metrics.
  void SetReference(double sigma_mean_mm, double min_resolution) {
    ref_sigma_mean_ = sigma_mean_mm;
    ref_min_resolution_ = min_resolution;
  }

  const FixedContribution& fixed() const { return fixed_; }
  const std::vector<TargetPoint>& targets() const { return targets_; }
  const std::vector<Camera>& selected_cameras() const { return selected_; }
  const Objective& objective() const { return objective_; }
  double scene_scale() const { return scene_scale_; }
  double region_scale() const { return region_scale_; }
  double density_scale() const { return density_scale_; }
  double sigma_cap_mm() const { return sigma_cap_mm_; }
  double PixelSigma(const Camera& c) const {
    return c.pixel_sigma > 0 ? c.pixel_sigma : pixel_sigma_;
  }
  const RayCaster& caster() const { return caster_; }
  /// Occluded() of rays laid out as [k * targets().size() + i] (k any number of rounds), each
  /// against the caster of target i's time sample.
  void OccludedByPoint(const std::vector<Ray>& rays, std::vector<uint8_t>* occluded) const;
  std::int64_t evaluations() const { return evaluations_; }

 private:
  Metrics Summarise(const std::vector<int>& count, const std::vector<Mat3>& J,
                    const std::vector<double>& dmax,
                    const std::vector<const CameraView*>& views) const;
  // The N-1 and calibration measures of the objectives that need them, from the counts and views.
  void AddObjectiveMeasures(const std::vector<int>& count,
                            const std::vector<const CameraView*>& views, Metrics* m) const;
  // Which calibration poses camera `camera` of `tester` observes, as bits.
  std::vector<std::uint64_t> CalibrationBits(const VisibilityTester& tester, int camera) const;
  static std::int64_t SharedBits(const std::vector<std::uint64_t>& a,
                                 const std::vector<std::uint64_t>& b);

  // One tester per time sample's caster for `cameras`; target i uses testers[Sample(i)].
  std::vector<std::unique_ptr<VisibilityTester>> Testers(const std::vector<Camera>& cameras) const;
  std::size_t Sample(std::size_t i) const {
    const int s = targets_[i].sample;
    return s >= 0 && std::size_t(s) < casters_.size() ? std::size_t(s) : 0;
  }

  const RayCaster& caster_;
  std::vector<const RayCaster*> casters_;  // per time sample; {&caster_} for a static scene
  std::vector<TargetPoint> targets_;
  Objective objective_;
  std::vector<Camera> selected_;
  FixedContribution fixed_;
  double scene_scale_ = 1, region_scale_ = 1, density_scale_ = 1, sigma_cap_mm_ = 1;
  double geometry_scale_ = 1;  // ContentBounds diagonal: the visibility tolerance's scale
  double pixel_sigma_ = 0.5;
  double ref_sigma_mean_ = 0, ref_min_resolution_ = 0;
  mutable std::int64_t evaluations_ = 0;
  // Camera ids: the fixed (enabled, unselected) cameras in rig order, then the selected ones.
  std::vector<std::string> fixed_ids_;
  std::vector<int> fixed_rig_, selected_rig_;  // rig indices
  // Calibration objective: the study's spec, its poses (drawn once for the starting rig), what each
  // fixed camera observes (bits) and the fixed cameras' shared counts.
  CalibrationSpec calib_spec_;
  std::vector<CalibrationPose> calib_poses_;
  std::vector<std::vector<std::uint64_t>> calib_fixed_;
  std::vector<std::vector<std::int64_t>> calib_fixed_shared_;
};

/// How a selected camera's pose is parameterised: x = (translation coordinates, rotation vector),
/// each scaled so that +-1 is the limit. Centre = C0 + basis * (x_t * max_move); rotation
/// R = R0 * Exp(x_r * max_rotate) (a rotation vector in the camera frame around the start pose, a
/// chart of SO(3) valid for angles below 180 degrees, so the rotation limit is a bound).
struct PoseChart {
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  double max_move = 0, max_rotate = 0;             // metres, radians
  Eigen::Matrix<double, 3, Eigen::Dynamic> basis;  // orthonormal columns (0 to 3)
  MountConstraint mount;
  int dims_t = 0, dims_r = 0, dims_f = 0;  // translation, rotation, zoom (last)
  double log_focal_range = 0;              // the zoom parameter is ln(f / f0) / log_focal_range
  int dims() const { return dims_t + dims_r + dims_f; }
  double FocalScale(const double* x) const {
    return dims_f > 0 ? std::exp(x[dims_t + dims_r] * log_focal_range) : 1.0;
  }
  std::vector<double> lower, upper;  // bounds of x

  static PoseChart Make(const Camera& camera, const CameraLimits& limits);
  Eigen::Isometry3d Pose(const double* x) const;
  /// Projects x onto the limits (norms <= 1, bounds); true when the result is admissible.
  void Project(double* x) const;
};

/// True when `p` lies inside a keep-out box (closed).
bool InKeepOut(const std::vector<Aabb>& keep_out, const Vec3& p);

/// Where the selected cameras' centres may go besides their limits: outside every keep-out box, and
/// at least `required(c)` from every scene surface: the clearance, or for a camera that starts
/// closer than that its start distance (it may stay or move away, never closer).
class Placement {
 public:
  Placement(const Scene& scene, const Rig& rig, const SuggestOptions& options);
  /// Distance from `p` to the nearest scene surface, metres (capped at `limit`).
  double SurfaceDistanceAt(const Vec3& p,
                           double limit = std::numeric_limits<double>::infinity()) const {
    return distance_.Distance(p, limit);
  }
  double required(std::size_t c) const { return required_[c]; }
  /// Metres by which `centre` of selected camera c is closer to a surface than required (0: none).
  double ClearanceDeficit(std::size_t c, const Vec3& centre) const {
    if (!(required_[c] > 0)) return 0.0;
    return std::max(0.0, required_[c] - distance_.Distance(centre, required_[c]));
  }
  bool Admissible(std::size_t c, const Vec3& centre) const {
    return !InKeepOut(keep_out_, centre) && ClearanceDeficit(c, centre) <= 0.0;
  }
  const std::vector<Aabb>& keep_out() const { return keep_out_; }

 private:
  std::vector<Aabb> keep_out_;
  SurfaceDistance distance_;
  std::vector<double> required_;  // per selected camera, metres
};

/// The limits of selected camera i.
const CameraLimits& LimitsOf(const SuggestOptions& options, std::size_t i);

/// The common start of every search: each selected camera's pose chart and start pose, and the
/// suggestion's "before" metrics (with the mix objective's reference scales set from them).
struct SearchStart {
  std::vector<PoseChart> charts;
  std::vector<Eigen::Isometry3d> start;
  Suggestion suggestion;
};
SearchStart BeginSearch(const Rig& rig, const SuggestOptions& options, int target_points,
                        ExactEvaluator& ev);

/// Rounds the change of each camera to the snap steps, within the limits and the placement rules;
/// returns the new poses.
std::vector<Eigen::Isometry3d> SnapPoses(const std::vector<PoseChart>& charts,
                                         const std::vector<Eigen::Isometry3d>& poses,
                                         const SuggestOptions& options, const Placement& placement);

/// Fills the per-camera change records (`focal_scales` empty: no zoom).
void FillChanges(const Rig& rig, const SuggestOptions& options,
                 const std::vector<Eigen::Isometry3d>& poses,
                 const std::vector<double>& focal_scales, const Placement& placement,
                 Suggestion* s);

/// The camera with its focal lengths scaled by `scale` (principal point and distortion kept).
Camera Zoomed(const Camera& camera, double scale);

double RotationAngleDeg(const Mat3& a, const Mat3& b);

}  // namespace pandora::suggest_detail
