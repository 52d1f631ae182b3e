#pragma once
/// \file summary.h
/// The summary of one field evaluation: a typed value (Summary) that the report, the accuracy
/// studies and the CLI read by member, and its JSON form, the summary.json written by
/// `pandora analyze`. Fractions are of the region's free voxels (`region_voxels`: voxel centres
/// inside the region and outside every solid object).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/rig/calibration.h"
#include "analysis/rig/rig_check.h"
#include "analysis/scene/scene.h"
#include "analysis/scene/surface_targets.h"
#include "volume/fields.h"
#include "volume/pixel_targets.h"
#include "volume/ptz_fields.h"
#include "volume/robustness.h"
#include "volume/time_fields.h"

namespace pandora {

/// Nearest-rank percentiles (each a value that occurs in the data) of the worst-direction 1-sigma
/// over the triangulable voxels, mm; nullopt when no voxel has a value.
struct SigmaPercentiles {
  std::optional<double> p50, p90, p99;
};

/// Nearest-rank percentiles of the resolution field over the voxels seen by at least one camera
/// (each voxel's best camera), px/m; nullopt when no voxel is seen.
struct ResolutionPercentiles {
  std::optional<double> p10, p50, p90;
};

/// Coverage: the share of the free region voxels seen by at least 1, 2, 3 cameras, and the
/// histogram ([k] = voxels seen by exactly k cameras).
struct CoverageSummary {
  double ge1 = 0, ge2 = 0, ge3 = 0;
  std::vector<std::int64_t> histogram;
};

/// One camera of the rig (disabled ones too, in rig order).
struct CameraSummary {
  std::string id, name;
  bool enabled = true;
  std::int64_t visible_voxels = 0;  ///< Free region voxels the camera sees.
  double visible_fraction = 0;      ///< visible_voxels / region_voxels.
  LensCoverage lens;                ///< Nominal and effective FOV, unreachable pixels.
};

/// The triangulation uncertainty (present when an uncertainty field was evaluated).
struct UncertaintySummary {
  double triangulable = 0;  ///< Share of the free region voxels.
  std::int64_t triangulable_voxels = 0, unobservable_voxels = 0;
  double pixel_sigma = 0;  ///< The study's, px.
  SigmaPercentiles sigma_max_mm;
  /// The study's target sigma_max (mm) and the share of the free region voxels meeting it; both
  /// set when the study has a target.
  std::optional<double> max_sigma_mm, meets_max_sigma;
  /// The study's motion model; when set, the steady-state percentiles are reported (null values
  /// when no voxel is triangulable or the steady fields were not asked for) and, with a target, the
  /// share meeting it in the steady state.
  std::optional<MotionModel> motion;
  bool steady_prior = false;  ///< The steady-state fields are the prior covariance.
  SigmaPercentiles sigma_max_steady_mm;
  std::optional<double> meets_max_sigma_steady;
};

/// Counts and timing of the evaluation.
struct TimingSummary {
  double seconds = 0, active_set_seconds = 0;
  std::int64_t rays = 0, point_camera_tests = 0;
  int threads = 0;
  double rays_per_second() const { return seconds > 0 ? rays / seconds : 0.0; }
  double tests_per_second() const { return seconds > 0 ? point_camera_tests / seconds : 0.0; }
};

/// One named sub-region of the study (Study::regions), from the same fields: its free voxels
/// (centres inside it, free in the study region) and their shares.
struct RegionSummary {
  std::string name;
  std::int64_t voxels = 0;
  double ge1 = 0, ge2 = 0, ge3 = 0;
  std::optional<double> resolution_p10;  ///< px/m, with the resolution field.
  std::optional<double> sigma_max_p50,
      sigma_max_p90;        ///< mm, with sigma_max; over its triangulable voxels.
  double triangulable = 0;  ///< Share with a sigma_max (with sigma_max).
};

/// The named sub-regions of `scene`'s study over `fields`.
std::vector<RegionSummary> SummarizeRegions(const Scene& scene, const Fields& fields);

/// What SummarizeRegions reads of one region, before its percentiles: a streamed run adds these up
/// tile by tile (its sigma and density values spilled, volume/value_spill.h).
struct RegionCounts {
  std::int64_t voxels = 0;
  std::int64_t ge[3] = {0, 0, 0};
  std::vector<float> sigmas, densities;  ///< sigma_max and resolution of its voxels that have them
};
/// The counts and values of each of the study's regions over `fields`, in study order.
std::vector<RegionCounts> CountRegions(const Scene& scene, const Fields& fields);
/// A region's summary from its counts; `resolution_p10`, `sigma_p50`, `sigma_p90`: the percentiles
/// of its values (nullopt when none), used when the fields had `has_resolution` / `has_sigma`.
RegionSummary FinishRegion(const std::string& name, const RegionCounts& counts, bool has_resolution,
                           bool has_sigma, std::int64_t sigma_count,
                           std::optional<double> resolution_p10, std::optional<double> sigma_p50,
                           std::optional<double> sigma_p90);

/// Everything summary.json holds, typed.
struct Summary {
  std::string scene, scene_sha256;  ///< Scene::path and Scene::sha256.
  std::string rig;
  int cameras = 0;  ///< Enabled cameras.
  std::vector<std::string> fields;
  double voxel_size_m = 0;
  Aabb region;  ///< The study region's box (a mesh region's bounds).
  Eigen::Vector3i region_dims = Eigen::Vector3i::Zero();  ///< Lattice size, voxels per axis.
  Region::Kind region_kind = Region::Kind::kBox;
  std::int64_t region_voxels = 0, solid_voxels = 0;
  std::int64_t active_voxels = 0;  ///< Seen by at least one camera.
  CoverageSummary coverage;
  std::optional<ResolutionPercentiles> resolution_px_per_m;  ///< With the resolution field.
  std::vector<CameraSummary> per_camera;
  std::optional<UncertaintySummary> uncertainty;  ///< With an uncertainty field.
  std::vector<Warning> warnings;                  ///< CheckRig's, in order.
  TimingSummary timing;
  /// With moving objects: the fields over the study's time samples (volume/time_fields.h).
  std::optional<TimeSummary> time;
  /// With surface targets: each target's shares (analysis/scene/surface_targets.h; `cameras` left
  /// out of the JSON).
  std::vector<SurfaceTargetResult> targets;
  std::vector<std::string> sample_labels;  ///< The time samples' labels (for the targets' rows).
  /// With study.pixel_targets: each over the region (volume/pixel_targets.h).
  std::vector<PixelTargetSummary> pixel_targets;
  /// With study.dori: the DORI classes' shares.
  std::optional<DoriSummary> dori;
  /// With study.regions: each named sub-region (Summarize fills it).
  std::vector<RegionSummary> regions;
  /// The calibration simulation (analysis/rig/calibration.h) when the study asks for one; the
  /// caller sets it (Summarize does not: it needs the ray caster).
  std::optional<CalibrationResult> calibration;
  /// N-1 robustness (volume/robustness.h) when the "cameras" field was evaluated; the caller sets
  /// it (ComputeCriticality needs the ray caster).
  std::optional<CriticalityTable> robustness;
  /// The PTZ fields (volume/ptz_fields.h) when the rig has a PTZ camera; the caller sets it.
  std::optional<PtzFieldsSummary> ptz;
};

/// Summarises the evaluated `fields` of `rig` in `scene`. `field_names`: the fields that were asked
/// for (the resolution percentiles need "resolution", the uncertainty block an uncertainty field);
/// `threads`: recorded in the timing.
Summary Summarize(const Scene& scene, const Rig& rig, const Fields& fields,
                  const std::vector<std::string>& field_names, int threads,
                  const std::vector<Warning>& warnings = {});

/// The JSON form (summary.json): rig, cameras, voxel_size_m, region_voxels, solid_voxels,
/// active_voxels, coverage {ge1, ge2, ge3, histogram}, with the resolution field
/// resolution_px_per_m {p10, p50, p90}, per_camera [{id, name, enabled, visible_voxels,
/// visible_fraction, fov_deg {nominal [h, v], effective [h, v]}, unreachable_pixels}] (analysis/
/// rig_check.h's LensCoverage), uncertainty {triangulable, triangulable_voxels,
/// unobservable_voxels, pixel_sigma, sigma_max_mm {p50, p90, p99}, [max_sigma_mm,
/// meets_max_sigma], [motion {q, rate_hz, covariance}, sigma_max_steady_mm, [meets_max_sigma_
/// steady]]}, timing {seconds, active_set_seconds, rays, rays_per_second, point_camera_tests,
/// tests_per_second, threads}, fields, region {min, max, dims, kind}, scene, scene_sha256,
/// warnings [{kind, camera, path, message}] (always present, empty when none), calibration
/// (analysis/rig/calibration.h's to_json), robustness (volume/robustness.h's to_json) and ptz
/// (volume/ptz_fields.h's to_json) when set. Percentiles without a value are null.
void to_json(nlohmann::json& j, const Summary& summary);

/// to_json(Summarize(...)): the summary.json of one evaluation.
nlohmann::json MakeSummary(const Scene& scene, const Rig& rig, const Fields& fields,
                           const std::vector<std::string>& field_names, int threads,
                           const std::vector<Warning>& warnings = {});

/// The table `pandora analyze` prints: the rig and region, coverage shares, the resolution and
/// sigma_max percentiles when present ("-" for a percentile without a value), one line per camera
/// (share of the region seen, effective and nominal FOV, disabled ones marked), the timing, and
/// FormatCalibration's lines when the calibration is set, FormatCriticality's when the robustness
/// is. Lines end in '\n'.
std::string FormatSummary(const Summary& summary);

/// The active values of the float grid `name` of `fields` (tiles once per voxel they cover), in
/// the grid's order; empty when the grid is missing.
std::vector<float> GridActiveValues(const Fields& fields, const std::string& name);

/// Nearest-rank percentiles of the active values of the float grid `name` of `fields` (tiles count
/// once per voxel they cover), one per entry of `percentiles` (each in [0, 100]); nullopt values
/// when the grid is missing or has no active value.
std::vector<std::optional<double>> GridPercentileValues(const Fields& fields,
                                                        const std::string& name,
                                                        const std::vector<int>& percentiles);

/// The same as {"pNN": value} (null where there is none).
nlohmann::json GridPercentiles(const Fields& fields, const std::string& name,
                               const std::vector<int>& percentiles);

/// The nearest-rank percentile p in [0, 100] of `values` (a value that occurs in them: the
/// ceil(p / 100 n)-th smallest, at least the first), nullopt when there is none. Takes a copy.
std::optional<double> NearestRankPercentile(std::vector<float> values, double p);

}  // namespace pandora
