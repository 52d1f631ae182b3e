#include <sys/resource.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/calibration.h"
#include "analysis/rig/rig_check.h"
#include "analysis/scene/mesh_io.h"
#include "analysis/scene/motion.h"
#include "analysis/scene/scene.h"
#include "analysis/scene/surface_targets.h"
#include "analysis/util/allocation_budget.h"
#include "analysis/util/error.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/mpi_session.h"
#include "app/output.h"
#include "app/session/analyze.h"
#include "app/session/session.h"
#include "volume/fields.h"
#include "volume/fields_transfer.h"
#include "volume/pixel_targets.h"
#include "volume/ptz_fields.h"
#include "volume/robustness.h"
#include "volume/summary.h"
#include "volume/summary_parts.h"
#include "volume/time_fields.h"
#include "volume/value_spill.h"
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
  if (fields.empty())
    throw InputError("--fields", "", "no field given", "e.g. --fields coverage,sigma_max");
  if (auto problem = CheckFieldList(fields, study.motion.has_value()))
    throw InputError("--fields", "", problem->reason, problem->hint);
  return fields;
}

// --memory-budget bounds the mesh imports as well (analysis/scene/mesh_io.h).
std::unique_ptr<ScopedMeshImportBudget> ImportBudget(const AnalyzeArgs& args) {
  if (std::isnan(args.memory_budget_mb) || !(args.memory_budget_mb > 0)) return nullptr;
  return std::make_unique<ScopedMeshImportBudget>(args.memory_budget_mb * 1048576.0,
                                                  "--memory-budget");
}

// The field options of `pandora analyze`: the study's, with --fields and --memory-budget applied.
FieldOptions AnalyzeFieldOptions(const AnalyzeArgs& args, const Scene& scene) {
  FieldOptions options;
  options.scene_path = scene.path;
  if (!std::isnan(args.voxel_size)) options.voxel_size_option = "--voxel-size";
  options.fields = scene.study.fields;
  if (!args.fields.empty())
    options.fields = CheckFieldsOption(SplitFields(args.fields), scene.study);
  options.memory_budget_bytes = scene.study.memory_budget_bytes;
  if (!std::isnan(args.memory_budget_mb)) {
    options.memory_budget_bytes =
        CheckPositiveOption("--memory-budget", args.memory_budget_mb, "MiB") * 1024.0 * 1024.0;
    CheckMemoryBudget(args.memory_budget_mb, "--memory-budget", "");
    options.memory_budget_option = "--memory-budget";
  }
  return options;
}

// The process's peak resident memory so far, MiB.
double PeakRssMiB() {
  struct rusage usage {};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // KiB on Linux
}

// An earlier run's outputs that this run does not replace would sit beside its summary.json as if
// they were this run's: an in-memory run removes every streamed tile, a streamed run of n tiles
// removes fields.vdb and tiles n and up (in the same transaction as the new outputs).
void RemoveStaleOutputs(OutputTransaction& output, const std::filesystem::path& out, bool streamed,
                        std::size_t tiles_written) {
  namespace fs = std::filesystem;
  if (streamed) output.Remove((out / "fields.vdb").string(), "--out");
  std::error_code ec;
  if (!fs::is_directory(out / "fields", ec)) return;
  for (const fs::directory_entry& e : fs::directory_iterator(out / "fields", ec)) {
    const std::string name = e.path().filename().string();
    unsigned index = 0;
    char tail[8] = {0};
    if (name.size() != 13 || std::sscanf(name.c_str(), "tile_%4u.%3s", &index, tail) != 2 ||
        std::string(tail) != "vdb")
      continue;
    if (!streamed || index >= tiles_written) output.Remove(e.path().string(), "--out");
  }
}

// The metadata of fields.vdb and of every streamed tile.
std::map<std::string, std::string> FieldsMetadata(const Scene& scene, const Rig& rig,
                                                  const std::string& run_id) {
  return {
      {"run_id", run_id},
      {"units", "m"},
      {"tool", "pandora"},
      {"tool_version", PANDORA_VERSION},
      {"scene_file", scene.path},
      {"scene_sha256", scene.sha256},
      {"rig_name", rig.name},
      {"rig", RigToJson(rig).dump()},
      {"voxel_size_m", FormatNumber(scene.study.voxel_size)},
  };
}

// The session options of an in-memory run: the rig, --disable, the fields and this process's
// partition of the blocks.
session::SessionOptions AnalyzeSessionOptions(const AnalyzeArgs& args, const Scene& scene,
                                              const MpiSession& mpi) {
  session::SessionOptions so;
  so.rig = args.rig;
  so.rig_option = "--rig";
  so.disable = args.disable;
  so.incremental = false;  // one evaluation: no per-pair state
  so.fields = AnalyzeFieldOptions(args, scene);
  // The summary reads sigma_max's percentiles from its grid: no second copy of the values.
  so.fields.value_lists = false;
  so.fields.partition_count = mpi.size();
  so.fields.partition_rank = mpi.rank();
  return so;
}

// Stages fields.vdb and summary.json beside the scene's inputs (rank 0), and removes an earlier
// run's streamed tiles.
void StageAnalyzeOutputs(OutputTransaction& output, const Scene& scene,
                         const std::filesystem::path& out, std::string& vdb_path,
                         std::string& summary_path) {
  AddSceneInputs(output, scene);
  vdb_path = output.Stage((out / "fields.vdb").string(), "--out");
  summary_path = output.Stage((out / "summary.json").string(), "--out");
  RemoveStaleOutputs(output, out, /*streamed=*/false, 0);
}

// Gathers every partition's fields at rank 0, merged into `fields`, with the per-rank statistics in
// `mpi_summary`; false on the other ranks (they are done).
bool MergeAtRoot(const MpiSession& mpi, Fields& fields, nlohmann::json& mpi_summary) {
  const auto t0 = std::chrono::steady_clock::now();
  const nlohmann::json mine{{"seconds", fields.stats.seconds},
                            {"rays", fields.stats.rays},
                            {"point_camera_tests", fields.stats.point_camera_tests}};
  const std::vector<std::string> parts =
      mpi.GatherToRoot(mine.dump() + '\n' + SerializePartialFields(fields));
  if (mpi.rank() != 0) return false;
  mpi_summary = {{"ranks", mpi.size()}, {"per_rank", nlohmann::json::array()}};
  mpi_summary["per_rank"].push_back(mine);
  for (std::size_t r = 1; r < parts.size(); ++r) {
    const std::size_t newline = parts[r].find('\n');
    mpi_summary["per_rank"].push_back(nlohmann::json::parse(parts[r].substr(0, newline)));
    MergePartialFields(parts[r].substr(newline + 1), &fields);
  }
  mpi_summary["merge_seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return true;
}

}  // namespace

double CheckPositiveOption(const char* option, double value, const char* unit) {
  if (!(value > 0) || !std::isfinite(value))
    throw InputError(option, "",
                     std::string("must be a positive number") + (*unit ? " of " : "") + unit);
  return value;
}

int RunAnalyze(const AnalyzeArgs& args) {
  if (args.stream) return RunStreamedAnalyze(args);
  if (!std::isnan(args.tile_size))
    throw InputError("--tile-size", "", "applies to a streamed run only", "add --stream");
  // Under mpirun every process runs this; rank 0 alone prints, stages and writes (docs/scale.md).
  const MpiSession mpi(args.mpi);
  const bool root = mpi.rank() == 0;
  const bool quiet = args.quiet || !root;
  // The study, with --voxel-size applied, and the rig, through the session layer; then the
  // outputs staged. Both outputs appear together (summary.json last), or neither does. Every
  // process reads its own copy of the inputs: one collective check after all of this, so an error
  // on any process (rank 0's staging included) ends every process with its one line, and none is
  // left waiting.
  std::shared_ptr<const session::Study> study;
  session::SessionOptions so;
  std::optional<ProgressBar> bar;
  std::optional<session::Session> session_holder;
  const std::filesystem::path out(args.out);
  OutputTransaction output;
  std::string vdb_path, summary_path;
  std::exception_ptr failure;
  try {
    {
      const auto import_budget = ImportBudget(args);
      study = LoadStudyWithVoxelSize(args.scene, args.voxel_size);
    }
    so = AnalyzeSessionOptions(args, study->scene(), mpi);
    bar.emplace("analyze " + study->FindRig(args.rig, "--rig").name +
                    (mpi.active() ? " (rank 0 of " + std::to_string(mpi.size()) + ")" : ""),
                !quiet);
    so.fields.progress = [&bar](double f) { bar->Update(f); };
    if (root) StageAnalyzeOutputs(output, study->scene(), out, vdb_path, summary_path);
    if (!mpi.active()) {
      // Every float field goes to disk leaf by leaf as its blocks finish, beside the staged
      // outputs: the analyses after the evaluation read each one back when they need it, one at a
      // time (Fields::Impl::Load), and fields.vdb is written a grid at a time
      // (docs/performance.md, "All nine fields against coverage alone").
      for (const std::string& f : so.fields.fields)
        if (f != "coverage" && f != "cameras") so.fields.spilled_fields.push_back(f);
      so.fields.spill_folder = std::filesystem::path(vdb_path).parent_path().string();
      so.fields.spill_blame = "--out";
    }
    session_holder.emplace(study, so);
  } catch (...) {
    failure = std::current_exception();
  }
  mpi.ThrowIfAnyFailed(failure);
  const Scene& scene = study->scene();
  FieldOptions& options = so.fields;
  session::Session& session = *session_holder;
  const Rig& rig = session.rig().rig();

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
  bar->Finish();
  // The partitions meet at rank 0: grids merged, statistics added (volume/fields_transfer.h).
  nlohmann::json mpi_summary;
  if (mpi.active() && !MergeAtRoot(mpi, fields, mpi_summary)) return 0;
  // Everything beside the fields, as every front end computes it (app/session/analyze.h): time
  // samples and surface targets, pixel targets and DORI, warnings, calibration, N-1, PTZ.
  session::AnalyzeOptions analysis;
  analysis.fields = options;
  analysis.fields.solid_trees = &study->solid_trees();  // the plausibility checks use them too
  analysis.spill_folder = out.string();
  analysis.spill_blame = "--out";
  analysis.threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  std::optional<ProgressBar> time_bar;
  analysis.time_stage = [&](std::size_t samples) -> std::function<void(double)> {
    time_bar.emplace("over " + std::to_string(samples) + " time samples", !args.quiet);
    return [&time_bar](double f) { time_bar->Update(f); };
  };
  session::RigAnalysis result =
      session::CompleteAnalysis(scene, study->caster(), rig, fields, &fields, analysis);
  if (time_bar) time_bar->Finish();
  const Summary& typed = result.summary;
  const std::vector<Warning>& warnings = result.warnings;
  nlohmann::json summary = typed;
  summary["run_id"] = output.run_id();
  if (mpi.active()) summary["mpi"] = mpi_summary;
  WriteFieldsVdb(
      std::move(fields), vdb_path,
      FieldsMetadata(scene, rig, output.run_id()));  // the last use: consumed to keep the peak down
  // The process's peak resident memory, the fields written (what the memory budget bounds).
  summary["timing"]["peak_rss_mib"] = PeakRssMiB();
  summary["timing"]["memory_budget_mib"] = options.memory_budget_bytes / 1048576.0;
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

namespace pandora::app {
namespace {

std::string Triple(const Eigen::Vector3i& v) {
  return std::to_string(v.x()) + "," + std::to_string(v.y()) + "," + std::to_string(v.z());
}

// The additive part of FieldStats, to send to rank 0 and add up there.
nlohmann::json StatsToJson(const FieldStats& s) {
  return {{"region_voxels", s.active_set.region_voxels},
          {"solid_voxels", s.active_set.solid_voxels},
          {"blocks", s.active_set.blocks},
          {"culled_blocks", s.active_set.culled_blocks},
          {"seen", s.seen_voxels},
          {"triangulable", s.triangulable_voxels},
          {"unobservable", s.unobservable_voxels},
          {"tests", s.point_camera_tests},
          {"rays", s.rays},
          {"seconds", s.seconds},
          {"cpu_seconds", s.cpu_seconds},
          {"active_set_seconds", s.active_set_seconds},
          {"estimated", s.estimated_bytes},
          {"histogram", s.coverage_histogram},
          {"per_camera", s.per_camera_seen}};
}

void AddStats(FieldStats* s, const nlohmann::json& j) {
  FieldStats part;
  part.active_set.region_voxels = j.at("region_voxels").get<std::int64_t>();
  part.active_set.solid_voxels = j.at("solid_voxels").get<std::int64_t>();
  part.active_set.blocks = j.at("blocks").get<std::int64_t>();
  part.active_set.culled_blocks = j.at("culled_blocks").get<std::int64_t>();
  part.seen_voxels = j.at("seen").get<std::int64_t>();
  part.triangulable_voxels = j.at("triangulable").get<std::int64_t>();
  part.unobservable_voxels = j.at("unobservable").get<std::int64_t>();
  part.point_camera_tests = j.at("tests").get<std::int64_t>();
  part.rays = j.at("rays").get<std::int64_t>();
  // Across processes the sum of the times is the work (the slowest would be the wall time).
  part.seconds = j.at("seconds").get<double>();
  part.cpu_seconds = j.at("cpu_seconds").get<double>();
  part.active_set_seconds = j.at("active_set_seconds").get<double>();
  part.estimated_bytes = j.at("estimated").get<double>();  // the largest tile's is kept
  part.coverage_histogram = j.at("histogram").get<std::vector<std::int64_t>>();
  part.per_camera_seen = j.at("per_camera").get<std::vector<std::int64_t>>();
  AddFieldStats(s, part);
}

nlohmann::json RegionCountsToJson(const std::vector<RegionCounts>& regions) {
  nlohmann::json out = nlohmann::json::array();
  for (const RegionCounts& r : regions) out.push_back({r.voxels, r.ge[0], r.ge[1], r.ge[2]});
  return out;
}

// Every process's `counts` (`size` of them), summed at rank 0 (empty on the others).
std::vector<std::int64_t> SumCountsAtRoot(const MpiSession& mpi,
                                          const std::vector<std::int64_t>& counts,
                                          std::size_t size) {
  const std::vector<std::string> parts = mpi.GatherToRoot(
      std::string(reinterpret_cast<const char*>(counts.data()), counts.size() * 8));
  std::vector<std::int64_t> sum(parts.empty() ? 0 : size, 0);
  for (const std::string& p : parts)
    for (std::size_t i = 0; i < size && i < p.size() / 8; ++i) {
      std::int64_t v;
      std::memcpy(&v, p.data() + 8 * i, 8);
      sum[i] += v;
    }
  return sum;
}

// Every process's `counts` summed, on every process (a collective).
std::vector<std::int64_t> AllSum(const MpiSession& mpi, const std::vector<std::int64_t>& counts) {
  if (!mpi.active()) return counts;
  const std::vector<std::int64_t> sum = SumCountsAtRoot(mpi, counts, counts.size());
  const std::string sent = mpi.Broadcast(
      std::string(reinterpret_cast<const char*>(sum.data()), sum.size() * sizeof(std::int64_t)));
  std::vector<std::int64_t> out(sent.size() / sizeof(std::int64_t));
  std::memcpy(out.data(), sent.data(), out.size() * sizeof(std::int64_t));
  return out;
}

// What a streamed run reads and plans before anything is staged.
struct StreamSetup {
  std::shared_ptr<const session::Study> study;
  Rig rig;
  FieldOptions options;
  std::vector<BlockColumns> tiles;
  VoxelLattice lattice;
  // Moving objects: the time samples and the scene's rigid parts (built once, for every tile).
  std::vector<TimeSample> samples;
  std::unique_ptr<RigidPartsRayCaster> parts;
  double parts_seconds = 0;
};

StreamSetup PrepareStream(const AnalyzeArgs& args) {
  StreamSetup setup;
  {
    const auto import_budget = ImportBudget(args);
    setup.study = LoadStudyWithVoxelSize(args.scene, args.voxel_size);
  }
  const auto& study = setup.study;
  const Scene& scene = study->scene();
  setup.rig = session::DisableCameras(study->FindRig(args.rig, "--rig"), args.disable, "--disable");
  setup.options = AnalyzeFieldOptions(args, scene);
  FieldOptions& options = setup.options;
  options.solid_trees = &study->solid_trees();
  const double tile_side = std::isnan(args.tile_size)
                               ? 0.0
                               : CheckPositiveOption("--tile-size", args.tile_size, "metres");
  setup.lattice =
      MakeLattice(scene.study.region.box, scene.study.voxel_size,
                  options.voxel_size_option.empty() ? scene.path : options.voxel_size_option,
                  options.voxel_size_option.empty() ? "$.study.voxel_size" : "");
  const VoxelLattice& lattice = setup.lattice;
  // The tiles share the budget with the scene's structures (held for the whole run).
  setup.tiles =
      PlanTiles(lattice, options.fields,
                std::max(0.0, options.memory_budget_bytes - SceneStructureBytes(scene)), tile_side);
  const std::vector<BlockColumns>& tiles = setup.tiles;
  if (scene.Animated() || scene.study.targets) {
    const auto t0 = std::chrono::steady_clock::now();
    setup.samples = scene.TimeSamples();
    setup.parts = MakeSceneParts(scene);
    setup.parts_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  constexpr std::size_t kMostTiles = 10000;
  if (tiles.size() > kMostTiles) {
    // Blame what sized the tiles: --tile-size, --memory-budget, or the scene's budget.
    const bool by_side = !std::isnan(args.tile_size),
               by_option = !options.memory_budget_option.empty();
    throw InputError(by_side     ? "--tile-size"
                     : by_option ? options.memory_budget_option
                                 : scene.path,
                     by_side || by_option ? "" : "$.study.memory_budget_mb",
                     "the region would stream in " + std::to_string(tiles.size()) +
                         " tiles, over " + std::to_string(kMostTiles),
                     "raise the memory budget, or use larger tiles or a coarser voxel size");
  }
  return setup;
}

// The tiles' files under --out: fields/tile_NNNN.vdb.
std::vector<std::string> TileFileNames(std::size_t count) {
  std::vector<std::string> tile_files;
  for (std::size_t t = 0; t < count; ++t) {
    char name[48];
    std::snprintf(name, sizeof name, "fields/tile_%04zu.vdb", t);
    tile_files.push_back(name);
  }
  return tile_files;
}

// Stages every tile and summary.json beside the scene's inputs (rank 0) and removes an earlier
// run's outputs this run does not replace; returns the staged tile paths and the run id, one a
// line, for the other processes.
std::string StageStreamOutputs(OutputTransaction& output, const Scene& scene,
                               const std::filesystem::path& out,
                               const std::vector<std::string>& tile_files,
                               std::vector<std::string>& tile_paths, std::string& summary_path) {
  std::string staged;
  AddSceneInputs(output, scene);
  for (const std::string& name : tile_files) {
    tile_paths.push_back(output.Stage((out / name).string(), "--out"));
    staged += tile_paths.back() + '\n';
  }
  summary_path = output.Stage((out / "summary.json").string(), "--out");
  RemoveStaleOutputs(output, out, /*streamed=*/true, tile_files.size());
  staged += output.run_id();
  return staged;
}

// A process's tiles added up: their statistics, the tile list for the summary, and the values
// behind the summary's percentiles spilled to disk (volume/value_spill.h) beside the staged tiles.
struct StreamTotals {
  StreamTotals(std::size_t region_count, const std::string& spill_folder, CountReducer reduce)
      : regions(region_count),
        region_spills(2 * region_count),
        time(spill_folder, "--out", reduce),
        pixel_targets(spill_folder, "--out", reduce),
        criticality(spill_folder, "--out", reduce),
        ptz(spill_folder, "--out", reduce) {}
  std::unique_ptr<ValueSpill> spills[3];  // resolution, sigma_max, sigma_max_steady
  FieldStats total;
  DoriSummary dori;
  // The named sub-regions: counts added up, values spilled (density, sigma_max per region).
  std::vector<RegionCounts> regions;
  std::vector<std::unique_ptr<ValueSpill>> region_spills;
  // The analyses beside the fields, part by part (volume/summary_parts.h): the fields over time,
  // pixel-size targets, N-1 criticality and PTZ fields of each tile.
  SpilledParts time, pixel_targets, criticality, ptz;
  nlohmann::json tile_list = nlohmann::json::array();
};

// The analyses beside the fields over one tile's fields `f` (evaluated with `tile_options`), as
// CompleteAnalysis runs them in memory (app/session/analyze.h): their derived grids into `f`,
// their parts added to `totals`.
void AnalyzeStreamTile(const StreamSetup& setup, const FieldOptions& tile_options, Fields& f,
                       StreamTotals& totals) {
  const Scene& scene = setup.study->scene();
  const Rig& rig = setup.rig;
  const int k = scene.TimeMinCameras();
  if (scene.Animated() && !setup.samples.empty()) {
    FieldOptions over_time = OverTimeOptions(tile_options);
    over_time.progress = nullptr;
    // The tile's fields stay held while its samples run: the samples get what the budget leaves
    // (PlanTiles gave the tile at most half of it, and the samples need at most what the tile did).
    over_time.memory_budget_bytes =
        std::max(0.0, tile_options.memory_budget_bytes - f.stats.estimated_bytes);
    totals.time.Add(TimeFieldsParts(scene, rig, *setup.parts, setup.samples, over_time, k, &f));
  }
  totals.pixel_targets.Add(PixelTargetParts(scene, rig, f, k, &f));
  if (HasCameraSets(f)) {
    // A part's lists (8 bytes per triangulable voxel and camera that sees it) at a time, as
    // small as the in-memory run's spilled parts (faster than large ones, and within any budget).
    AddCriticalityParts(scene, rig, f, setup.study->caster(), k, totals.criticality);
    AddCoverageN1Grid(&f);
  }
  if (RigHasPtz(rig)) totals.ptz.Add(PtzFieldsParts(scene, rig, setup.study->caster(), f, &f));
}

// Evaluates this process's tiles (every size-th) one at a time, each written to its staged path
// and then dropped; adds them up in `totals`, the values spilled into `spill_folder`.
void EvaluateStreamTiles(const StreamSetup& setup, const MpiSession& mpi,
                         const std::vector<std::string>& tile_files,
                         const std::vector<std::string>& tile_paths,
                         const std::map<std::string, std::string>& meta,
                         const std::string& spill_folder, bool want_resolution, ProgressBar& bar,
                         StreamTotals& totals) {
  const auto& study = setup.study;
  const Scene& scene = study->scene();
  const Rig& rig = setup.rig;
  const FieldOptions& options = setup.options;
  const std::vector<BlockColumns>& tiles = setup.tiles;
  const VoxelLattice& lattice = setup.lattice;
  auto& spills = totals.spills;
  FieldStats& total = totals.total;
  DoriSummary& dori = totals.dori;
  std::vector<RegionCounts>& regions = totals.regions;
  auto& region_spills = totals.region_spills;
  nlohmann::json& tile_list = totals.tile_list;
  std::vector<std::size_t> mine;
  for (std::size_t t = std::size_t(mpi.rank()); t < tiles.size(); t += std::size_t(mpi.size()))
    mine.push_back(t);
  for (auto& spill : spills) spill = std::make_unique<ValueSpill>(spill_folder, "--out");
  for (auto& spill : region_spills) spill = std::make_unique<ValueSpill>(spill_folder, "--out");
  for (std::size_t i = 0; i < mine.size(); ++i) {
    const std::size_t t = mine[i];
    FieldOptions o = options;
    o.tile = tiles[t];
    o.progress = [&bar, i, n = mine.size()](double f) { bar.Update((double(i) + f) / double(n)); };
    Fields f = EvaluateFields(scene, rig, study->caster(), o);
    ReleaseFreedMemory();  // the tile's freed blocks, before its analyses
    FieldStats& st = f.stats;
    AnalyzeStreamTile(setup, o, f, totals);
    // DORI classes: the tile's grid, and its counts added up (the shares at the end).
    if (scene.study.dori) {
      const DoriSummary d = EvaluateDori(scene, f, &f);
      dori.voxels += d.voxels;
      for (int k = 0; k < 4; ++k) dori.reached[k] += d.reached[k];
    }
    const std::vector<RegionCounts> tile_regions = CountRegions(scene, f);
    for (std::size_t r = 0; r < tile_regions.size(); ++r) {
      regions[r].voxels += tile_regions[r].voxels;
      for (int k = 0; k < 3; ++k) regions[r].ge[k] += tile_regions[r].ge[k];
      region_spills[2 * r]->Append(tile_regions[r].densities);
      region_spills[2 * r + 1]->Append(tile_regions[r].sigmas);
    }
    if (want_resolution) spills[0]->Append(GridActiveValues(f, "resolution"));
    spills[1]->Append(st.sigma_max_mm);
    spills[2]->Append(st.sigma_max_steady_mm);
    std::vector<float>().swap(st.sigma_max_mm);  // spilled: not kept in memory
    std::vector<float>().swap(st.sigma_max_steady_mm);
    AddFieldStats(&total, st);
    const Eigen::Vector3i lo = tiles[t].VoxelMin(), end = tiles[t].VoxelEnd(lattice);
    std::map<std::string, std::string> tile_meta = meta;
    tile_meta["tile"] = std::to_string(t) + " of " + std::to_string(tiles.size());
    tile_meta["tile_voxel_min"] = Triple(lo);
    tile_meta["tile_voxel_end"] = Triple(end);
    tile_list.push_back({{"index", t},
                         {"file", tile_files[t]},
                         {"voxel_min", {lo.x(), lo.y(), lo.z()}},
                         {"voxel_end", {end.x(), end.y(), end.z()}},
                         {"region_voxels", st.active_set.region_voxels},
                         {"seen_voxels", st.seen_voxels},
                         {"seconds", st.seconds},
                         {"rank", mpi.rank()}});
    WriteFieldsVdb(std::move(f), tile_paths[t], tile_meta);  // then dropped: one tile at a time
  }
}

// Rank 0 adds up every process's statistics into `totals` (from `parts`, its own included), with
// every tile in `all_tiles` by index and each process's peak memory in `peak_rss`.
void AddUpAtRoot(const std::vector<std::string>& parts, std::size_t region_count,
                 StreamTotals& totals, nlohmann::json& all_tiles, nlohmann::json& peak_rss) {
  FieldStats& total = totals.total;
  DoriSummary& dori = totals.dori;
  std::vector<RegionCounts>& regions = totals.regions;
  total = FieldStats{};
  dori = DoriSummary{};
  regions.assign(region_count, RegionCounts{});
  for (const std::string& p : parts) {
    const nlohmann::json j = nlohmann::json::parse(p);
    AddStats(&total, j.at("stats"));
    const auto counts = j.at("dori").get<std::vector<std::int64_t>>();
    dori.voxels += counts.at(0);
    for (int k = 0; k < 4; ++k) dori.reached[k] += counts.at(1 + k);
    const auto& rs = j.at("regions");
    for (std::size_t r = 0; r < region_count; ++r) {
      regions[r].voxels += rs.at(r).at(0).get<std::int64_t>();
      for (int k = 0; k < 3; ++k) regions[r].ge[k] += rs.at(r).at(1 + k).get<std::int64_t>();
    }
    for (const auto& tile : j.at("tiles")) all_tiles.push_back(tile);
    peak_rss.push_back(j.at("peak_rss_mib"));
  }
  std::sort(all_tiles.begin(), all_tiles.end(),
            [](const auto& a, const auto& b) { return a.at("index") < b.at("index"); });
}

// The summary's percentiles and target shares from every process's spilled values, and each named
// region's summary (rank 0's; the other processes' are not used).
struct StreamPercentiles {
  std::vector<std::optional<double>> resolution_p, sigma_p, steady_p;
  std::int64_t sigma_meets = 0, steady_meets = 0;
  std::vector<RegionSummary> region_summaries;
};

// Selects the percentiles by two rounds of summed counts (a collective: every process calls it).
StreamPercentiles SelectStreamPercentiles(const MpiSession& mpi, const Scene& scene,
                                          const FieldOptions& options, const StreamTotals& totals,
                                          bool want_resolution) {
  const std::size_t region_count = scene.study.regions.size();
  const auto& spills = totals.spills;
  const auto& region_spills = totals.region_spills;
  const std::vector<RegionCounts>& regions = totals.regions;
  const auto percentiles = [&](const ValueSpill& spill, const std::vector<double>& p) {
    // Rank 0 selects the bins from the summed upper counts; every process counts inside them.
    const PercentileBins selection =
        SelectPercentileBins(SumCountsAtRoot(mpi, spill.HighCounts(), 1 << 16), p);
    const std::string sent = mpi.Broadcast(std::string(
        reinterpret_cast<const char*>(selection.bins.data()), selection.bins.size() * 4));
    std::vector<std::uint32_t> bins(sent.size() / 4);
    std::memcpy(bins.data(), sent.data(), sent.size());
    return ResolvePercentiles(
        selection, SumCountsAtRoot(mpi, spill.LowCounts(bins), bins.size() << 16), p.size());
  };
  const auto sum_at_root = [&](std::int64_t count) {
    const std::vector<std::int64_t> sum = SumCountsAtRoot(mpi, {count}, 1);
    return sum.empty() ? std::int64_t(0) : sum[0];  // rank 0's; the others' are not used
  };
  const std::vector<std::optional<double>> resolution_p = percentiles(*spills[0], {10, 50, 90});
  const std::vector<std::optional<double>> sigma_p = percentiles(*spills[1], {50, 90, 99});
  const std::vector<std::optional<double>> steady_p = percentiles(*spills[2], {50, 90, 99});
  // The shares meeting the study's target (a pass over each file only when there is one).
  const std::optional<double> target = scene.study.max_sigma_mm;
  const std::int64_t sigma_meets = target ? sum_at_root(spills[1]->CountAtMost(*target)) : 0;
  const std::int64_t steady_meets = target ? sum_at_root(spills[2]->CountAtMost(*target)) : 0;
  // Each region's percentiles, and how many of its voxels have a sigma_max (every process's spill).
  std::vector<RegionSummary> region_summaries;
  const bool has_sigma =
      std::find(options.fields.begin(), options.fields.end(), "sigma_max") != options.fields.end();
  for (std::size_t r = 0; r < region_count; ++r) {
    const auto p10 = percentiles(*region_spills[2 * r], {10});
    const auto sigma_p = percentiles(*region_spills[2 * r + 1], {50, 90});
    const std::int64_t sigma_count = sum_at_root(region_spills[2 * r + 1]->size());
    region_summaries.push_back(FinishRegion(scene.study.regions[r].first, regions[r],
                                            want_resolution, has_sigma, sigma_count, p10[0],
                                            sigma_p[0], sigma_p[1]));
  }
  return {resolution_p, sigma_p, steady_p, sigma_meets, steady_meets, std::move(region_summaries)};
}

// The percentiles and shares from the spilled values into `typed`: the same nearest ranks over the
// same multisets as an in-memory run.
void ApplyStreamPercentiles(const StreamPercentiles& p, bool want_resolution, const Fields& merged,
                            Summary& typed) {
  if (want_resolution)
    typed.resolution_px_per_m =
        ResolutionPercentiles{p.resolution_p[0], p.resolution_p[1], p.resolution_p[2]};
  if (typed.uncertainty) {
    UncertaintySummary& u = *typed.uncertainty;
    const std::int64_t region = merged.stats.active_set.region_voxels;
    const auto share = [region](std::int64_t n) {
      return region > 0 ? double(n) / double(region) : 0.0;
    };
    u.sigma_max_mm = SigmaPercentiles{p.sigma_p[0], p.sigma_p[1], p.sigma_p[2]};
    if (u.max_sigma_mm) u.meets_max_sigma = share(p.sigma_meets);
    if (u.motion) {
      u.sigma_max_steady_mm = SigmaPercentiles{p.steady_p[0], p.steady_p[1], p.steady_p[2]};
      if (u.max_sigma_mm) u.meets_max_sigma_steady = share(p.steady_meets);
    }
  }
}

// This process's totals as rank 0 adds them up, with its peak memory so far.
nlohmann::json StreamPartJson(const StreamTotals& totals) {
  const nlohmann::json part{{"stats", StatsToJson(totals.total)},
                            {"tiles", totals.tile_list},
                            {"dori",
                             {totals.dori.voxels, totals.dori.reached[0], totals.dori.reached[1],
                              totals.dori.reached[2], totals.dori.reached[3]}},
                            {"regions", RegionCountsToJson(totals.regions)},
                            {"peak_rss_mib", PeakRssMiB()}};
  return part;
}

// The analyses beside the fields, finished from every tile's parts.
struct StreamAnalyses {
  std::optional<TimeSummary> time;
  std::vector<PixelTargetSummary> pixel_targets;
  std::optional<CriticalityTable> criticality;
  std::optional<PtzFieldsSummary> ptz;
};

// Sums every process's parts and finishes each analysis (a collective: every process calls it; the
// results are rank 0's to use).
StreamAnalyses FinishStreamAnalyses(const StreamSetup& setup, StreamTotals& totals) {
  const Scene& scene = setup.study->scene();
  const Rig& rig = setup.rig;
  const int k = scene.TimeMinCameras();
  StreamAnalyses out;
  for (SpilledParts* parts :
       {&totals.time, &totals.pixel_targets, &totals.criticality, &totals.ptz})
    parts->Reduce();
  if (scene.Animated() && !setup.samples.empty()) {
    out.time = FinishTimeFields(setup.samples, k, totals.time.Counts(), totals.time.Seconds(),
                                totals.time);
    double seconds = 0;
    for (double s : totals.time.Seconds()) seconds += s;
    out.time->seconds = seconds;
    out.time->parts_seconds = setup.parts_seconds;
  }
  SummaryParts pixel;
  pixel.counts = totals.pixel_targets.Counts();
  pixel.seconds = totals.pixel_targets.Seconds();
  out.pixel_targets = FinishPixelTargets(scene, k, pixel);
  if (!totals.criticality.Counts().empty()) {  // (the region's size is rank 0's sum: its result)
    const auto t0 = std::chrono::steady_clock::now();
    out.criticality = FinishCriticality(rig, k, totals.total.active_set.region_voxels,
                                        totals.criticality.Counts(), totals.criticality);
    // The tiles' parts (summed over tiles and processes) and the percentiles over all of them.
    out.criticality->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (double s : totals.criticality.Seconds()) out.criticality->seconds += s;
  }
  if (RigHasPtz(rig))
    out.ptz = FinishPtzFields(scene, rig, totals.ptz.Counts(), totals.ptz.Seconds(), totals.ptz);
  return out;
}

// The finished analyses into the summary, as CompleteAnalysis sets them in memory; the surface
// targets (they do not depend on the region) computed here.
void ApplyStreamAnalyses(const StreamSetup& setup, StreamAnalyses&& analyses, Summary& typed) {
  const Scene& scene = setup.study->scene();
  if (scene.Animated() || scene.study.targets) {
    for (const TimeSample& s : setup.samples) typed.sample_labels.push_back(s.label);
    typed.time = std::move(analyses.time);
    typed.targets = EvaluateSurfaceTargets(scene, setup.rig, *setup.parts, setup.samples,
                                           scene.TimeMinCameras());
  }
  typed.pixel_targets = std::move(analyses.pixel_targets);
  typed.robustness = std::move(analyses.criticality);
  typed.ptz = std::move(analyses.ptz);
}

}  // namespace

int RunStreamedAnalyze(const AnalyzeArgs& args) {
  // Under mpirun every process evaluates its share of the tiles and writes them itself (into rank
  // 0's staging folder: the processes share a file system); rank 0 adds up the statistics and
  // writes the summary (docs/scale.md). Every process reads its own copy of the inputs, then rank
  // 0 stages the outputs: one collective check after both, so an error on any process ends them
  // all with its one line.
  const MpiSession mpi(args.mpi);
  const bool root = mpi.rank() == 0;
  StreamSetup setup;
  // Every tile and the summary appear together (summary.json last), or none does.
  const std::filesystem::path out(args.out);
  OutputTransaction output;
  std::vector<std::string> tile_files, tile_paths;
  std::string summary_path, staged;
  std::exception_ptr failure;
  try {
    setup = PrepareStream(args);
    tile_files = TileFileNames(setup.tiles.size());
    if (root)
      staged = StageStreamOutputs(output, setup.study->scene(), out, tile_files, tile_paths,
                                  summary_path);
  } catch (...) {
    failure = std::current_exception();
  }
  mpi.ThrowIfAnyFailed(failure);
  const auto& study = setup.study;
  const Scene& scene = study->scene();
  const Rig& rig = setup.rig;
  const FieldOptions& options = setup.options;
  const std::vector<BlockColumns>& tiles = setup.tiles;
  const VoxelLattice& lattice = setup.lattice;
  // The staged paths and the run id, from rank 0 to every process.
  std::string run_id = output.run_id();
  if (mpi.active()) {
    std::istringstream lines(mpi.Broadcast(staged));
    tile_paths.assign(tiles.size(), {});
    for (std::string& path : tile_paths) std::getline(lines, path);
    std::getline(lines, run_id);
  }

  const bool want_resolution =
      std::find(options.fields.begin(), options.fields.end(), "resolution") != options.fields.end();
  const std::map<std::string, std::string> meta = FieldsMetadata(scene, rig, run_id);
  // This process's tiles (every size-th), their statistics added up, the values behind the
  // summary's percentiles spilled to disk (volume/value_spill.h) beside the staged tiles.
  const std::string spill_folder = std::filesystem::path(tile_paths[0]).parent_path().string();
  const std::size_t region_count = scene.study.regions.size();
  StreamTotals totals(region_count, spill_folder,
                      [&mpi](const std::vector<std::int64_t>& v) { return AllSum(mpi, v); });
  ProgressBar bar("analyze " + rig.name + " (streamed, " + std::to_string(tiles.size()) + " tiles" +
                      (mpi.active() ? ", rank 0 of " + std::to_string(mpi.size()) : "") + ")",
                  !(args.quiet || !root));
  try {
    EvaluateStreamTiles(setup, mpi, tile_files, tile_paths, meta, spill_folder, want_resolution,
                        bar, totals);
  } catch (...) {
    failure = std::current_exception();
  }
  if (!mpi.AllOk(!failure)) {
    if (failure && root) std::rethrow_exception(failure);
    return 2;
  }
  bar.Finish();

  // Rank 0 adds up every process's statistics; the percentiles are selected from every process's
  // spilled values by two rounds of summed counts (only the counts travel).
  const std::vector<std::string> parts = mpi.GatherToRoot(StreamPartJson(totals).dump());
  nlohmann::json all_tiles = nlohmann::json::array(), peak_rss = nlohmann::json::array();
  if (root) AddUpAtRoot(parts, region_count, totals, all_tiles, peak_rss);
  StreamPercentiles p = SelectStreamPercentiles(mpi, scene, options, totals, want_resolution);
  // The analyses beside the fields from every tile's parts (collectives: every process finishes).
  StreamAnalyses analyses = FinishStreamAnalyses(setup, totals);
  if (!root) return 0;

  Fields merged;
  merged.lattice = lattice;
  merged.stats = std::move(totals.total);
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  RigCheckOptions check;
  check.visible_voxels = merged.stats.per_camera_seen;
  study->solid_trees().LendTo(scene, &check);  // built by the tiles already
  const std::vector<Warning> warnings = CheckRig(scene, rig, study->caster(), check);
  Summary typed = Summarize(scene, rig, merged, options.fields, threads, warnings);
  ApplyStreamPercentiles(p, want_resolution, merged, typed);
  if (scene.study.dori) {
    totals.dori.SetShares();
    typed.dori = totals.dori;
  }
  typed.regions = std::move(p.region_summaries);
  ApplyStreamAnalyses(setup, std::move(analyses), typed);
  if (scene.study.calibration)
    typed.calibration = SimulateCalibration(scene, rig, study->caster(), *scene.study.calibration);
  nlohmann::json summary = typed;
  summary["run_id"] = run_id;
  summary["stream"] = {{"tiles", all_tiles},
                       {"tile_count", tiles.size()},
                       {"ranks", mpi.size()},
                       {"memory_budget_mib", options.memory_budget_bytes / 1048576.0},
                       {"largest_tile_estimate_mib", merged.stats.estimated_bytes / 1048576.0},
                       {"peak_rss_mib", peak_rss}};
  WriteFileAtomically(summary_path, summary.dump(2) + "\n");
  output.Commit();
  if (!args.quiet) {
    std::fputs(FormatSummary(typed).c_str(), stdout);
    std::printf("wrote %zu tiles in %s and %s (peak memory %.0f MiB%s)\n", tiles.size(),
                (out / "fields").c_str(), (out / "summary.json").c_str(), PeakRssMiB(),
                mpi.active() ? " on rank 0" : "");
    std::fflush(stdout);
    for (const Warning& w : warnings)
      std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  }
  return 0;
}

// Registers `pandora analyze` and its options.
Command AddAnalyzeCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<AnalyzeArgs>();
  AnalyzeArgs& analyze = *args;
  int& threads = common.threads;
  const CLI::Validator& threads_check = common.threads_check;
  CLI::App* a = app.add_subcommand(
      "analyze", "Evaluate fields over the study region; write fields.vdb and summary.json");
  a->add_option("scene", analyze.scene, "Scene file (JSON)")->required();
  a->add_option("--rig", analyze.rig, "Rig name (default: the first rig)");
  a->add_option("--disable", analyze.disable,
                "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                "loses when they fail)")
      ->delimiter(',');
  a->add_option("--out", analyze.out, "Output folder")->capture_default_str();
  a->add_option("--voxel-size", analyze.voxel_size,
                "Voxel size in metres (default: study.voxel_size)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  a->add_option("--fields", analyze.fields, "Comma-separated fields (default: study.fields)");
  a->add_option("--memory-budget", analyze.memory_budget_mb,
                "Memory budget in MiB (default: study.memory_budget_mb)")
      ->check(Number(0, HUGE_VAL, "MiB", false, true));
  a->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  a->add_flag("--quiet,-q", analyze.quiet, "Print nothing but errors");
  a->add_flag("--mpi", analyze.mpi,
              "Under mpirun: split the blocks over the processes; rank 0 writes (docs/scale.md)");
  a->add_flag("--stream", analyze.stream,
              "Evaluate and write the region tile by tile within the memory budget: "
              "fields/tile_NNNN.vdb (docs/scale.md)");
  a->add_option(
       "--tile-size", analyze.tile_size,
       "With --stream: the tiles' side in metres (default: as few tiles as the budget allows)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  return {a, [args] { return RunAnalyze(*args); }};
}

}  // namespace pandora::app
