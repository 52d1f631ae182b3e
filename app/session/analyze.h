#pragma once
/// \file analyze.h
/// The one analysis conductor: everything a rig's analysis computes beside its fields, in one
/// order, for every front end. `pandora analyze` (and rank 0 of an MPI run, after the merge),
/// `pandora report` and Python's `evaluate()` call CompleteAnalysis after the fields; AnalyzeRig
/// evaluates the fields too. What a front end keeps for itself: parsing and checking its options,
/// progress bars, writing files, printing.
///
/// The steps, each only where the scene asks for it: the fields at every time sample and the
/// surface targets at each (moving objects or study.targets; docs/time.md), pixel-size targets and
/// DORI classes (study.pixel_targets, study.dori), the plausibility warnings (CheckRig), the typed
/// Summary, calibration feasibility (study.calibration), N-1 (every camera's failure; the fields'
/// camera sets) and PTZ reach and tours (a PTZ camera in the rig).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/rig/rig_check.h"
#include "analysis/scene/motion.h"
#include "app/session/study.h"
#include "volume/fields.h"
#include "volume/summary.h"

namespace pandora::session {

struct AnalyzeOptions {
  /// The fields evaluated: Summarize's field names and, less "cameras", the fields at each time
  /// sample (its budget, scene path and option names too; OverTimeOptions).
  FieldOptions fields;
  /// Recorded in the summary's timing.
  int threads = 0;
  /// Called with the number of time samples before they are evaluated; returns the progress
  /// callback of that stage (0..1), or an empty function. Unset: no progress.
  std::function<std::function<void(double)>(std::size_t samples)> time_stage;
  /// The scene's rigid parts (MakeSceneParts), when the caller keeps them for several rigs; null:
  /// built here when needed, and their build time recorded (time.parts_seconds).
  const RigidPartsRayCaster* parts = nullptr;
  /// The steps a front end may leave out: the report has no section for pixel targets, DORI and
  /// PTZ yet; the viewer's Compare shows the headline numbers only.
  bool pixel_targets = true, dori = true, ptz = true, calibration = true, robustness = true;
  /// Where N-1 writes its sigma_max lists when they outgrow memory (ListMemory,
  /// volume/robustness.h; empty: the system's temporary folder) and what a file error there names.
  std::string spill_folder, spill_blame;
};

/// What CompleteAnalysis adds: the full typed summary and its warnings (also in summary.warnings).
struct RigAnalysis {
  Summary summary;
  std::vector<Warning> warnings;
};

/// Everything after the fields of `rig` (see the file comment). With `grids` (usually &fields) the
/// derived grids (time, pixels_*, dori, coverage_n1, ptz_*) go into it; null: `fields` is only
/// read. Throws InputError as the steps do (pixel targets need the "cameras" field, DORI the
/// "resolution" field).
RigAnalysis CompleteAnalysis(const Scene& scene, const RayCaster& caster, const Rig& rig,
                             const Fields& fields, Fields* grids, const AnalyzeOptions& options);

/// EvaluateFields(study, rig, options.fields) and then CompleteAnalysis: one rig's whole analysis.
struct RigFieldsAnalysis {
  Fields fields;
  RigAnalysis analysis;
};
RigFieldsAnalysis AnalyzeRig(const Study& study, const Rig& rig, const AnalyzeOptions& options);

}  // namespace pandora::session
