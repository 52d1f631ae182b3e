#pragma once
/// \file pixel_targets.h
/// Pixel-size targets: "a 14 mm marker spans at least 4 pixels", "a face at least 80 pixels", in
/// as many cameras as triangulation needs; and the surveillance DORI classes of EN 62676-4 (the
/// best camera's pixel density at least 25 / 62.5 / 125 / 250 px/m: detection, observation,
/// recognition, identification). Computed after the fields from the per-camera visibility grids
/// and each camera's projection Jacobian (analysis/geometry/visibility.h PixelDensity): no ray is
/// cast again.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/scene/scene.h"
#include "volume/fields.h"
#include "volume/summary_parts.h"

namespace pandora {

/// One pixel target over the region.
struct PixelTargetSummary {
  PixelTarget target;
  /// share_ge[j - 1]: share of the free region voxels seen by at least j cameras each at a pixel
  /// density of at least target.px_per_m(), j = 1 .. max(3, min_cameras).
  std::vector<double> share_ge;
  double seconds = 0;  ///< The pass over the camera sets, shared by all the study's pixel targets.
};

/// The DORI classes over the region (the best camera's density, the resolution field).
struct DoriSummary {
  /// Share of the free region voxels whose best density reaches detection (25 px/m), observation
  /// (62.5), recognition (125), identification (250).
  double detection = 0, observation = 0, recognition = 0, identification = 0;
  /// The counts behind the shares: free region voxels, and those reaching each class (a streamed
  /// run adds its tiles' counts; not in summary.json).
  std::int64_t voxels = 0;
  std::int64_t reached[4] = {0, 0, 0, 0};
  /// The shares from the counts.
  void SetShares() {
    const double n = voxels > 0 ? double(voxels) : 1.0;
    detection = reached[0] / n;
    observation = reached[1] / n;
    recognition = reached[2] / n;
    identification = reached[3] / n;
  }
};

/// The EN 62676-4 thresholds, px/m.
inline constexpr double kDoriPxPerM[4] = {25.0, 62.5, 125.0, 250.0};

/// Evaluates scene.study.pixel_targets over `fields` (which must hold the "cameras" field) for
/// `rig`; when `grids` is not null, adds per target a float grid "pixels_<name>" (cameras that meet
/// it, whole numbers) to its Fields::Impl::extra. Throws InputError (path "$.study.pixel_targets")
/// when the cameras field is missing.
std::vector<PixelTargetSummary> EvaluatePixelTargets(const Scene& scene, const Rig& rig,
                                                     const Fields& fields, int min_cameras,
                                                     Fields* grids);

/// EvaluatePixelTargets in parts (volume/summary_parts.h): the counts over the voxels of `fields`
/// (a streamed run's tile, or the whole region), its grids into `grids` as EvaluatePixelTargets.
SummaryParts PixelTargetParts(const Scene& scene, const Rig& rig, const Fields& fields,
                              int min_cameras, Fields* grids);
/// The summaries from every part added up (SummaryParts::Add).
std::vector<PixelTargetSummary> FinishPixelTargets(const Scene& scene, int min_cameras,
                                                   const SummaryParts& parts);

/// The DORI shares from the resolution field (InputError "$.study.dori" when it is missing); with
/// `grids`, adds a float grid "dori" (the class 0 .. 4 reached, active on the free region voxels).
DoriSummary EvaluateDori(const Scene& scene, const Fields& fields, Fields* grids);

}  // namespace pandora
