#pragma once
/// \file robustness.h
/// N-1 robustness: what the rig loses when any one camera fails (unplugged, bumped, occluded by a
/// new rack), computed from the per-voxel camera sets of an evaluation (the "cameras" field)
/// without casting a ray. Coverage after a failure is exact from the counts (a voxel camera c sees
/// loses one camera). The uncertainty after a failure is re-derived at the voxels c sees from the
/// other cameras that see them: their projection Jacobians, the same per-camera information
/// contribution, exact fixed-point sum, eigenvalue solver and statistics as the field evaluation
/// (volume/information_sum.h), so every row equals a full evaluation of the rig with that camera
/// disabled, bit for bit (test volume/robustness_test.cpp). docs/failures.md.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "volume/fields.h"
#include "volume/summary_parts.h"

namespace pandora {

/// The region after one camera fails. Shares are of the free region voxels.
struct CriticalityRow {
  int camera = -1;  ///< Rig index.
  std::string id;
  std::int64_t seen_voxels = 0;  ///< Voxels the camera sees (intact).
  double ge1 = 0, ge2 = 0, ge3 = 0,
         ge_k = 0;  ///< Shares seen by >= 1, 2, 3, k cameras after it fails.
  /// With the sigma_max field: the share triangulable after it fails and the nearest-rank sigma_max
  /// percentiles (mm) over those voxels (nullopt when none is triangulable).
  std::optional<double> triangulable;
  std::int64_t triangulable_voxels = 0;
  std::optional<double> sigma_max_p50_mm, sigma_max_p90_mm;
};

/// Every enabled camera's failure, and the region-level N-1 numbers.
struct CriticalityTable {
  int k = 3;                         ///< The study's camera count (Scene::TimeMinCameras()).
  std::int64_t region_voxels = 0;    ///< Free region voxels.
  double ge_k = 0;                   ///< Intact share seen by >= k cameras.
  bool uncertainty = false;          ///< The rows carry the sigma_max columns.
  std::vector<CriticalityRow> rows;  ///< Enabled cameras, rig order.
  /// Index into `rows` of the worst single failure (the lowest ge_k; ties: the lowest triangulable
  /// share, then the highest sigma_max p90, then rig order); -1 when there are no rows.
  int worst = -1;
  double mean_ge_k = 0;  ///< Mean over the rows of ge_k (the intact ge_k when there are none).
  double seconds = 0;    ///< Wall time of ComputeCriticality (streamed: summed over tiles).
  /// Bytes of sigma_max lists ComputeCriticality wrote to temporary files (0: kept in memory).
  double spilled_bytes = 0;

  /// ge_k lost by the worst failure (0 without rows).
  double worst_loss() const { return worst >= 0 ? ge_k - rows[worst].ge_k : 0.0; }
  /// Indices into `rows`, most critical first (the order that picks `worst`).
  std::vector<int> MostCritical() const;
};

/// True when `fields` holds the per-camera sets (the "cameras" field was evaluated).
bool HasCameraSets(const Fields& fields);

/// Where ComputeCriticality keeps the sigma_max lists of its percentiles (about 8 bytes per
/// triangulable voxel and camera that sees it: 1.3 GB for 11 M voxels seen by 15 cameras each):
/// in memory when they take at most `bytes`, else computed part by part (each part's lists at
/// most a quarter of `bytes`) and appended to unnamed temporary files in `folder` (empty: the
/// system's temporary folder), as a streamed run keeps them (volume/summary_parts.h). The table
/// is the same either way, bit for bit. `blame`: what a file error names (default: the folder).
struct ListMemory {
  double bytes = 16.0 * 1048576.0;
  std::string folder, blame;
};

/// The criticality of every enabled camera of `rig` from `fields`, which must be an evaluation of
/// exactly `rig` over `scene` with the "cameras" field (HasCameraSets; throws std::invalid_argument
/// otherwise). With the "sigma_max" field the uncertainty columns are filled: the Jacobians at the
/// voxels each camera sees are recomputed (`caster` is only held by the visibility tester: no ray
/// is cast). `k` >= 1: the camera count of ge_k. Runs in parallel with TBB.
CriticalityTable ComputeCriticality(const Scene& scene, const Rig& rig, const Fields& fields,
                                    const RayCaster& caster, int k, const ListMemory& memory = {});

/// ComputeCriticality in parts (volume/summary_parts.h): the counts and sigma_max lists over the
/// voxels of `fields` (a streamed run's tile, or the whole region). Throws as ComputeCriticality.
SummaryParts CriticalityParts(const Scene& scene, const Rig& rig, const Fields& fields,
                              const RayCaster& caster, int k);
/// CriticalityParts of `fields` in parts of leaves, each part's lists at most about `part_bytes`
/// (and their working copies about three times that), added to `into` one after the other: a
/// streamed run's tile without its whole lists in memory. Its time is added as a part with only
/// `seconds` (one value). Parts as small as ComputeCriticality's spilled ones (the default) are
/// the fastest: on the 2 cm capture stage 1-16 MiB parts took 15-17 s of N-1 over 16 tiles, 64
/// MiB 21 s, 128 MiB 29 s (the threads' working copies then come from fresh pages each part).
void AddCriticalityParts(const Scene& scene, const Rig& rig, const Fields& fields,
                         const RayCaster& caster, int k, SpilledParts& into,
                         double part_bytes = ListMemory().bytes / 4.0);
/// The table from every part's counts added up and their lists; `region_voxels`: the free region
/// voxels of all the parts. Equal to ComputeCriticality of the whole region (seconds left 0).
CriticalityTable FinishCriticality(const Rig& rig, int k, std::int64_t region_voxels,
                                   const std::vector<std::int64_t>& counts,
                                   PercentileSource& lists);

/// Adds the float grid "coverage_n1" to `fields` (Fields::Impl::extra, written to fields.vdb):
/// per free region voxel the coverage after the worst single failure there, max(coverage - 1, 0).
/// Needs the coverage field; does nothing without it.
void AddCoverageN1Grid(Fields* fields);

/// {k, ge_k, worst {camera, ge_k, loss}, mean_ge_k, seconds, per_camera [{id, seen_voxels, ge1,
/// ge2, ge3, ge_k, triangulable, sigma_max_p50_mm, sigma_max_p90_mm}]}; the uncertainty columns are
/// null without the sigma_max field, worst is null without rows.
void to_json(nlohmann::json& j, const CriticalityTable& table);

/// The lines `pandora analyze` prints: the N-1 summary and the `rows` most critical cameras.
std::string FormatCriticality(const CriticalityTable& table, int rows = 3);

}  // namespace pandora
