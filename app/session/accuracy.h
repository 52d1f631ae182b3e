#pragma once
/// \file accuracy.h
/// The accuracy studies behind `pandora accuracy` (issue 3, point 6): error against run time for
/// the approximations Pandora makes or could make.
///   (a) voxel size: the coverage and uncertainty summaries at coarser and finer voxels against the
///       finest size evaluated (RunVoxelStudy);
///   (b) Monte Carlo: the sample covariance of Ceres triangulations of noisy pixels against the
///       closed-form prediction J^-1, with the prediction's own cost (RunMonteCarloStudy);
///   (c) steady state: the closed form, doubling and plain Riccati iteration in double against the
///       long-double reference (analysis/geometry/uncertainty_reference.h) (RunSteadyStudy);
///   (e) coarse-to-fine: a coarse evaluation refined where the field changes, against the full
///       evaluation at the study's voxel size (RunRefineStudy, refine_study.cpp);
///   (f) Monte Carlo gate per voxel: at randomly sampled voxels seen by >= 2 cameras, the sample
///       covariance of 2,000 noisy triangulations against the predicted one, axis by axis
///       (eigenvalues and eigenvector directions) (RunGateStudy, monte_carlo_gate.cpp).
/// Each returns a typed result (rows and notes); app/report/accuracy_tables.h turns them into the
/// tables, CSV files and plots. Timings are wall times on this machine.
///
/// Plain header: no OpenVDB, Ceres or Embree (the studies use volume/ and
/// analysis/geometry/triangulation inside accuracy.cpp).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/scene/scene.h"

namespace pandora {

class SolidTrees;

/// Sizes of the studies. The defaults are the full study; Quick() the short one the tests run.
struct AccuracyOptions {
  /// Voxel sizes as multiples of the study's voxel_size, coarse to fine; the last evaluated is the
  /// reference. Each > 0.
  std::vector<double> voxel_factors{4, 2, 1, 0.5, 0.25};
  /// A finer size is not evaluated when 8 times the previous size's time exceeds this (seconds).
  double max_reference_seconds = 30;
  /// Sample points of the Monte Carlo study (>= 1): centres of the region's 3 x 3 x 3 cells seen
  /// by at least two cameras, spread evenly.
  int sample_points = 5;
  /// Monte Carlo trial counts (each >= 2), one row each.
  std::vector<int> trials{100, 300, 1000, 3000, 10000};
  /// Each timing repeats its call in doubling batches until this many seconds have passed (> 0).
  double min_timing_seconds = 0.05;
  /// Steps of the "tolerance 0" Riccati iteration, which never stops early (>= 1).
  int run_on_iterations = 1000000;
  /// Seed of the Monte Carlo noise: the first (trial count, point) run uses it, each next one the
  /// next integer (MonteCarloCovariance seeds its trials from it).
  std::uint64_t seed = 1;
  /// Monte Carlo gate (f): voxels sampled (>= 1) and noisy triangulations per voxel (>= 2).
  int gate_voxels = 100;
  int gate_trials = 2000;

  /// The short study: factors 4, 2, 1, 0.5; 3 points; 100 .. 3000 trials; 0.01 s timings; 1e5
  /// run-on steps; a gate of 12 voxels (still 2,000 trials each).
  static AccuracyOptions Quick();

  /// Throws InputError(file = the field's name, e.g. "trials", json_path "", reason) when a value
  /// is outside the range documented above.
  void Check() const;
};

// ---------------------------------------------------------------------------------------------
// (a) Voxel size.

/// One voxel size.
struct VoxelRow {
  double factor = 1, voxel_size = 0;  ///< Multiple of the study's; metres.
  std::int64_t region_voxels = 0, triangulable_voxels = 0;
  double seconds = 0;  ///< Best evaluation wall time over `repeats`.
  int repeats = 0;     ///< Small evaluations are repeated (best of up to 5, within ~0.3 s).
  double ge[3] = {kNaN, kNaN, kNaN};            ///< Coverage >= 1, 2, 3 cameras (fractions).
  double p50 = kNaN, p90 = kNaN;                ///< sigma_max percentiles, mm (NaN: none).
  double steady_p50 = kNaN, steady_p90 = kNaN;  ///< Steady-state ones (NaN without a motion model).
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
};

struct VoxelStudy {
  std::vector<VoxelRow> rows;      ///< Coarse to fine; the last is the reference.
  std::vector<std::string> notes;  ///< Sizes skipped, and why.
  bool steady = false;             ///< The study has a motion model: steady-state columns.
};

/// Evaluates coverage, sigma_max and sigma_mean (and their steady-state forms with a motion model)
/// at each voxel size of options.voxel_factors until one would exceed the memory budget or the time
/// limit. Throws InputError as EvaluateFields (except over-budget sizes, which end the study with a
/// note).
VoxelStudy RunVoxelStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                         const AccuracyOptions& options);

// ---------------------------------------------------------------------------------------------
// (b) Monte Carlo.

/// A point of the region seen by at least two enabled cameras.
struct SamplePoint {
  Vec3 X = Vec3::Zero();
  std::vector<Camera> cameras;  ///< The enabled cameras that see X (exact visibility).
  Information info;             ///< Of those cameras at the study's pixel sigma.
  double sigma_max = 0;         ///< Predicted, m.
};

/// The centres of the region box's 3 x 3 x 3 cells that at least two cameras of `rig` see (exact
/// visibility, occlusion included), then `wanted` of them spread evenly over that list (first and
/// last kept). `info` and `sigma_max` are left to the caller.
std::vector<SamplePoint> SamplePoints(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                      std::size_t wanted);

/// The closed-form prediction at one point: Jacobians, information, eigen-decomposition, J^-1,
/// every camera with pixel noise `sigma_px`. `info` (if given) receives the decomposed information.
StaticUncertainty PredictUncertainty(const SamplePoint& point, double sigma_px,
                                     Information* info = nullptr);

/// The note the Monte Carlo studies add when an enabled camera of `rig` sets its own pixel sigma
/// (they use the study's `sigma_px` for every camera); empty when none does.
std::string OwnPixelSigmaNote(const Rig& rig, double sigma_px);

/// One trial count over every sample point.
struct MonteCarloRow {
  int trials = 0, points = 0, failures = 0;
  double seconds_per_point = 0;
  double rel_mean = 0, rel_max = 0;    ///< |sigma_max empirical / predicted - 1|, over the points.
  double frob_mean = 0, frob_max = 0;  ///< Frobenius relative error of the covariance.
};

struct MonteCarloStudy {
  std::vector<SamplePoint> points;  ///< Triangulable ones.
  std::vector<MonteCarloRow> rows;
  /// Per point, single thread (NaN: no point).
  double prediction_seconds = std::numeric_limits<double>::quiet_NaN();
  /// Monte Carlo time per point for 1% mean sigma_max error (power-law fit; NaN: none).
  double seconds_for_1pct = std::numeric_limits<double>::quiet_NaN();
  double sigma_px = 0;  ///< The study's pixel sigma, used for every camera.
  std::vector<std::string> notes;
};

/// Picks options.sample_points sample points, predicts sigma_max at each (dropping those that are
/// not triangulable), times the prediction, runs MonteCarloCovariance
/// (analysis/geometry/triangulation.h) for each trial count and fits a power law of the mean error
/// against time for the 1% crossing.
MonteCarloStudy RunMonteCarloStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                   const AccuracyOptions& options);

/// The least-squares line log(y) = a + b log(x) through the points with x > 0 and y > 0, and the x
/// where it crosses y = `y_target`: NaN with fewer than two such points or when b >= 0 (the error
/// does not fall with time).
double PowerLawCrossing(const std::vector<double>& x, const std::vector<double>& y,
                        double y_target);

// ---------------------------------------------------------------------------------------------
// (c) Steady-state solvers.

/// A motion model the solvers are compared under.
struct SteadyCase {
  std::string name;
  MotionModel motion;
};

/// One solver in one case, per voxel (three axes).
struct SteadyRow {
  std::string case_name, method, label;  ///< label: short method name for the plot's legend.
  MotionModel motion;
  double lambda_min = 0, lambda_max = 0;  ///< Tracking index of the axes, sqrt(q T^3 / r).
  int iterations = 0;                     ///< Largest over the axes; 0 for the closed form.
  bool converged = true;
  bool run_on = false;  ///< Iteration with tolerance 0: runs its step budget, never "converges".
  double seconds = 0;   ///< Per voxel (all three axes).
  double error = 0;  ///< Largest relative error of the posterior position variance over the axes.
};

struct SteadyStudy {
  std::vector<SteadyCase>
      cases;  ///< The study's motion (or "nominal" q 1 at 30 Hz), fast motion, 1 MHz.
  std::vector<SteadyRow>
      rows;               ///< Per case: long-double doubling (the reference's own check),
                          ///< closed form, doubling 2x2 and 6x6, iteration at four tolerances.
  Mat3 J = Mat3::Zero();  ///< The information matrix used (1/m^2).
  std::string J_source;   ///< Where J came from.
  std::vector<std::string> notes;
};

/// Compares the steady-state solvers on the information matrix of the Monte Carlo sample point with
/// the median predicted sigma_max (or an isotropic J for 1 mm when there is none), per eigen-axis,
/// against SteadyPositionVarianceLong.
SteadyStudy RunSteadyStudy(const Scene& scene, const MonteCarloStudy& monte_carlo,
                           const AccuracyOptions& options);

// ---------------------------------------------------------------------------------------------
// (e) Coarse-to-fine evaluation.

/// One coarse voxel size and refinement tolerance.
struct RefineRow {
  int factor = 2;          ///< Coarse voxel = factor x the study's voxel size.
  double tolerance = 0.1;  ///< Relative sigma_max difference between neighbours that refines.
  double coarse_seconds = 0, refine_seconds = 0;  ///< The coarse and the refining evaluations.
  std::int64_t refined_voxels = 0;  ///< Study-size voxels evaluated by the refining pass.
  /// Against the full evaluation at the study's size, over its region voxels: the share whose
  /// coverage count differs (or that the result lacks), %; the relative sigma_max error over the
  /// voxels triangulable in both (median, 99th percentile, largest), %; and the voxels triangulable
  /// in one and not the other.
  double coverage_wrong_pct = 0;
  double class_wrong_pct = 0;  ///< ... whose class 0, 1, 2, >= 3 cameras differs, %.
  double sigma_p50_pct = 0, sigma_p99_pct = 0, sigma_max_pct = 0;
  std::int64_t triangulable_mismatch = 0;
};

struct RefineStudy {
  double voxel_size = 0;         ///< The study's (the reference's), metres.
  double reference_seconds = 0;  ///< The full evaluation at that size (best of up to 3).
  std::int64_t reference_voxels = 0, reference_triangulable = 0;
  std::vector<RefineRow> rows;
  std::vector<std::string> notes;
};

/// Coarse-to-fine: evaluates coverage and sigma_max at `factor` times the study's voxel size, marks
/// the coarse cells where the field changes (a neighbour among the 26 differs in its coverage class
/// 0, 1, 2, >= 3 or in triangulability, or in sigma_max by more than `tolerance` relative, or lies
/// outside the region or in a solid), evaluates the study-size voxels of those cells only
/// (FieldOptions::voxel_filter: exact values there) and gives every other voxel its coarse cell's
/// values; then compares with the full evaluation at the study's size. Rows for factors 2 and 4,
/// tolerances 0.02 and 0.1. `solid_trees` (a study's, may be null): the solids' search trees, kept
/// between the evaluations.
RefineStudy RunRefineStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                           const SolidTrees* solid_trees = nullptr);

// ---------------------------------------------------------------------------------------------
// (f) Monte Carlo gate per voxel.

/// The gate's tolerances: each eigenvalue of the sample covariance (a variance, m^2) within this
/// relative distance of the predicted one, major (largest) to minor, and each resolvable
/// eigenvector within kGateAngleDeg of the predicted one.
inline constexpr double kGateEigenTolerance[3] = {0.10, 0.15, 0.20};
inline constexpr double kGateAngleDeg = 3.0;
/// An axis is resolvable when the sample's own statistical error of its direction, the largest over
/// the other axes j of sqrt(l_i l_j / (n - 1)) / |l_i - l_j| (first-order perturbation of a sample
/// covariance's eigenvectors; n trials, predicted eigenvalues l), is at most this many degrees: at
/// 1 degree the 3-degree tolerance is three standard errors. Nearly equal eigenvalues leave their
/// plane's directions undetermined at any sample count; such axes are counted, not compared.
inline constexpr double kGateResolvableDeg = 1.0;

/// One sampled voxel.
struct GateVoxel {
  Vec3 X = Vec3::Zero();  ///< The voxel's centre, m.
  int cameras = 0;        ///< Enabled cameras that see it (exact visibility).
  double angle_deg = 0;   ///< Largest triangulation angle among them.
  /// Eigenvalues (variances, m^2), largest first: predicted (J^-1) and of the sample covariance.
  double predicted[3] = {0, 0, 0}, empirical[3] = {0, 0, 0};
  /// Angle between each predicted eigenvector and the sample's matching one, degrees (NaN: the
  /// axis is not resolvable at this trial count, see kGateResolvableDeg).
  double axis_deg[3] = {0, 0, 0};
  /// Sample skewness of the errors along the predicted major axis: 0 for the Gaussian the
  /// first-order prediction assumes; large where it stops holding (small angles, grazing views).
  double skew_major = 0;
  int failures = 0;  ///< Trials whose triangulation failed (excluded).
  /// Every eigenvalue within its tolerance and every resolvable axis within kGateAngleDeg.
  bool pass = false;
  double Ratio(int axis) const { return empirical[axis] / predicted[axis]; }
};

struct GateStudy {
  int trials = 0;
  double sigma_px = 0;
  std::vector<GateVoxel> voxels;  ///< In sampling order.
  double seconds = 0;             ///< Wall time of every voxel's trials.
  std::vector<std::string> notes;
  /// Share of the voxels that pass (NaN: no voxel).
  double PassShare() const;
};

/// Samples options.gate_voxels voxel centres of the study region uniformly at random (seeded by
/// options.seed; up to 200 candidates per wanted voxel), keeps those that >= 2 enabled cameras see
/// and that are triangulable, and runs MonteCarloCovariance (options.gate_trials, Ceres) at each
/// at the study's pixel sigma, comparing the sample covariance with J^-1 axis by axis.
GateStudy RunGateStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                       const AccuracyOptions& options);

}  // namespace pandora
