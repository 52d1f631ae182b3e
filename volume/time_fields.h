#pragma once
/// \file time_fields.h
/// Fields over time: the study's fields evaluated at every time sample of a scene with moving
/// objects (analysis/scene/motion.h), each sample over the scene as it is then (the moved objects
/// occlude, a solid body's inside is not free space while it is there), with the sample's ray
/// caster from the scene's rigid parts (no BVH rebuilt). Combined per voxel into the worst case and
/// the share of time, and per sample into the summary's rows. docs/time.md.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analysis/scene/motion.h"
#include "analysis/scene/scene.h"
#include "volume/fields.h"
#include "volume/summary_parts.h"

namespace pandora {

class RigidPartsRayCaster;

/// One time sample's headline numbers.
struct TimeSampleSummary {
  std::string label;
  double time = 0;
  std::int64_t region_voxels = 0;              ///< Free region voxels at this sample.
  double ge1 = 0, ge2 = 0, ge3 = 0, ge_k = 0;  ///< Shares seen by >= 1, 2, 3, min_cameras cameras.
  std::optional<double> sigma_max_p50, sigma_max_p90;  ///< mm, with an uncertainty field.
  double seconds = 0;
};

/// The fields over all samples: what summary.json's "time" holds.
struct TimeSummary {
  int min_cameras = 3;
  std::vector<TimeSampleSummary> samples;
  /// Voxels free in at least one sample.
  std::int64_t voxels = 0;
  /// Share of those voxels whose coverage_min (the fewest cameras over the samples where the voxel
  /// is free) is at least min_cameras: covered all the time.
  double always = 0;
  /// Share of (voxel, sample) pairs, over the free pairs, seen by >= min_cameras cameras.
  double mean = 0;
  int worst_sample = 0;  ///< The sample with the lowest ge_k.
  /// sigma_max over every triangulable (voxel, sample) pair, mm (with an uncertainty field).
  std::optional<double> sigma_max_p50, sigma_max_p90, sigma_max_p99;
  double seconds = 0;        ///< Wall time of all samples.
  double parts_seconds = 0;  ///< Building the parts' BVHs once (set by the caller).
};

struct TimeFieldsResult {
  TimeSummary summary;
  /// Grids for fields.vdb (Fields::Impl::extra): "coverage_min" (Float, whole numbers: the fewest
  /// cameras over the samples where the voxel is free) and "coverage_time_share" (Float in [0, 1]:
  /// the share of those samples with >= min_cameras cameras), active on the voxels free in at least
  /// one sample.
  Fields grids;
};

/// What evaluating one sample cost (EvaluateSamples).
struct SampleCost {
  bool full = false;              ///< Evaluated in full (the first sample, or nothing kept).
  std::int64_t dirty_blocks = 0;  ///< 8^3 blocks re-derived.
  std::int64_t rays = 0;          ///< Occlusion segments cast.
  double seconds = 0;             ///< The scene at the sample, its caster and the fields.
};

/// The objects' bounds that differ between two samples' scenes (SceneAtSample of one scene): for
/// every object whose vertices moved, its bounds in each. What FieldEvaluator::UpdateScene needs.
SceneChange MovedBounds(const Scene& before, const Scene& after);

/// Evaluates `options.fields` for `rig` at every sample in turn and calls `visit(s, fields, cost)`
/// with sample s's fields: equal, voxel for voxel and bit for bit, to EvaluateFields of
/// SceneAtSample(scene, samples[s]) with CasterAtSample(parts, scene, samples[s]). The first sample
/// is evaluated in full, the next ones by difference (FieldEvaluator::UpdateScene with the bounds
/// of what moved since the previous sample: only the (block, camera) pairs whose segments can meet
/// them are cast again). When the evaluator's kept state would exceed the memory budget, every
/// sample is evaluated in full. Stops after the sample during which FieldOptions::cancel is set
/// (a sample evaluated by difference runs to its end). docs/time.md.
void EvaluateSamples(
    const Scene& scene, const Rig& rig, const RigidPartsRayCaster& parts,
    const std::vector<TimeSample>& samples, const FieldOptions& options,
    const std::function<void(std::size_t, const Fields&, const SampleCost&)>& visit);

/// Evaluates `options.fields` for `rig` at every sample (EvaluateSamples) and combines them.
/// `parts` is MakeSceneParts(scene). Throws as EvaluateFields.
TimeFieldsResult EvaluateFieldsOverTime(const Scene& scene, const Rig& rig,
                                        const RigidPartsRayCaster& parts,
                                        const std::vector<TimeSample>& samples,
                                        const FieldOptions& options, int min_cameras);

/// EvaluateFieldsOverTime in parts (volume/summary_parts.h): the samples over options.tile (a
/// streamed run's tile) or the whole region, their counts and sigma_max lists; the combined grids
/// ("coverage_min", "coverage_time_share") into `grids` when not null.
SummaryParts TimeFieldsParts(const Scene& scene, const Rig& rig, const RigidPartsRayCaster& parts,
                             const std::vector<TimeSample>& samples, const FieldOptions& options,
                             int min_cameras, Fields* grids);
/// The summary from every part's counts and timings added up and their lists (seconds left 0).
TimeSummary FinishTimeFields(const std::vector<TimeSample>& samples, int min_cameras,
                             const std::vector<std::int64_t>& counts,
                             const std::vector<double>& seconds, PercentileSource& lists);

/// The options of EvaluateFieldsOverTime from a run's fields options: the samples evaluated whole
/// (one partition: under MPI rank 0 evaluates them, docs/scale.md), with only the fields the time
/// summary and grids are made of: "coverage", and "sigma_max" when the run asks for any
/// uncertainty field (its percentiles per sample); the others are never written per sample, so
/// they are not evaluated. What `pandora analyze` and the viewer's Compare use.
FieldOptions OverTimeOptions(FieldOptions options);

/// Moves the result's grids into `fields` (written to fields.vdb with them).
void AddTimeGrids(Fields* fields, TimeFieldsResult* result);

}  // namespace pandora
