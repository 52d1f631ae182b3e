#pragma once
/// \file ptz_fields.h
/// Fields of the rig's pan-tilt-zoom cameras (docs/ptz.md): per free region voxel and PTZ camera
/// the reach time (seconds from the current setting until some setting sees the voxel at a zoom
/// meeting the study's pixel-density target, occlusion included), its minimum over the rig's PTZ
/// cameras, the shares of the region reachable within budgets; for a camera with a tour, the
/// fraction of the tour's period each voxel is watched and its longest unwatched stretch.
/// Computed after the fields (the coverage grid gives the free region voxels).

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/surface_distance.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/ptz.h"
#include "analysis/scene/scene.h"
#include "volume/fields.h"
#include "volume/summary_parts.h"

namespace pandora {

/// One PTZ camera over the region. Shares are of the free region voxels.
struct PtzCameraFields {
  std::string id;
  int camera = -1;        ///< Rig index.
  double max_time_s = 0;  ///< The longest move from the current setting (PtzReach::MaxTime).
  std::int64_t reachable_voxels = 0;  ///< With a finite reach time.
  double reachable_share = 0;
  std::vector<double> within;  ///< Share with reach time <= PtzFieldsSummary::within_s[i].
  double trace_s = 0, within_trace = 0;  ///< The head's trace budget and the share within it.
  std::optional<double> reach_p50_s, reach_p90_s;  ///< Over the reachable voxels.
  // The tour (when the head has one).
  bool tour = false;
  int stops = 0;
  double period_s = 0;
  double watched_mean = 0;   ///< Mean over the region of the fraction of the period watched.
  double watched_share = 0;  ///< Share of the region watched at some time in the period.
  /// Longest unwatched stretch (s) over the voxels watched at some time.
  std::optional<double> gap_p50_s, gap_p90_s, gap_max_s;
};

struct PtzFieldsSummary {
  double min_px_per_m = 0;   ///< The density target (0: any zoom).
  std::string pixel_target;  ///< Its pixel target's name, if it came from one.
  std::vector<double> within_s;
  std::int64_t region_voxels = 0;
  std::vector<PtzCameraFields> cameras;  ///< Enabled PTZ cameras, rig order.
  /// The minimum over the PTZ cameras: share reachable by some PTZ, and within each budget.
  double reachable_share = 0;
  std::vector<double> within;
  std::int64_t rays = 0;  ///< Occlusion segments cast.
  double seconds = 0;
};

/// True when `rig` has an enabled camera with a PTZ head.
bool RigHasPtz(const Rig& rig);

/// The scene's triangles in double precision, for the VisibilityTester of PTZ work, when some
/// enabled PTZ camera of `rig` has a tour and a centre offset from its pivot: WatchTour then
/// certifies the occlusion along each move on them (PtzSweptOcclusion) instead of sampling it.
/// Null otherwise (nothing needs them).
std::unique_ptr<SurfaceDistance> PtzSweptOccluders(const Scene& scene, const Rig& rig);

/// Reach time of X for `base` (a rig camera with a head) from its current setting: PtzReach's
/// geometric reach time (bisection to `tolerance_s`) with the occlusion of the segment from the
/// reaching setting's centre. With a zero offset the centre is the pivot for every setting, so an
/// occluded segment means never (exact); with an offset an occluded first reach is retried at the
/// longest move and, if visible there, bisected on the occluded test too. +inf when never.
/// `tester` holds the rig's cameras (its caster and the occlusion tolerance of camera `camera`).
double PtzReachTime(const VisibilityTester& tester, int camera, const Vec3& X, double min_px_per_m,
                    double tolerance_s = 1e-3, std::int64_t* rays = nullptr);

/// The watched intervals of X over the tour of rig camera `camera` (WatchTour with PtzSees at the
/// density target and the occlusion from each setting's centre; one segment when the offset is
/// zero, the pivot being the centre of every setting).
PtzWatch PtzTourWatch(const VisibilityTester& tester, int camera,
                      const std::vector<PtzHead::TourLeg>& legs, const Vec3& X, double min_px_per_m,
                      std::int64_t* rays = nullptr);

/// Evaluates the PTZ fields of the enabled PTZ cameras of `rig` over the free region voxels of
/// `fields` (its coverage grid; nothing is computed without it or without a PTZ camera: the
/// summary then has no cameras). With `grids`, adds to its Fields::Impl::extra:
/// "ptz_reach_time/<id>" (s, active where reachable), "ptz_reach_time" (the minimum over the PTZ
/// cameras), and for a camera with a tour "ptz_watched/<id>" (fraction of the period, every region
/// voxel) and "ptz_gap/<id>" (longest unwatched stretch, s, active where watched at some time).
/// Parallel (TBB).
PtzFieldsSummary EvaluatePtzFields(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                   const Fields& fields, Fields* grids);

/// EvaluatePtzFields in parts (volume/summary_parts.h): the counts and lists over the free region
/// voxels of `fields` (a streamed run's tile, or the whole region), the grids into `grids`. Empty
/// without a PTZ camera or a coverage grid.
SummaryParts PtzFieldsParts(const Scene& scene, const Rig& rig, const RayCaster& caster,
                            const Fields& fields, Fields* grids);
/// The summary from every part's counts and timings added up and their lists.
PtzFieldsSummary FinishPtzFields(const Scene& scene, const Rig& rig,
                                 const std::vector<std::int64_t>& counts,
                                 const std::vector<double>& seconds, PercentileSource& lists);

/// {min_px_per_m, pixel_target, within_s, region_voxels, cameras [{id, max_time_s, reachable_share,
/// within, trace_s, within_trace, reach_p50_s, reach_p90_s, tour: null | {stops, period_s,
/// watched_mean, watched_share, gap_p50_s, gap_p90_s, gap_max_s}}], rig {reachable_share, within},
/// rays, seconds}.
void to_json(nlohmann::json& j, const PtzFieldsSummary& summary);

/// The lines `pandora analyze` prints.
std::string FormatPtzFields(const PtzFieldsSummary& summary);

}  // namespace pandora
