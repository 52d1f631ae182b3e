#pragma once
/// \file fields.h
/// Field evaluation over the study region into sparse OpenVDB grids. This header does not include
/// OpenVDB; volume/fields_vdb.h gives access to the grids themselves.

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/ray_caster.h"
#include "analysis/scene.h"
#include "volume/active_set.h"

namespace pandora {

/// The fields (names from FieldNames(), analysis/scene.h):
///  - "coverage"   Int32: number of cameras that see the voxel centre. Active on every free region
///                 voxel (0 where none sees it); culled blocks are stored as constant tiles.
///  - "cameras"    Int64: bit c set when camera c (index in the rig) sees the voxel. Active where at
///                 least one camera sees it. Up to 64 cameras.
///  - "resolution" Float, px/m: the best pixel density (PixelDensity of the projection Jacobian) among
///                 the cameras that see the voxel. Active where at least one camera sees it.
///  - "sigma_max", "sigma_mean" Float, mm: worst-direction and RMS 1-sigma of the static
///                 triangulation covariance (analysis/uncertainty.h); "triangulation_angle" Float,
///                 degrees: largest angle between two rays that see the voxel; "condition" Float:
///                 cond(J). Active where the voxel is triangulable (>= 2 cameras, observable).
///  - "sigma_max_steady", "sigma_mean_steady" Float, mm: the same for the steady-state Kalman
///                 covariance under study.motion.
/// Options of EvaluateFields.
struct FieldOptions {
  std::vector<std::string> fields{"coverage", "cameras", "resolution"};
  double memory_budget_bytes = 4.0e9;
  /// Called from worker threads with the fraction done in [0, 1]; must be thread-safe and cheap.
  std::function<void(double)> progress;
  /// Keep every occlusion segment cast, in evaluation order (benchmarks replay them).
  bool record_rays = false;
  /// Used in error messages.
  std::string scene_path;
  /// Where the voxel size came from, for error messages: empty for the scene file's
  /// $.study.voxel_size, else the command-line option (e.g. "--voxel-size").
  std::string voxel_size_option;
  /// Set when the memory budget came from a command-line option (its name): an over-budget error
  /// then blames that option, unless the voxel size came from an option too.
  std::string memory_budget_option;
};

/// Counts and timing of one evaluation.
struct FieldStats {
  ActiveSetStats active_set;
  std::int64_t seen_voxels = 0;                ///< Voxels seen by at least one camera.
  std::int64_t triangulable_voxels = 0;        ///< >= 2 cameras and observable (when computed).
  std::int64_t unobservable_voxels = 0;        ///< >= 2 cameras but a direction unobservable.
  /// sigma_max (mm) of every triangulable voxel, unsorted; filled when an uncertainty field is
  /// computed (for percentiles). Likewise sigma_max_steady when a motion model is set.
  std::vector<float> sigma_max_mm, sigma_max_steady_mm;
  std::vector<std::int64_t> coverage_histogram;  ///< [k] = voxels seen by exactly k cameras.
  std::vector<std::int64_t> per_camera_seen;     ///< [c] = voxels camera c sees.
  std::int64_t point_camera_tests = 0;  ///< (voxel, camera) pairs decided, culled blocks included.
  std::int64_t rays = 0;                ///< Occlusion segments cast.
  double seconds = 0;                   ///< Wall time of the whole evaluation.
  /// CPU time of the process during the evaluation (all threads). On a shared machine it is less
  /// disturbed by other work than the wall time; `pandora bench` prints ratios of both.
  double cpu_seconds = 0;
  double active_set_seconds = 0;        ///< Of which building the active set.
  double estimated_bytes = 0;           ///< The memory estimate checked against the budget.
};

/// Opaque holder of the evaluated grids (OpenVDB inside).
class Fields {
 public:
  Fields();
  ~Fields();
  Fields(Fields&&) noexcept;
  Fields& operator=(Fields&&) noexcept;

  VoxelLattice lattice;
  FieldStats stats;
  std::vector<Ray> recorded_rays;  ///< With FieldOptions::record_rays.

  struct Impl;
  Impl& impl() { return *impl_; }
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// An upper bound of the memory the fields of `lattice` may need (grids at full density plus working
/// buffers), in bytes.
double EstimateFieldBytes(const VoxelLattice& lattice, const std::vector<std::string>& fields,
                          int camera_count);

/// Evaluates the requested fields for the enabled cameras of `rig` over `scene.study.region`.
/// Throws InputError when the memory estimate exceeds the budget (path "$.study.voxel_size", with the
/// smallest voxel size that fits in the hint), when a field name is unknown ("$.study.fields"), when
/// a steady-state field is asked for without study.motion, or when the rig has more than 64 cameras. Runs in parallel with TBB (limit threads with
/// tbb::global_control).
Fields EvaluateFields(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const FieldOptions& options);

}  // namespace pandora
