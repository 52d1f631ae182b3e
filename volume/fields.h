#pragma once
/// \file fields.h
/// Field evaluation over the study region into sparse OpenVDB grids. This header does not include
/// OpenVDB; volume/fields_vdb.h gives access to the grids themselves.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "volume/active_set.h"

namespace pandora {

class SolidTrees;

/// The fields (names from FieldNames(), analysis/scene/scene.h):
///  - "coverage"   Int32: number of cameras that see the voxel centre. Active on every free region
///                 voxel (0 where none sees it); culled blocks are stored as constant tiles.
///  - "cameras"    the set of cameras that see each voxel, kept sparse: one BoolGrid per camera of
///                 the rig (Fields::Impl::visible[c], active and true where camera c sees the
///                 voxel; written to fields.vdb as "visible/<id>"). Any number of cameras.
///  - "resolution" Float, px/m: the best pixel density (PixelDensity of the projection Jacobian)
///  among
///                 the cameras that see the voxel. Active where at least one camera sees it.
///  - "sigma_max", "sigma_mean" Float, mm: worst-direction and RMS 1-sigma of the static
///                 triangulation covariance (analysis/geometry/uncertainty.h);
///                 "triangulation_angle" Float, degrees: largest angle between two rays that see
///                 the voxel; "condition" Float: cond(J). Active where the voxel is triangulable
///                 (>= 2 cameras, observable).
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
  /// Fill FieldStats::sigma_max_mm (sigma_max_steady_mm) also where the evaluation's sigma_max
  /// (sigma_max_steady) grid holds the very same values. false: one evaluation (EvaluateFields)
  /// leaves such a list empty, and Summarize reads the grid instead (8 bytes per triangulable
  /// voxel less with both; `pandora analyze`). An evaluator that keeps state always fills them.
  bool value_lists = true;
  /// One evaluation only (EvaluateFields, or an evaluator without kept state; an evaluator that
  /// keeps state holds every grid): the float fields listed here are not held as they are
  /// evaluated. Each block's leaf goes to an unnamed temporary file in `spill_folder` as the block
  /// finishes (volume/leaf_spill.h); the fields then hold them in Fields::Impl::spilled, not in
  /// Fields::Impl::floats, until WriteFieldsVdb reads them back one at a time. For fields nothing
  /// reads before they are written (`pandora analyze`: 50 MB per field at 11 M voxels). Errors
  /// creating or writing the file blame `spill_blame`.
  std::vector<std::string> spilled_fields;
  std::string spill_folder, spill_blame;
  /// Try every camera pair for triangulation_angle instead of only those whose angle bound can
  /// still win (the same values, more work): for tests and benchmarks.
  bool exhaustive_angle_pairs = false;
  /// Time the uncertainty fields' own steps (FieldStats::phases), two clock reads per step and
  /// block or camera: for `pandora bench`, which reports them from an evaluation of their own.
  bool time_phases = false;
  /// Set from another thread to stop FieldEvaluator::Update early; the evaluator then keeps the
  /// fields of the previous update (nothing half updated). Checked once per block.
  const std::atomic<bool>* cancel = nullptr;
  /// Used in error messages.
  std::string scene_path;
  /// Where `fields` came from, for error messages: empty for the scene file's $.study.fields,
  /// else the option's field ("{fields}": Python's evaluate(fields=...)).
  std::string fields_option;
  /// Where the voxel size came from, for error messages: empty for the scene file's
  /// $.study.voxel_size, else the command-line option (e.g. "{voxel_size}").
  std::string voxel_size_option;
  /// Set when the memory budget came from a command-line option (its name): an over-budget error
  /// then blames that option, unless the voxel size came from an option too.
  std::string memory_budget_option;
  /// Distributed evaluation (`pandora analyze --mpi`, docs/scale.md): this process evaluates only
  /// the blocks of partition `partition_rank` of `partition_count`, a static load balance that
  /// every process computes alike (blocks by estimated cost, free voxels times candidate cameras,
  /// largest first, each to the least loaded partition). The other blocks' voxels stay inactive and
  /// out of the statistics until MergePartialFields (volume/fields_transfer.h) adds them. For one
  /// full evaluation (EvaluateFields, or an evaluator without kept state); 1: every block.
  int partition_count = 1, partition_rank = 0;
  /// Coarse-to-fine refinement (app/session/accuracy.h RunRefineStudy): when set, only the lattice
  /// voxels (i, j, k) it returns true for are evaluated; the others stay inactive and out of the
  /// statistics. The evaluated voxels get exactly the values a full evaluation gives them. Called
  /// once per free region voxel while the active set is built, from worker threads.
  std::function<bool(int i, int j, int k)> voxel_filter;
  /// A streamed evaluation's tile (`pandora analyze --stream`, docs/scale.md): when set, only the
  /// blocks of these block columns are evaluated, the rest of the region stays inactive and out of
  /// the statistics; the memory estimate is the tile's. Every evaluated voxel gets exactly the
  /// values of a full evaluation, so the tiles' union is the full evaluation's fields.
  std::optional<BlockColumns> tile;
  /// The scene's solid and region-mesh search trees, kept between evaluations (a study's,
  /// volume/solid_trees.h); nullptr: the evaluation builds the ones it needs and drops them.
  const SolidTrees* solid_trees = nullptr;

  /// Checks the options against `scene` (FieldEvaluator does before it evaluates): at least one
  /// field, each known and listed once, steady-state ones only with a motion model; a memory
  /// budget > 0; 1 <= partition_count and 0 <= partition_rank < partition_count. InputError naming
  /// the scene file's JSON path ($.study.fields[i]) or the option's field (fields_option,
  /// memory_budget_option; {partition_count}).
  void Check(const Scene& scene) const;
};

/// Counts and timing of one evaluation.
struct FieldStats {
  ActiveSetStats active_set;
  std::int64_t seen_voxels = 0;          ///< Voxels seen by at least one camera.
  std::int64_t triangulable_voxels = 0;  ///< >= 2 cameras and observable (when computed).
  std::int64_t unobservable_voxels = 0;  ///< >= 2 cameras but a direction unobservable.
  /// sigma_max (mm) of every triangulable voxel, unsorted; filled when an uncertainty field is
  /// computed (for percentiles). Likewise sigma_max_steady when a motion model is set. Left empty
  /// where the grid of that field holds the values and FieldOptions::value_lists is false.
  std::vector<float> sigma_max_mm, sigma_max_steady_mm;
  std::vector<std::int64_t> coverage_histogram;  ///< [k] = voxels seen by exactly k cameras.
  std::vector<std::int64_t> per_camera_seen;     ///< [c] = voxels camera c sees.
  std::int64_t point_camera_tests = 0;  ///< (voxel, camera) pairs decided, culled blocks included.
  std::int64_t rays = 0;                ///< Occlusion segments cast.
  double seconds = 0;                   ///< Wall time of the whole evaluation.
  /// CPU time of the process during the evaluation (all threads). On a shared machine it is less
  /// disturbed by other work than the wall time; `pandora bench` prints ratios of both.
  double cpu_seconds = 0;
  double active_set_seconds = 0;  ///< Of which building the active set.
  double estimated_bytes = 0;     ///< The memory estimate checked against the budget.
  /// triangulation_angle's work in this evaluation or update: (voxel, camera pair) dot products
  /// computed, and those an all-pairs search would compute (docs/performance.md).
  std::int64_t angle_pairs_tried = 0, angle_pairs_all = 0;
  /// With FieldOptions::time_phases: seconds (summed over the threads) in the steps that only the
  /// uncertainty fields take, each already vectorised over a block's voxels: the contributions
  /// J^T J of seen voxels (with their bands), the exact sums (limbs), the 3x3 eigenvalues and the
  /// exact best camera pair and its angle. Zero otherwise.
  struct Phases {
    double contributions = 0, sums = 0, eigenvalues = 0, angles = 0;
    double Total() const { return contributions + sums + eigenvalues + angles; }
  } phases;
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

/// An upper bound of the memory the fields of `lattice` may need (grids at full density plus
/// working buffers), in bytes.
double EstimateFieldBytes(const VoxelLattice& lattice, const std::vector<std::string>& fields,
                          int camera_count);

/// The memory the scene's structures hold while fields are evaluated (its meshes, the ray caster's
/// BVH, the solids' search trees, the triangles in double precision when a PTZ tour has a moving
/// centre), in bytes: counted in the memory budget with the fields'.
double SceneStructureBytes(const Scene& scene);

/// The tiles of a streamed evaluation (`pandora analyze --stream`, docs/scale.md): rectangles of
/// whole block columns that cover the lattice's columns once, row by row along y, then x. With
/// `tile_side` > 0 (metres) each tile is that wide (rounded to whole 8-voxel blocks, at least one);
/// otherwise the tiles are as few and as square as keep each one's EstimateFieldBytes within half
/// of `budget_bytes` (the other half for the scene, its BVH and search trees, and writing). A
/// single column over that target still makes a tile of its own (the evaluation then refuses it).
std::vector<BlockColumns> PlanTiles(const VoxelLattice& lattice,
                                    const std::vector<std::string>& fields, double budget_bytes,
                                    double tile_side);

/// What one FieldEvaluator::Update did.
struct FieldUpdate {
  bool full = false;        ///< Every camera was evaluated (the first update, or all changed).
  int changed_cameras = 0;  ///< Cameras re-cast: moved, re-aimed, new intrinsics, (dis)abled.
  std::int64_t dirty_blocks = 0;  ///< 8^3 blocks inside a changed camera's old or new frustum.
  std::int64_t dirty_voxels = 0;  ///< Voxels whose values were recomputed.
  std::int64_t rays = 0;          ///< Occlusion segments cast by this update.
  double seconds = 0;             ///< Wall time of the update.
  bool cancelled = false;         ///< FieldOptions::cancel was set: nothing changed.
};

/// What moved between two scenes (FieldEvaluator::UpdateScene): boxes around every triangle that
/// differs, where it was and where it is.
struct SceneChange {
  std::vector<Aabb> before, after;
};

/// The incremental field evaluator. It keeps, per 8^3 block, which cameras see which voxel (a
/// 512-bit mask per camera that sees the block: sparse, any number of cameras) and each seen
/// (voxel, camera) pair's information contribution and pixel density. When cameras change it
/// re-casts only those cameras, only inside their old and new frusta, and re-derives only the
/// voxels whose camera set or contributions changed. Coverage (a count), the best density (a
/// maximum) and the information (an exact fixed-point sum, so independent of order) are updated
/// from the changed cameras alone and equal what a full evaluation computes from all of them: the
/// fields equal a full recompute voxel for voxel, bit for bit
/// (docs/architecture.md; test volume/field_evaluator_test.cpp). The scene and the ray caster must
/// outlive the evaluator.
class FieldEvaluator {
 public:
  /// Checks the field list and the memory budget as EvaluateFields does (same InputErrors) and
  /// builds the active set's region and solid classification once. `keep_state` false: one
  /// evaluation only, the per-pair data is dropped block by block (EvaluateFields' memory).
  FieldEvaluator(const Scene& scene, const RayCaster& caster, FieldOptions options,
                 bool keep_state = true);
  ~FieldEvaluator();
  FieldEvaluator(FieldEvaluator&&) noexcept;
  FieldEvaluator& operator=(FieldEvaluator&&) noexcept;

  /// Brings the fields up to date with `rig`: the first call evaluates every enabled camera; later
  /// calls compare the rig camera by camera with the previous one (pose, lens, range, pixel sigma,
  /// enabled; cameras added or removed at the end count as changed) and update only what changed.
  /// The rig may have any number of cameras. Returns what it did; on cancellation the previous
  /// fields stay. Throws InputError when the kept state would exceed the memory budget.
  FieldUpdate Update(const Rig& rig);

  /// Brings the fields up to date with a new `scene` and its `caster` (the next time sample of a
  /// scene with moving objects): the same study, rig and camera geometry, where every triangle
  /// that differs from the previous scene's lies inside one of the `moved` boxes, in its old place
  /// (SceneChange::before) and in its new one (after). Re-builds the active set (a moved solid
  /// takes its voxels out of the region), evaluates anew the blocks whose free voxels changed, and
  /// elsewhere re-casts only the (block, camera) pairs whose segments can meet a moved box; only
  /// the voxels a camera sees now and did not, or the reverse, are re-derived. The fields equal a
  /// full evaluation of `scene` voxel for voxel, bit for bit (test volume/time_fields_test.cpp).
  /// Evaluates in full when nothing is kept, or when the scene's extent (the visibility tolerance's
  /// scale) changed; before the first Update (or after a cancelled one) only takes the new scene.
  /// Not cancellable. `scene` and `caster` must outlive the evaluator or the next UpdateScene.
  FieldUpdate UpdateScene(const Scene& scene, const RayCaster& caster, const SceneChange& moved);

  const Fields& fields() const;
  /// Replaces FieldOptions::progress and FieldOptions::cancel for the next updates (a session's
  /// background job passes its own).
  void SetCallbacks(std::function<void(double)> progress, const std::atomic<bool>* cancel);
  /// Moves the fields out (the evaluator is then empty: the next Update evaluates in full).
  Fields TakeFields();
  /// Bytes held for incremental updates (masks, per-pair contributions, per-voxel caches).
  double state_bytes() const;

  struct State;

 private:
  std::unique_ptr<State> state_;
};

/// Evaluates the requested fields for the enabled cameras of `rig` over `scene.study.region`: one
/// FieldEvaluator update without kept state. Throws InputError when the memory estimate exceeds the
/// budget (path "$.study.voxel_size", with the smallest voxel size that fits in the hint), when a
/// field name is unknown ("$.study.fields"), or when a steady-state field is asked for without
/// study.motion. Runs in parallel with TBB (limit threads with tbb::global_control).
Fields EvaluateFields(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const FieldOptions& options);

}  // namespace pandora
