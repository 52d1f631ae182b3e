#pragma once
/// \file summary.h
/// The summary.json written by `pandora analyze`. Fractions are of the region's free voxels
/// (`region_voxels`: voxel centres inside the region and outside every solid object).

#include <nlohmann/json.hpp>

#include "analysis/rig_check.h"
#include "analysis/scene.h"
#include "volume/fields.h"

namespace pandora {

/// Builds the summary: rig, cameras, voxel_size_m, region_voxels, solid_voxels, active_voxels,
/// coverage {ge1, ge2, ge3, histogram}, with the resolution field resolution_px_per_m {p10, p50,
/// p90} (nearest rank over the voxels seen by at least one camera, each voxel's best camera),
/// per_camera [{id, name, enabled, visible_voxels, visible_fraction, fov_deg {nominal [h, v],
/// effective [h, v]}, unreachable_pixels}] (analysis/rig_check.h's LensCoverage), uncertainty,
/// timing {seconds, active_set_seconds, rays, rays_per_second, point_camera_tests,
/// tests_per_second, threads}, fields, region, scene, scene_sha256, and warnings [{kind, camera,
/// path, message}] (CheckRig's, in order; always present, empty when none).
nlohmann::json MakeSummary(const Scene& scene, const Rig& rig, const Fields& fields,
                           const std::vector<std::string>& field_names, int threads,
                           const std::vector<Warning>& warnings = {});

/// Nearest-rank percentiles of the active values of the float grid `name` of `fields` (tiles count
/// once per voxel they cover), as {"pNN": value} for each p in `percentiles`; null values when the
/// grid is missing or has no active value.
nlohmann::json GridPercentiles(const Fields& fields, const std::string& name,
                               const std::vector<int>& percentiles);

}  // namespace pandora
