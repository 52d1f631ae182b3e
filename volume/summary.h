#pragma once
/// \file summary.h
/// The summary.json written by `pandora analyze`. Fractions are of the region's free voxels
/// (`region_voxels`: voxel centres inside the region and outside every solid object).

#include <nlohmann/json.hpp>

#include "analysis/scene.h"
#include "volume/fields.h"

namespace pandora {

/// Builds the summary: rig, cameras, voxel_size_m, region_voxels, solid_voxels, active_voxels,
/// coverage {ge1, ge2, ge3, histogram}, per_camera [{id, name, enabled, visible_voxels,
/// visible_fraction}], timing {seconds, active_set_seconds, rays, rays_per_second,
/// point_camera_tests, tests_per_second, threads}, fields, region, scene, scene_sha256, version.
nlohmann::json MakeSummary(const Scene& scene, const Rig& rig, const Fields& fields,
                           const std::vector<std::string>& field_names, int threads);

}  // namespace pandora
