// `pandora bench`: field evaluation against a raw Embree occlusion loop over the very same rays,
// measured in the same run, so the ratio is meaningful on a shared, noisy machine.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/session/study.h"
#include "volume/fields.h"
#include "volume/time_fields.h"

namespace pandora::app {

namespace {

// Coverage alone, the uncertainty fields and every field, timed in the same run, interleaved
// (drifts in machine load hit all alike), the best of each.
struct FieldSetTimes {
  std::vector<std::string> uncertainty_fields, all_fields;
  double coverage = std::numeric_limits<double>::infinity();
  double uncertainty = std::numeric_limits<double>::infinity();
  double all = std::numeric_limits<double>::infinity();
  double cpu_coverage = std::numeric_limits<double>::infinity();
  double cpu_uncertainty = std::numeric_limits<double>::infinity();
  FieldStats all_stats;
};

FieldSetTimes TimeFieldSets(const Scene& scene, const Rig& rig, const RayCaster& caster,
                            const FieldOptions& options, int repeat) {
  FieldSetTimes t;
  FieldOptions coverage_only = options;
  coverage_only.fields = {"coverage"};
  FieldOptions with_uncertainty = options;
  with_uncertainty.fields = {"coverage", "sigma_max", "sigma_mean", "triangulation_angle",
                             "condition"};
  if (scene.study.motion) {
    with_uncertainty.fields.push_back("sigma_max_steady");
    with_uncertainty.fields.push_back("sigma_mean_steady");
  }
  // Every field the scene can have (the nine with a motion model).
  FieldOptions all_fields = options;
  all_fields.fields.clear();
  for (const std::string& f : FieldNames())
    if (scene.study.motion || f.find("steady") == std::string::npos) all_fields.fields.push_back(f);
  for (int r = 0; r < repeat; ++r) {
    const FieldStats c = EvaluateFields(scene, rig, caster, coverage_only).stats;
    const FieldStats u = EvaluateFields(scene, rig, caster, with_uncertainty).stats;
    t.all_stats = EvaluateFields(scene, rig, caster, all_fields).stats;
    t.all = std::min(t.all, t.all_stats.seconds);
    t.coverage = std::min(t.coverage, c.seconds);
    t.uncertainty = std::min(t.uncertainty, u.seconds);
    t.cpu_coverage = std::min(t.cpu_coverage, c.cpu_seconds);
    t.cpu_uncertainty = std::min(t.cpu_uncertainty, u.cpu_seconds);
  }
  t.uncertainty_fields = with_uncertainty.fields;
  t.all_fields = all_fields.fields;
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
  // Not the study's search trees: the moved solids differ from them, and every sample's
  // evaluation builds what it needs alike.
  all.solid_trees = nullptr;
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
  // The solids' search trees are the study's, built once (in the recording pass) like Embree's
  // BVH and kept: the field time is what each evaluation does.
  options.solid_trees = &study->solid_trees();

  // One recording pass gives the exact rays the evaluation casts (and warms caches).
  options.record_rays = true;
  Fields recorded = EvaluateFields(scene, rig, *caster, options);
  options.record_rays = false;
  const std::vector<Ray> rays = std::move(recorded.recorded_rays);

  // Interleave the two measurements so drifts in machine load hit both alike; keep the best of
  // each.
  double best_fields = std::numeric_limits<double>::infinity();
  double best_raw = std::numeric_limits<double>::infinity();
  double best_packet = std::numeric_limits<double>::infinity();
  FieldStats stats;
  std::size_t occluded = 0;
  for (int r = 0; r < args.repeat; ++r) {
    const Fields f = EvaluateFields(scene, rig, *caster, options);
    best_fields = std::min(best_fields, f.stats.seconds);
    stats = f.stats;
    const RawOcclusionResult raw = RawEmbreeOcclusion(*caster, rays);
    best_raw = std::min(best_raw, raw.seconds);
    occluded = raw.occluded;
    best_packet =
        std::min(best_packet, RawEmbreeOcclusion(*caster, rays, RawMode::kPacket).seconds);
  }

  const FieldSetTimes sets = TimeFieldSets(scene, rig, *caster, options, args.repeat);
  const double best_coverage = sets.coverage, best_uncertainty = sets.uncertainty;
  const double cpu_coverage = sets.cpu_coverage, cpu_uncertainty = sets.cpu_uncertainty;
  const FieldStats& all_stats = sets.all_stats;
  const std::vector<std::string>& uncertainty_fields = sets.uncertainty_fields;
  const std::vector<std::string>& all_field_names = sets.all_fields;
  const TimeSampleTimes times =
      TimeSamples(scene, rig, *caster, options, all_field_names, args.repeat);
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
              rays.size() / best_raw / 1e6);
  const std::string packet_label =
      "raw Embree rtcOccluded" + std::to_string(width) + " packets, same rays";
  std::printf("  %-44s %9.4f s  %8s            %8.2f M rays/s\n", packet_label.c_str(), best_packet,
              "", rays.size() / best_packet / 1e6);
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
      all_field_names.size(), sets.all, sets.all / best_coverage);
  const std::int64_t two_or_more =
      all_stats.seen_voxels -
      (all_stats.coverage_histogram.size() > 1 ? all_stats.coverage_histogram[1] : 0);
  if (all_stats.angle_pairs_all > 0)
    std::printf(
        "  triangulation_angle: %.1f%% of the (voxel, camera pair) dot products of an all-pairs "
        "search, %.1f pairs per voxel seen twice or more\n",
        100.0 * double(all_stats.angle_pairs_tried) / double(all_stats.angle_pairs_all),
        double(all_stats.angle_pairs_tried) / double(std::max<std::int64_t>(1, two_or_more)));
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
                     {"raw_rays_per_second", rays.size() / best_raw},
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
                     {"uncertainty_overhead_cpu", cpu_overhead},
                     {"all_fields", all_field_names},
                     {"all_fields_seconds", sets.all},
                     {"all_fields_ratio", sets.all / best_coverage},
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
