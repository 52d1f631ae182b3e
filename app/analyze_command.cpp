#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "analysis/calibration.h"
#include "analysis/error.h"
#include "analysis/ray_caster.h"
#include "analysis/motion.h"
#include "analysis/rig_check.h"
#include "analysis/surface_targets.h"
#include "analysis/scene.h"
#include "app/commands.h"
#include "app/mpi_session.h"
#include "app/session/session.h"
#include "app/output.h"
#include "volume/fields.h"
#include "volume/fields_transfer.h"
#include "volume/robustness.h"
#include "volume/summary.h"
#include "volume/pixel_targets.h"
#include "volume/time_fields.h"
#include "volume/vdb_io.h"

#ifndef PANDORA_VERSION
#define PANDORA_VERSION "dev"
#endif

namespace pandora::app {
namespace {

std::vector<std::string> SplitFields(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

std::string FormatNumber(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.12g", v);
  return buffer;
}

// The --fields option: known names, each once, steady-state ones only with a motion model.
std::vector<std::string> CheckFieldsOption(const std::vector<std::string>& fields,
                                           const Study& study) {
  if (fields.empty()) throw InputError("--fields", "", "no field given", "e.g. --fields coverage,sigma_max");
  if (auto problem = CheckFieldList(fields, study.motion.has_value()))
    throw InputError("--fields", "", problem->reason, problem->hint);
  return fields;
}

}  // namespace

double CheckPositiveOption(const char* option, double value, const char* unit) {
  if (!(value > 0) || !std::isfinite(value))
    throw InputError(option, "", std::string("must be a positive number") + (*unit ? " of " : "") + unit);
  return value;
}

int RunAnalyze(const AnalyzeArgs& args) {
  // Under mpirun every process runs this; rank 0 alone prints, stages and writes (docs/scale.md).
  const MpiSession mpi(args.mpi);
  const bool root = mpi.rank() == 0;
  const bool quiet = args.quiet || !root;
  // The study, with --voxel-size applied, and the rig, through the session layer.
  const auto study = LoadStudyWithVoxelSize(args.scene, args.voxel_size);
  const Scene& scene = study->scene();
  session::SessionOptions so;
  so.rig = args.rig;
  so.rig_option = "--rig";
  so.disable = args.disable;
  so.incremental = false;  // one evaluation: no per-pair state
  FieldOptions& options = so.fields;
  options.scene_path = scene.path;
  if (!std::isnan(args.voxel_size)) options.voxel_size_option = "--voxel-size";
  options.fields = scene.study.fields;
  if (!args.fields.empty()) options.fields = CheckFieldsOption(SplitFields(args.fields), scene.study);
  options.memory_budget_bytes = scene.study.memory_budget_bytes;
  if (!std::isnan(args.memory_budget_mb)) {
    options.memory_budget_bytes =
        CheckPositiveOption("--memory-budget", args.memory_budget_mb, "MiB") * 1024.0 * 1024.0;
    CheckMemoryBudget(args.memory_budget_mb, "--memory-budget", "");
    options.memory_budget_option = "--memory-budget";
  }
  options.partition_count = mpi.size();
  options.partition_rank = mpi.rank();
  ProgressBar bar("analyze " + study->FindRig(args.rig, "--rig").name +
                      (mpi.active() ? " (rank 0 of " + std::to_string(mpi.size()) + ")" : ""),
                  !quiet);
  options.progress = [&bar](double f) { bar.Update(f); };
  session::Session session(study, so);
  const Rig& rig = session.rig().rig();
  // Both outputs appear together (summary.json last), or neither does. Under MPI every process
  // learns whether rank 0 could stage them before any evaluates (a failure on one rank must not
  // leave the others waiting).
  const std::filesystem::path out(args.out);
  OutputTransaction output;
  std::string vdb_path, summary_path;
  std::exception_ptr failure;
  if (root) {
    try {
      AddSceneInputs(output, scene);
      vdb_path = output.Stage((out / "fields.vdb").string(), "--out");
      summary_path = output.Stage((out / "summary.json").string(), "--out");
    } catch (...) {
      failure = std::current_exception();
    }
  }
  if (!mpi.AllOk(!failure)) {
    if (failure) std::rethrow_exception(failure);
    return 2;  // rank 0 printed why
  }

  try {
    session.UpdateFields();
  } catch (...) {
    failure = std::current_exception();
  }
  if (!mpi.AllOk(!failure)) {
    if (failure && root) std::rethrow_exception(failure);
    return 2;
  }
  Fields fields = session.TakeFields();
  bar.Finish();
  // The partitions meet at rank 0: grids merged, statistics added (volume/fields_transfer.h).
  nlohmann::json mpi_summary;
  if (mpi.active()) {
    const auto t0 = std::chrono::steady_clock::now();
    const nlohmann::json mine{{"seconds", fields.stats.seconds},
                              {"rays", fields.stats.rays},
                              {"point_camera_tests", fields.stats.point_camera_tests}};
    const std::vector<std::string> parts = mpi.GatherToRoot(mine.dump() + '\n' + SerializePartialFields(fields));
    if (!root) return 0;
    mpi_summary = {{"ranks", mpi.size()}, {"per_rank", nlohmann::json::array()}};
    mpi_summary["per_rank"].push_back(mine);
    for (std::size_t r = 1; r < parts.size(); ++r) {
      const std::size_t newline = parts[r].find('\n');
      mpi_summary["per_rank"].push_back(nlohmann::json::parse(parts[r].substr(0, newline)));
      MergePartialFields(parts[r].substr(newline + 1), &fields);
    }
    mpi_summary["merge_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // Moving objects: the fields at every time sample; surface targets at each (docs/time.md).
  std::optional<TimeSummary> time;
  std::vector<SurfaceTargetResult> targets;
  std::vector<std::string> sample_labels;
  if (scene.Animated() || scene.study.targets) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto parts = MakeSceneParts(scene);
    const double parts_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::vector<TimeSample> samples = scene.TimeSamples();
    for (const TimeSample& s : samples) sample_labels.push_back(s.label);
    if (!samples.empty()) {
      FieldOptions over_time = options;
      over_time.partition_count = 1;  // rank 0 evaluates the time samples whole (docs/scale.md)
      over_time.partition_rank = 0;
      // The per-camera sets of every sample are not kept: coverage and the uncertainty fields are.
      over_time.fields.erase(std::remove(over_time.fields.begin(), over_time.fields.end(), "cameras"),
                             over_time.fields.end());
      ProgressBar time_bar("over " + std::to_string(samples.size()) + " time samples", !args.quiet);
      over_time.progress = [&time_bar](double f) { time_bar.Update(f); };
      TimeFieldsResult result =
          EvaluateFieldsOverTime(scene, rig, *parts, samples, over_time, scene.TimeMinCameras());
      time_bar.Finish();
      result.summary.parts_seconds = parts_seconds;
      time = result.summary;
      AddTimeGrids(&fields, &result);
    }
    targets = EvaluateSurfaceTargets(scene, rig, *parts, samples, scene.TimeMinCameras());
  }
  // Pixel-size targets and DORI classes, from the fields without casting again.
  std::vector<PixelTargetSummary> pixel_targets = EvaluatePixelTargets(scene, rig, fields, scene.TimeMinCameras(), &fields);
  std::optional<DoriSummary> dori;
  if (scene.study.dori) dori = EvaluateDori(scene, fields, &fields);
  const RayCaster& caster = study->caster();

  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  // Plausibility warnings, after every input check (they are printed only when the run succeeds).
  RigCheckOptions check;
  check.visible_voxels = fields.stats.per_camera_seen;
  const std::vector<Warning> warnings = CheckRig(scene, rig, caster, check);
  Summary typed = Summarize(scene, rig, fields, options.fields, threads, warnings);
  typed.time = time;
  typed.targets = std::move(targets);
  typed.sample_labels = sample_labels;
  typed.pixel_targets = std::move(pixel_targets);
  typed.dori = dori;
  if (scene.study.calibration)
    typed.calibration = SimulateCalibration(scene, rig, caster, *scene.study.calibration);
  // N-1: what the rig loses when any one camera fails, from the per-voxel camera sets (docs/failures.md).
  if (HasCameraSets(fields)) {
    typed.robustness = ComputeCriticality(scene, rig, fields, caster, scene.TimeMinCameras());
    AddCoverageN1Grid(&fields);
  }
  // PTZ cameras: reach times, reachable shares, tours (docs/ptz.md).
  if (RigHasPtz(rig)) typed.ptz = EvaluatePtzFields(scene, rig, caster, fields, &fields);
  nlohmann::json summary = typed;
  summary["run_id"] = output.run_id();
  if (mpi.active()) summary["mpi"] = mpi_summary;
  std::map<std::string, std::string> meta{
      {"run_id", output.run_id()},
      {"units", "m"},
      {"tool", "pandora"},
      {"tool_version", PANDORA_VERSION},
      {"scene_file", scene.path},
      {"scene_sha256", scene.sha256},
      {"rig_name", rig.name},
      {"rig", RigToJson(rig).dump()},
      {"voxel_size_m", FormatNumber(scene.study.voxel_size)},
  };
  WriteFieldsVdb(std::move(fields), vdb_path, meta);  // the last use: consumed to keep the peak down
  WriteFileAtomically(summary_path, summary.dump(2) + "\n");
  output.Commit();
  if (!args.quiet) {
    std::fputs(FormatSummary(typed).c_str(), stdout);
    std::printf("wrote %s and %s\n", (out / "fields.vdb").c_str(), (out / "summary.json").c_str());
    std::fflush(stdout);
    for (const Warning& w : warnings)
      std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  }
  return 0;
}

}  // namespace pandora::app
