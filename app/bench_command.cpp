// `pandora bench`: field evaluation against a raw Embree occlusion loop over the very same rays,
// measured in the same run, so the ratio is meaningful on a shared, noisy machine.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/session/study.h"
#include "volume/fields.h"
#include "volume/fields_transfer.h"
#include "volume/time_fields.h"

namespace pandora::app {

namespace {

// The bench's tiles, evaluated one after another: the region's block columns as `pandora analyze
// --stream` plans them within the budget (less the scene's structures), no wider than keeps one
// tile's recorded rays within a quarter of it (a ray is 64 bytes and its Embree copy 48 more;
// at most one per free voxel and enabled camera). One tile (the whole region) when it fits.
std::vector<BlockColumns> BenchTiles(const Scene& scene, const Rig& rig,
                                     const FieldOptions& options,
                                     const std::vector<std::string>& fields,
                                     const VoxelLattice& lattice) {
  const double budget = std::max(0.0, options.memory_budget_bytes - SceneStructureBytes(scene));
  const double vs = lattice.voxel_size;
  const double ray_bytes_per_m2 = double(lattice.dims.z()) / (vs * vs) *
                                  double(std::max(1, rig.enabled_count())) * (sizeof(Ray) + 48.0);
  const double area = double(lattice.dims.x()) * double(lattice.dims.y()) * vs * vs;
  const double side = ray_bytes_per_m2 * area > budget / 4
                          ? std::max(8 * vs, std::sqrt(budget / 4 / ray_bytes_per_m2))
                          : 0.0;
  return PlanTiles(lattice, fields, budget, side);
}

// What the bench times, summed over its tiles: each tile's best of the repetitions (the tiles are
// disjoint, so the sums are the whole region's), with the statistics of the whole region.
struct BenchTimes {
  std::size_t tiles = 0, largest_tile_rays = 0;
  std::vector<std::string> uncertainty_fields, all_fields;
  double fields = 0, raw = 0, packet = 0;  // the field evaluation and the two raw Embree loops
  double coverage = 0, uncertainty = 0, all = 0, cpu_coverage = 0, cpu_uncertainty = 0;
  FieldStats stats, all_stats;
  std::size_t rays = 0, occluded = 0;
  // The uncertainty fields' own steps, timed in an all-fields evaluation of their own (each
  // step's best over the repetitions).
  FieldStats::Phases phases;
};

// Field set options: coverage alone, the uncertainty fields, every field the scene can have (the
// nine with a motion model).
void FieldSets(const Scene& scene, const FieldOptions& options, FieldOptions* coverage_only,
               FieldOptions* with_uncertainty, FieldOptions* all_fields) {
  *coverage_only = *with_uncertainty = *all_fields = options;
  coverage_only->fields = {"coverage"};
  with_uncertainty->fields = {"coverage", "sigma_max", "sigma_mean", "triangulation_angle",
                              "condition"};
  if (scene.study.motion) {
    with_uncertainty->fields.push_back("sigma_max_steady");
    with_uncertainty->fields.push_back("sigma_mean_steady");
  }
  all_fields->fields.clear();
  for (const std::string& f : FieldNames())
    if (scene.study.motion || f.find("steady") == std::string::npos)
      all_fields->fields.push_back(f);
}

// One tile: a recording evaluation gives the exact rays the evaluation casts there (and warms the
// caches); then, `repeat` times and interleaved (drifts in machine load hit all alike), the field
// evaluation, the raw Embree loops over those rays, and the field sets; the best of each added to
// `t`. The tile's rays and fields are dropped before the next tile.
void TimeTile(const Scene& scene, const Rig& rig, const RayCaster& caster, FieldOptions options,
              const std::optional<BlockColumns>& tile, int repeat, BenchTimes& t) {
  options.tile = tile;
  FieldOptions coverage_only, with_uncertainty, all_fields;
  FieldSets(scene, options, &coverage_only, &with_uncertainty, &all_fields);
  options.record_rays = true;
  std::vector<Ray> rays = EvaluateFields(scene, rig, caster, options).recorded_rays;
  options.record_rays = false;
  const double inf = std::numeric_limits<double>::infinity();
  double fields = inf, raw = inf, packet = inf, coverage = inf, uncertainty = inf, all = inf;
  double cpu_coverage = inf, cpu_uncertainty = inf;
  FieldStats::Phases phases{inf, inf, inf, inf};
  FieldOptions timed = all_fields;
  timed.time_phases = true;
  FieldStats stats, all_stats;
  std::size_t occluded = 0;
  for (int r = 0; r < repeat; ++r) {
    stats = EvaluateFields(scene, rig, caster, options).stats;
    fields = std::min(fields, stats.seconds);
    const RawOcclusionResult single = RawEmbreeOcclusion(caster, rays);
    raw = std::min(raw, single.seconds);
    occluded = single.occluded;
    packet = std::min(packet, RawEmbreeOcclusion(caster, rays, RawMode::kPacket).seconds);
    const FieldStats c = EvaluateFields(scene, rig, caster, coverage_only).stats;
    const FieldStats u = EvaluateFields(scene, rig, caster, with_uncertainty).stats;
    all_stats = EvaluateFields(scene, rig, caster, all_fields).stats;
    coverage = std::min(coverage, c.seconds);
    uncertainty = std::min(uncertainty, u.seconds);
    all = std::min(all, all_stats.seconds);
    cpu_coverage = std::min(cpu_coverage, c.cpu_seconds);
    cpu_uncertainty = std::min(cpu_uncertainty, u.cpu_seconds);
    const FieldStats::Phases p = EvaluateFields(scene, rig, caster, timed).stats.phases;
    phases.contributions = std::min(phases.contributions, p.contributions);
    phases.sums = std::min(phases.sums, p.sums);
    phases.eigenvalues = std::min(phases.eigenvalues, p.eigenvalues);
    phases.angles = std::min(phases.angles, p.angles);
  }
  ++t.tiles;
  t.largest_tile_rays = std::max(t.largest_tile_rays, rays.size());
  t.rays += rays.size();
  t.occluded += occluded;
  t.fields += fields, t.raw += raw, t.packet += packet;
  t.coverage += coverage, t.uncertainty += uncertainty, t.all += all;
  t.cpu_coverage += cpu_coverage, t.cpu_uncertainty += cpu_uncertainty;
  t.phases.contributions += phases.contributions, t.phases.sums += phases.sums;
  t.phases.eigenvalues += phases.eigenvalues, t.phases.angles += phases.angles;
  // The statistics of the whole region: the tiles' added (their lists are not needed here).
  stats.sigma_max_mm.clear(), stats.sigma_max_steady_mm.clear();
  all_stats.sigma_max_mm.clear(), all_stats.sigma_max_steady_mm.clear();
  AddFieldStats(&t.stats, stats);
  AddFieldStats(&t.all_stats, all_stats);
  t.uncertainty_fields = with_uncertainty.fields;
  t.all_fields = all_fields.fields;
}

// The whole bench over the tiles of BenchTiles (the largest field set's plan).
BenchTimes TimeTiles(const Scene& scene, const Rig& rig, const RayCaster& caster,
                     const FieldOptions& options, int repeat) {
  FieldOptions coverage_only, with_uncertainty, all_fields;
  FieldSets(scene, options, &coverage_only, &with_uncertainty, &all_fields);
  const VoxelLattice lattice =
      MakeLattice(scene.study.region.box, scene.study.voxel_size,
                  options.voxel_size_option.empty() ? scene.path : options.voxel_size_option,
                  options.voxel_size_option.empty() ? "$.study.voxel_size" : "");
  const std::vector<BlockColumns> tiles =
      BenchTiles(scene, rig, options, all_fields.fields, lattice);
  BenchTimes t;
  for (const BlockColumns& tile : tiles)  // one tile: the whole region, evaluated as before
    TimeTile(scene, rig, caster, options,
             tiles.size() > 1 ? std::optional<BlockColumns>(tile) : std::nullopt, repeat, t);
  return t;
}

// A scene with moving objects asking for every field: its time samples as `pandora analyze`
// evaluates them (what the time summary needs, the first sample in full, the next by difference),
// against one static evaluation of every field (but the per-camera sets) of the scene as placed;
// interleaved, the best of each.
struct TimeSampleTimes {
  std::size_t samples = 0, fields = 0;
  std::string sample_fields;  // what each sample evaluates, comma-separated
  double over_time = std::numeric_limits<double>::infinity();
  double one_static = std::numeric_limits<double>::infinity();
  std::int64_t first_rays = 0, later_rays = 0;  // cast by the first sample and by all the others
  std::int64_t later_blocks = 0, blocks = 0;    // re-derived by the others; of one evaluation
  double first = 0, later = 0;                  // seconds: the first sample, all the others
};

TimeSampleTimes TimeSamples(const Scene& scene, const Rig& rig, const RayCaster& caster,
                            const FieldOptions& options, const std::vector<std::string>& fields,
                            int repeat) {
  TimeSampleTimes t;
  const std::vector<TimeSample> samples = scene.TimeSamples();
  t.samples = samples.size();
  if (samples.empty()) return t;
  const auto parts = MakeSceneParts(scene);
  FieldOptions all = options;
  all.fields = fields;
  // The study's search trees, as `pandora analyze` lends them: the static evaluation and each
  // sample use the kept tree of every solid whose mesh is the scene's (SolidTrees::Object) and
  // build their own for the moved ones.
  all.fields.erase(std::remove(all.fields.begin(), all.fields.end(), "cameras"), all.fields.end());
  t.fields = all.fields.size();
  // What the time summary is made of (coverage and sigma_max per sample): as `pandora analyze`.
  const FieldOptions over_time = OverTimeOptions(all);
  for (const std::string& f : over_time.fields)
    t.sample_fields += (t.sample_fields.empty() ? "" : ",") + f;
  for (int r = 0; r < repeat; ++r) {
    const FieldStats one = EvaluateFields(scene, rig, caster, all).stats;
    t.one_static = std::min(t.one_static, one.seconds);
    t.blocks = one.active_set.blocks;
    double seconds = 0, first = 0;
    t.first_rays = t.later_rays = t.later_blocks = 0;
    EvaluateSamples(scene, rig, *parts, samples, over_time,
                    [&](std::size_t s, const Fields&, const SampleCost& cost) {
                      seconds += cost.seconds;
                      if (s == 0) first = cost.seconds;
                      (s == 0 ? t.first_rays : t.later_rays) += cost.rays;
                      if (s > 0) t.later_blocks += cost.dirty_blocks;
                    });
    if (seconds < t.over_time) t.first = first, t.later = seconds - first;
    t.over_time = std::min(t.over_time, seconds);
  }
  return t;
}

// The uncertainty fields' own steps and the floor they set for all fields / coverage alone (each
// step is vectorised, and the eigenvalues and the best pair are fixed bit for bit:
// docs/performance.md), and the share of camera pairs triangulation_angle tried.
void PrintUncertaintySteps(const BenchTimes& t) {
  const FieldStats::Phases& ph = t.phases;
  std::printf(
      "  uncertainty's own steps (timed in one more all-fields evaluation): contributions %.4f s, "
      "exact sums %.4f s, eigenvalues %.4f s, best pairs %.4f s\n",
      ph.contributions, ph.sums, ph.eigenvalues, ph.angles);
  std::printf(
      "  ratio (coverage alone + those steps) / coverage alone = %.3f (a floor for all fields / "
      "coverage alone; eigenvalues and best pairs alone %.3f)\n",
      1.0 + ph.Total() / t.coverage, 1.0 + (ph.eigenvalues + ph.angles) / t.coverage);
  const FieldStats& all_stats = t.all_stats;
  const std::int64_t two_or_more =
      all_stats.seen_voxels -
      (all_stats.coverage_histogram.size() > 1 ? all_stats.coverage_histogram[1] : 0);
  if (all_stats.angle_pairs_all > 0)
    std::printf(
        "  triangulation_angle: %.1f%% of the (voxel, camera pair) dot products of an all-pairs "
        "search, %.1f pairs per voxel seen twice or more\n",
        100.0 * double(all_stats.angle_pairs_tried) / double(all_stats.angle_pairs_all),
        double(all_stats.angle_pairs_tried) / double(std::max<std::int64_t>(1, two_or_more)));
}

// Prints TimeSamples' measurement (nothing for a static scene).
void PrintTimeSamples(const TimeSampleTimes& times) {
  if (times.samples == 0) return;
  const double later = double(std::max<std::size_t>(1, times.samples - 1));
  std::printf(
      "  %zu time samples, all %zu fields: %.4f s = %.3f x one static evaluation (%.4f s; "
      "target <= 2)\n",
      times.samples, times.fields, times.over_time, times.over_time / times.one_static,
      times.one_static);
  std::printf(
      "    each sample evaluates %s; the first in full %.4f s, the next %.4f s each: %.1f%% of "
      "the first's rays cast again, %.1f%% of the blocks re-derived\n",
      times.sample_fields.c_str(), times.first, times.later / later,
      100.0 * double(times.later_rays) / later /
          double(std::max<std::int64_t>(1, times.first_rays)),
      100.0 * double(times.later_blocks) / later / double(std::max<std::int64_t>(1, times.blocks)));
}

}  // namespace

int RunBench(const BenchArgs& args) {
  if (args.render) return RunRenderBench(args);
  if (args.incremental) return RunIncrementalBench(args);
  const auto study = LoadStudyWithVoxelSize(args.scene, args.voxel_size);
  const Scene& scene = study->scene();
  const Rig& rig = study->FindRig(args.rig, "--rig");
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string json_path = args.json_out.empty() ? "" : output.Stage(args.json_out, "--json");
  const RayCaster* caster = &study->caster();
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

  FieldOptions options;
  options.scene_path = scene.path;
  if (!std::isnan(args.voxel_size)) options.voxel_size_option = "--voxel-size";
  options.fields = {"coverage", "cameras", "resolution"};
  options.memory_budget_bytes = scene.study.memory_budget_bytes;
  if (!std::isnan(args.memory_budget_mb)) {
    CheckMemoryBudget(args.memory_budget_mb, "--memory-budget", "");
    options.memory_budget_bytes = args.memory_budget_mb * 1048576.0;
    options.memory_budget_option = "--memory-budget";
  }
  // The solids' search trees are the study's, built once (in the recording pass) like Embree's
  // BVH and kept: the field time is what each evaluation does.
  options.solid_trees = &study->solid_trees();

  const BenchTimes t = TimeTiles(scene, rig, *caster, options, args.repeat);
  const double best_fields = t.fields, best_raw = t.raw, best_packet = t.packet;
  const FieldStats& stats = t.stats;
  const std::size_t occluded = t.occluded;
  const double best_coverage = t.coverage, best_uncertainty = t.uncertainty;
  const double cpu_coverage = t.cpu_coverage, cpu_uncertainty = t.cpu_uncertainty;
  const FieldStats& all_stats = t.all_stats;
  const std::vector<std::string>& uncertainty_fields = t.uncertainty_fields;
  const std::vector<std::string>& all_field_names = t.all_fields;
  // The time samples evaluate the whole region at once: with the region in one tile only.
  const TimeSampleTimes times =
      t.tiles == 1 ? TimeSamples(scene, rig, *caster, options, all_field_names, args.repeat)
                   : TimeSampleTimes{};
  const double uncertainty_overhead = best_uncertainty / best_coverage - 1.0;
  const double cpu_overhead = cpu_uncertainty / cpu_coverage - 1.0;

  const double ratio = best_raw / best_fields;
  const double packet_ratio = best_packet / best_fields;
  const int width = EmbreePacketWidth(*caster);
  std::printf("pandora bench: %s, rig %s, %zu triangles, voxel %.4g m, %d threads\n",
              scene.path.c_str(), rig.name.c_str(), caster->triangle_count(),
              scene.study.voxel_size, threads);
  std::printf(
      "  region voxels %lld, blocks %lld (culled %lld), point-camera tests %lld, rays %lld "
      "(%zu occluded)\n",
      (long long)stats.active_set.region_voxels, (long long)stats.active_set.blocks,
      (long long)stats.active_set.culled_blocks, (long long)stats.point_camera_tests,
      (long long)stats.rays, occluded);
  std::printf("  %-44s %9.4f s  %8.2f M tests/s  %8.2f M rays/s\n",
              "field evaluation (best of runs)", best_fields,
              stats.point_camera_tests / best_fields / 1e6, stats.rays / best_fields / 1e6);
  std::printf("  %-44s %9.4f s  %8s            %8.2f M rays/s\n",
              "raw Embree rtcOccluded1 loop, same rays", best_raw, "",
              double(t.rays) / best_raw / 1e6);
  const std::string packet_label =
      "raw Embree rtcOccluded" + std::to_string(width) + " packets, same rays";
  std::printf("  %-44s %9.4f s  %8s            %8.2f M rays/s\n", packet_label.c_str(), best_packet,
              "", double(t.rays) / best_packet / 1e6);
  if (t.tiles > 1)
    std::printf(
        "  in %zu tiles of block columns, one at a time (at most %zu rays, %.0f MiB, held at "
        "once; budget %.0f MiB); each tile's best of %d runs, summed\n",
        t.tiles, t.largest_tile_rays,
        double(t.largest_tile_rays) * (sizeof(Ray) + 48.0) / 1048576.0,
        options.memory_budget_bytes / 1048576.0, args.repeat);
  std::printf("  of the field time, active set (region, solids, culling): %.4f s\n",
              stats.active_set_seconds);
  std::printf(
      "  not in it: the solids' search trees, built once per study like the BVH: %d in %.4f s\n",
      study->solid_trees().built(), study->solid_trees().build_seconds());
  std::printf("  ratio raw single-ray time / field time = %.3f (target >= 0.8)\n", ratio);
  std::printf(
      "  ratio raw packet time / field time     = %.3f (target >= 0.8; our overhead over Embree)\n",
      packet_ratio);
  std::printf(
      "  coverage alone %.4f s; with %zu uncertainty fields %.4f s: +%.1f%% (target <= 25%%)\n",
      best_coverage, uncertainty_fields.size() - 1, best_uncertainty, 100.0 * uncertainty_overhead);
  std::printf("  the same in CPU time: %.4f s and %.4f s: +%.1f%% (less disturbed by other load)\n",
              cpu_coverage, cpu_uncertainty, 100.0 * cpu_overhead);
  std::printf(
      "  all %zu fields %.4f s: ratio all fields / coverage alone = %.3f (target <= 1.15)\n",
      all_field_names.size(), t.all, t.all / best_coverage);
  PrintUncertaintySteps(t);
  PrintTimeSamples(times);

  if (!args.json_out.empty()) {
    nlohmann::json j{{"scene", scene.path},
                     {"rig", rig.name},
                     {"triangles", caster->triangle_count()},
                     {"voxel_size_m", scene.study.voxel_size},
                     {"threads", threads},
                     {"repeat", args.repeat},
                     {"region_voxels", stats.active_set.region_voxels},
                     {"point_camera_tests", stats.point_camera_tests},
                     {"rays", stats.rays},
                     {"field_seconds", best_fields},
                     {"raw_embree_seconds", best_raw},
                     {"tests_per_second", stats.point_camera_tests / best_fields},
                     {"field_rays_per_second", stats.rays / best_fields},
                     {"raw_rays_per_second", double(t.rays) / best_raw},
                     {"tiles", t.tiles},
                     {"recorded_rays", t.rays},
                     {"largest_tile_rays", t.largest_tile_rays},
                     {"memory_budget_mib", options.memory_budget_bytes / 1048576.0},
                     {"raw_packet_seconds", best_packet},
                     {"packet_width", width},
                     {"ratio", ratio},
                     {"packet_ratio", packet_ratio},
                     {"solid_trees", study->solid_trees().built()},
                     {"solid_tree_seconds", study->solid_trees().build_seconds()},
                     {"coverage_only_seconds", best_coverage},
                     {"with_uncertainty_seconds", best_uncertainty},
                     {"uncertainty_fields", uncertainty_fields},
                     {"uncertainty_overhead", uncertainty_overhead},
                     {"coverage_only_cpu_seconds", cpu_coverage},
                     {"with_uncertainty_cpu_seconds", cpu_uncertainty},
                     {"contribution_seconds", t.phases.contributions},
                     {"exact_sum_seconds", t.phases.sums},
                     {"eigenvalue_seconds", t.phases.eigenvalues},
                     {"best_pair_seconds", t.phases.angles},
                     {"uncertainty_overhead_cpu", cpu_overhead},
                     {"all_fields", all_field_names},
                     {"all_fields_seconds", t.all},
                     {"all_fields_ratio", t.all / best_coverage},
                     {"angle_pairs_tried", all_stats.angle_pairs_tried},
                     {"angle_pairs_all", all_stats.angle_pairs_all}};
    if (times.samples > 0)
      j["time_samples"] = {{"samples", times.samples},
                           {"seconds", times.over_time},
                           {"static_seconds", times.one_static},
                           {"ratio", times.over_time / times.one_static}};
    WriteFileAtomically(json_path, j.dump(2) + "\n");
    output.Commit();
  }
  return 0;
}

// Registers `pandora bench` and its options (`viewer_flag`: --viewer, which main handles).
Command AddBenchCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<BenchArgs>();
  BenchArgs& bench = *args;
  int& threads = common.threads;
  const CLI::Validator& threads_check = common.threads_check;
  auto viewer_flag_value = std::make_shared<bool>(false);  // main runs pandora-view for it
  bool& viewer_flag = *viewer_flag_value;
  CLI::App* b = app.add_subcommand(
      "bench", "Time field evaluation against a raw Embree loop over the same rays");
  b->add_option("scene", bench.scene, "Scene file (JSON)")->required();
  b->add_option("--rig", bench.rig, "Rig name (default: the first rig)");
  b->add_option("--voxel-size", bench.voxel_size,
                "Voxel size in metres (default: study.voxel_size)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  b->add_option("--repeat", bench.repeat, "Timed repetitions (the best is reported)")
      ->check(Number(1, 1000, "repetitions", true));
  b->add_option("--json", bench.json_out, "Also write the results to this JSON file");
  b->add_option("--memory-budget", bench.memory_budget_mb,
                "Memory budget in MiB (default: study.memory_budget_mb or 4096): the region is "
                "timed in tiles whose fields and recorded rays fit it");
  b->add_flag("--render", bench.render,
              "Time `pandora render` (1280x720) against raw Embree loops over the same primary and "
              "shadow rays");
  b->add_option("--view", bench.view,
                "With --render: the named view (default: the scene's first view)");
  b->add_option("--size", bench.size, "With --render: image size WxH")->capture_default_str();
  b->add_flag("--viewer", viewer_flag,
              "Frame rates of `pandora view` (navigating, all cameras moving) against the exact "
              "CPU renderer");
  b->add_flag("--incremental", bench.incremental,
              "Time the field update after moving one camera against a full evaluation");
  b->add_option("--move", bench.move, "With --incremental: how far each camera moves, metres")
      ->check(Number(0, HUGE_VAL, "metres", false, true))
      ->capture_default_str();
  b->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  return {b, [args, viewer_flag_value] { return RunBench(*args); }};
}

}  // namespace pandora::app
