// The one analysis conductor (app/session/analyze.h).
#include "app/session/analyze.h"

#include <chrono>
#include <optional>

#include "analysis/rig/calibration.h"
#include "analysis/scene/surface_targets.h"
#include "analysis/util/allocation_budget.h"
#include "volume/pixel_targets.h"
#include "volume/ptz_fields.h"
#include "volume/robustness.h"
#include "volume/solid_trees.h"
#include "volume/time_fields.h"

namespace pandora::session {
namespace {

// The moving objects' part: the fields at every time sample (summary.time, and their grids into
// `grids` when given), the surface targets at each, and the samples' labels.
void AnalyzeOverTime(const Scene& scene, const Rig& rig, Fields* grids,
                     const AnalyzeOptions& options, Summary& summary) {
  std::unique_ptr<RigidPartsRayCaster> built;
  double parts_seconds = 0;
  const RigidPartsRayCaster* parts = options.parts;
  if (!parts) {
    const auto t0 = std::chrono::steady_clock::now();
    built = MakeSceneParts(scene);
    parts_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    parts = built.get();
  }
  const std::vector<TimeSample> samples = scene.TimeSamples();
  for (const TimeSample& s : samples) summary.sample_labels.push_back(s.label);
  if (!samples.empty()) {
    FieldOptions over_time = OverTimeOptions(options.fields);
    over_time.progress = options.time_stage ? options.time_stage(samples.size()) : nullptr;
    TimeFieldsResult result =
        EvaluateFieldsOverTime(scene, rig, *parts, samples, over_time, scene.TimeMinCameras());
    result.summary.parts_seconds = parts_seconds;
    summary.time = result.summary;
    if (grids) AddTimeGrids(grids, &result);
  }
  summary.targets = EvaluateSurfaceTargets(scene, rig, *parts, samples, scene.TimeMinCameras());
}

}  // namespace

RigAnalysis CompleteAnalysis(const Scene& scene, const RayCaster& caster, const Rig& rig,
                             const Fields& fields, Fields* grids, const AnalyzeOptions& options) {
  Summary over_time;  // the parts computed before the summary, moved into it below
  if (scene.Animated() || scene.study.targets)
    AnalyzeOverTime(scene, rig, grids, options, over_time);
  // Pixel-size targets and DORI classes, from the fields without casting again.
  std::vector<PixelTargetSummary> pixel_targets;
  if (options.pixel_targets)
    pixel_targets = EvaluatePixelTargets(scene, rig, fields, scene.TimeMinCameras(), grids);
  std::optional<DoriSummary> dori;
  if (options.dori && scene.study.dori) dori = EvaluateDori(scene, fields, grids);
  // Plausibility warnings, after every input check.
  RigAnalysis out;
  RigCheckOptions check;
  check.visible_voxels = fields.stats.per_camera_seen;
  if (const SolidTrees* trees = options.fields.solid_trees)
    trees->LendTo(scene, &check);  // the study's, not built again
  out.warnings = CheckRig(scene, rig, caster, check);
  Summary& s = out.summary;
  s = Summarize(scene, rig, fields, options.fields.fields, options.threads, out.warnings);
  s.time = std::move(over_time.time);
  s.targets = std::move(over_time.targets);
  s.sample_labels = std::move(over_time.sample_labels);
  s.pixel_targets = std::move(pixel_targets);
  s.dori = dori;
  if (options.calibration && scene.study.calibration)
    s.calibration = SimulateCalibration(scene, rig, caster, *scene.study.calibration);
  // N-1: what the rig loses when any one camera fails, from the per-voxel camera sets
  // (docs/failures.md).
  if (options.robustness && HasCameraSets(fields)) {
    ListMemory lists;
    lists.folder = options.spill_folder;
    lists.blame = options.spill_blame;
    s.robustness = ComputeCriticality(scene, rig, fields, caster, scene.TimeMinCameras(), lists);
    if (grids) AddCoverageN1Grid(grids);
  }
  // PTZ cameras: reach times, reachable shares, tours (docs/ptz.md).
  if (options.ptz && RigHasPtz(rig)) s.ptz = EvaluatePtzFields(scene, rig, caster, fields, grids);
  return out;
}

RigFieldsAnalysis AnalyzeRig(const Study& study, const Rig& rig, const AnalyzeOptions& options) {
  AnalyzeOptions with_trees = options;
  if (!with_trees.fields.solid_trees) with_trees.fields.solid_trees = &study.solid_trees();
  RigFieldsAnalysis out{EvaluateFields(study.scene(), rig, study.caster(), with_trees.fields), {}};
  // The evaluation's freed blocks (8 bytes per triangulable voxel with the steady fields, and
  // more) would stay resident beside what the analyses below allocate.
  ReleaseFreedMemory();
  out.analysis =
      CompleteAnalysis(study.scene(), study.caster(), rig, out.fields, &out.fields, with_trees);
  return out;
}

}  // namespace pandora::session
