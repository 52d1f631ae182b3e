#pragma once
/// \file suggest.h
/// Suggest and accept (issue 5): nudge the cameras the person selected, within the limits the
/// person set, to improve an objective over target points; the other cameras stay fixed. The
/// optimiser (Ceres, suggest/suggest_ceres.cpp) works on a smooth surrogate of visibility; every
/// candidate is judged by the exact evaluation (the visibility rules of the volume fields), and a
/// suggestion is offered only when the exact objective improved. This header is light: no Ceres, no
/// JSON.
///
/// Units: metres and radians inside; the CLI and the suggestion file speak metres and degrees.

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/geometry.h"
#include "analysis/geometry/pose.h"  // the Euler angles snap_rotate_deg rounds
#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"

namespace pandora {

/// Where a camera's centre may go, besides the largest move.
struct MountConstraint {
  enum class Kind {
    kFree,   ///< Anywhere within max_move of the start.
    kPlane,  ///< On the plane through the start centre with normal `axis` (a wall, a ceiling).
    kLine,   ///< On the line through the start centre along `axis` (a ceiling rail).
    kBox,    ///< Inside `box` (which must hold the start centre).
  };
  Kind kind = Kind::kFree;
  Vec3 axis = Vec3::UnitZ();  ///< Plane normal or line direction (any length > 0).
  Aabb box;
};

/// The limits of one selected camera.
struct CameraLimits {
  double max_move = 0.3;  ///< Largest distance of the new centre from the start, metres (>= 0).
  double max_rotate_deg =
      10.0;  ///< Largest rotation angle between start and new orientation (>= 0).
  /// Zoom range: the horizontal field of view (degrees, FocalFromHfov for the camera's lens model)
  /// may change within [min_hfov_deg, max_hfov_deg], which must hold the current one. Both 0: the
  /// focal length stays. A zoom scales fx and fy together; principal point and distortion stay.
  double min_hfov_deg = 0, max_hfov_deg = 0;
  MountConstraint mount;
};

/// What to optimise. Every objective is judged on the target points with the exact visibility
/// rules.
enum class ObjectiveKind {
  kCoverage,         ///< Share of target points seen by at least `k` cameras (higher is better).
  kSigmaMean,        ///< Mean sigma_max in mm (lower); untriangulable points count as `sigma_cap`.
  kSigmaPercentile,  ///< The `percentile` of sigma_max in mm (lower); untriangulable points are
                     ///< +inf, and while the percentile is +inf a smaller untriangulable share is
                     ///< better.
  kResolution,  ///< Minimum over the points of the best pixel density, px/m (higher); unseen: 0.
  kMix,         ///< Weighted mix of the three, each relative to its value at the start (higher).
  /// N-1: the share of target points still seen by at least `k` cameras after the worst single
  /// camera failure (any enabled camera, selected or fixed, fails; the worst is the one that leaves
  /// the smallest share), as volume/robustness.h defines it for the fields (higher).
  kCoverageN1,
  /// Calibration connectivity (needs the study's "calibration", docs/calibration.md): the strength
  /// of the calibration chain, the largest number of shared target poses w such that the cameras
  /// sharing >= w poses connect every enabled camera (the weakest edge of the maximum spanning tree
  /// of the co-visibility graph; 0 while some camera shares no pose with the rest). Every camera is
  /// calibratable with the rest when it is >= the study's min_shared (higher).
  kCalibration,
};

struct Objective {
  ObjectiveKind kind = ObjectiveKind::kCoverage;
  int k = 2;               ///< For coverage (and the mix's coverage term), >= 1.
  double percentile = 90;  ///< For kSigmaPercentile, in (0, 100].
  /// Weights of the mix: coverage share, sigma (start mean / mean), resolution (min / start min).
  double w_coverage = 1, w_sigma = 1, w_resolution = 1;
};

/// Parses an objective name: "coverage" / "coverageK" (K = 1..64, e.g. "coverage2"), "sigma-mean",
/// "sigma-pNN" (e.g. "sigma-p90"), "resolution", "mix", "coverage-n1" / "coverageK-n1" (e.g.
/// "coverage3-n1"), "calibration". Returns nullopt for anything else.
std::optional<Objective> ParseObjective(const std::string& name);
/// The canonical name ("coverage2", "sigma-p90", ...).
std::string ObjectiveName(const Objective& objective);
/// True when larger values of the objective are better (coverage, resolution, mix).
bool ObjectiveHigherIsBetter(const Objective& objective);

/// A target point: in the region (no normal) or on a target surface (with its outward unit normal,
/// which must face a camera for it to count, as in VisibilityTester).
struct TargetPoint {
  Vec3 p = Vec3::Zero();
  std::optional<Vec3> normal;
  /// The time sample the point belongs to (SuggestOptions::sample_casters); 0 for a static scene.
  int sample = 0;
};

/// Samples `count` target points. With no surface names: stratified jittered samples of the study
/// region, without the points inside solid objects (the volume fields leave those voxels inactive).
/// With surface names (SceneObject::name, or a prefix "name/" for a mesh with several parts): area-
/// weighted samples on those objects' triangles with their normals; `count` in all, split between
/// region and surfaces when `include_region` is also true. Deterministic for a seed. Throws
/// InputError (file = scene.path) for an unknown surface name or when no point can be placed.
std::vector<TargetPoint> SampleTargets(const Scene& scene, int count,
                                       const std::vector<std::string>& surfaces,
                                       bool include_region, std::uint64_t seed);

/// Exact measures over the target points.
struct Metrics {
  double objective = 0;   ///< The objective's value (see ObjectiveKind).
  double coverage_k = 0;  ///< Share seen by >= objective.k cameras.
  double coverage2 = 0;   ///< Share seen by >= 2 cameras.
  /// sigma_max percentiles (mm) over all target points; +inf where the rank falls on an
  /// untriangulable point (written as null with "untriangulable" in files).
  double sigma_p50 = 0, sigma_p90 = 0, sigma_p95 = 0;
  double sigma_mean = 0;      ///< Mean sigma_max (mm), untriangulable points counted as the cap.
  double untriangulable = 0;  ///< Share of points that are not triangulable.
  double min_resolution = 0;  ///< px/m; 0 when some point is seen by no camera.
  /// With the N-1 objective: the share seen by >= k cameras after the worst single failure, and
  /// that camera's id (the first in rig order on a tie; empty without enabled cameras).
  struct N1 {
    double coverage_k = 0;
    std::string worst_camera;
  };
  std::optional<N1> n1;
  /// With the calibration objective: the co-visibility graph of the study's calibration poses.
  struct Calibration {
    std::int64_t weakest = 0;          ///< The chain's strength, poses (the objective).
    std::string weakest_a, weakest_b;  ///< The cameras of that weakest spanning-tree edge.
    std::int64_t tree_total = 0;  ///< Shared poses summed over the maximum spanning tree's edges.
    int components = 0;           ///< Components of the graph of edges >= min_shared.
    int uncalibratable = 0;       ///< Enabled cameras outside the largest one (CalibrationGraph).
    std::int64_t poses = 0;       ///< Calibration poses simulated.
  };
  std::optional<Calibration> calibration;
};

/// One selected camera's result.
struct CameraChange {
  int index = -1;  ///< In the rig.
  std::string id;
  Eigen::Isometry3d before = Eigen::Isometry3d::Identity();  ///< world_from_camera at the start.
  Eigen::Isometry3d after = Eigen::Isometry3d::Identity();
  double move_m = 0;       ///< |centre change|, metres.
  double rotate_deg = 0;   ///< Angle of the relative rotation, degrees.
  double focal_scale = 1;  ///< fx_after / fx_before (1 without a zoom range).
  double hfov_before_deg = 0, hfov_after_deg = 0;  ///< Horizontal field of view, degrees.
  /// Distance from the centre to the nearest scene surface before and after, metres (infinity in a
  /// scene without geometry).
  double surface_distance_before = 0, surface_distance_after = 0;
  /// A message when this camera could not help (for example it sees none of the target and the
  /// surrogate has no gradient); empty otherwise.
  std::string note;
};

/// The exact objective as the optimisation went: seconds since start against the best value so far.
struct TracePoint {
  double seconds = 0;
  std::int64_t evaluations = 0;  ///< Surrogate + exact evaluations so far.
  double objective = 0;          ///< Best exact objective so far.
};

struct SuggestOptions {
  std::vector<int> cameras;  ///< Rig indices of the selected cameras (distinct, enabled).
  /// With moving objects: the ray caster of each time sample (RigidPartsRayCaster::At); target
  /// point i is tested against sample_casters[targets[i].sample]. Empty: the static caster for all.
  /// The casters must outlive the call.
  std::vector<const RayCaster*> sample_casters;
  std::vector<CameraLimits> limits;  ///< One per selected camera, or one for all.
  std::vector<Aabb> keep_out;        ///< Boxes no selected camera centre may enter.
  /// Metres every suggested camera centre keeps from every scene surface (any object's triangles:
  /// walls, floor, furniture, solid or not). A camera that starts closer may stay or move away but
  /// never closer than it starts. 0: no clearance.
  double clearance = 0.1;
  Objective objective;
  int outer_iterations = 4;       ///< Occlusion re-evaluated between them.
  int max_inner_iterations = 30;  ///< Ceres iterations per outer iteration.
  /// Candidate poses per active camera at each of the three radii of the exact screening before the
  /// Ceres nudge (three chains; see suggest_search.cpp), for coverage objectives (N-1 included);
  /// the others, whose exact evaluation costs more, get a quarter. 0: no screening, the nudge
  /// starts from the current poses only.
  int screening_candidates = 200;
  /// Installable steps (0: none): each camera's centre is rounded per axis of its mount: along a
  /// mount direction that is a world axis (free and box mounts, axis-aligned rails and planes) to a
  /// coordinate that is a multiple of snap_move (metres: so the scene file shows k * step), along
  /// an oblique one to a move that is a multiple of it; its yaw / pitch / roll change (scene-format
  /// Euler angles) to multiples of snap_rotate_deg. Never beyond the limits or the placement rules
  /// (the nearest grid point, else the one towards the start, else the start position); then
  /// evaluated again.
  double snap_move = 0, snap_rotate_deg = 0;
  /// Used in error messages (the option or JSON path that set the selection and limits).
  std::string scene_path;
  /// Called on the searching thread with the fraction done in [0, 1]: the screening's chains up
  /// to 0.3, then the nudge's outer iterations. Empty: not called.
  std::function<void(double fraction)> progress;
  /// Polled between exact evaluations (a screening candidate, a Ceres step); once set, the search
  /// stops and Suggest returns the best poses judged so far, snapped as asked, with
  /// Suggestion::stopped (the viewer's Cancel). Null: never. Must outlive the call.
  const std::atomic<bool>* cancel = nullptr;

  /// Checks the options against `rig` (of `scene`): a selection of distinct, enabled, fixed
  /// cameras, limits (one set or one per camera) that hold each camera's current pose and field of
  /// view, mounts with a direction, boxes that hold the cameras, finite non-negative clearance and
  /// snap steps, k in 1..64. InputError naming the field at fault as `{field}` ({cameras},
  /// {max_move}, {hfov_range}, ...), which each front end writes its own way.
  void Check(const Scene& scene, const Rig& rig) const;
};

struct Suggestion {
  bool improved = false;  ///< The exact objective improved: the poses are worth offering.
  std::string message;    ///< One line: what happened (always set).
  bool stopped = false;   ///< SuggestOptions::cancel ended the search early.
  Objective objective;
  std::vector<CameraChange> cameras;
  Metrics before, after;  ///< Exact; `after` at the returned poses (the start when not improved).
  std::optional<Metrics> unsnapped;  ///< The optimum before snapping, when snapping was asked for.
  int iterations = 0;                ///< Ceres iterations, all outer iterations together.
  int outer_iterations = 0;
  std::int64_t evaluations = 0;   ///< Surrogate + exact evaluations.
  int screened = 0;               ///< Exact evaluations up to the end of the screening.
  double screened_objective = 0;  ///< The best exact objective at the end of the screening.
  double seconds = 0;
  std::vector<TracePoint> trace;
  int target_points = 0;
};

/// The exact evaluation of a rig over target points (the selected cameras' poses may be replaced).
/// Builds one VisibilityTester over the enabled cameras with the real ray caster.
Metrics EvaluateExact(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const std::vector<TargetPoint>& targets, const Objective& objective,
                      const std::vector<const RayCaster*>& sample_casters = {});

/// Target points on the surfaces of the study's targets (Study::targets) at every time sample:
/// `points` per target spread by area (seeded), each moved with its group to every sample, with the
/// sample's index. What a suggestion optimises to see moving bodies over time. Throws InputError
/// (file = scene.path, "$.study.targets") when the study has no targets.
std::vector<TargetPoint> SampleTimeTargets(const Scene& scene,
                                           const std::vector<TimeSample>& samples, int points,
                                           std::uint64_t seed);

/// Checks the selection and the limits (throws InputError naming `options.scene_path` and the
/// option) and runs the Ceres nudge. Every candidate pose keeps the limits, the keep-out boxes and
/// the clearance (SuggestOptions::clearance). Deterministic.
Suggestion Suggest(const Scene& scene, const Rig& rig, const RayCaster& caster,
                   const std::vector<TargetPoint>& targets, const SuggestOptions& options);

/// The baseline: random perturbations of the selected cameras within the same limits (Gaussian,
/// standard deviation 0.25 of each limit per parameter, around the best so far, projected onto the
/// limits), each judged by the exact objective, the better kept, until `evaluation_budget`
/// evaluations are spent. With `adaptive_step` the step size follows the 1/5 success rule (x1.5 on
/// success, x1.5^-1/4 on failure). Same result structure and trace.
Suggestion BaselineSearch(const Scene& scene, const Rig& rig, const RayCaster& caster,
                          const std::vector<TargetPoint>& targets, const SuggestOptions& options,
                          std::int64_t evaluation_budget, std::uint64_t seed,
                          bool adaptive_step = false);

/// Moves each listed camera `move` metres in a random direction and turns it `rotate_deg` about a
/// random axis perpendicular to its optical axis (a pan / tilt away from where it looked; seeded),
/// for benchmarks of recovery. Returns the perturbed rig.
Rig PerturbCameras(const Rig& rig, const std::vector<int>& cameras, double move, double rotate_deg,
                   std::uint64_t seed);

}  // namespace pandora
