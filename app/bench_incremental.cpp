// `pandora bench --incremental`: how long the fields take to catch up after one camera moves, as a
// ratio to a full evaluation measured in the same run (interleaved, so load drifts hit both).
// Each camera in turn moves sideways by --move metres and back; every move is one
// FieldEvaluator::Update, timed from the edit to fields that equal a full recompute.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/session/study.h"
#include "volume/fields.h"

namespace pandora::app {
namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Each camera of `rig` in turn moved sideways by `move` in its own frame (its x axis), then back:
// `update(edited)` after every move.
template <typename F>
void MoveEachCamera(const Rig& rig, double move, F&& update) {
  Rig edited = rig;
  for (Camera& camera : edited.cameras) {
    const Vec3 side = camera.world_from_camera.linear().col(0);
    for (const double step : {move, -move}) {
      camera.world_from_camera.translation() += step * side;
      update(edited);
    }
  }
}

// The same edits on an evaluator of their own that times the uncertainty fields' own steps (not
// the timed one: its clock reads would weigh on the updates measured): the mean time per update
// in its dirty voxels' eigenvalues and best pairs, computed as a full evaluation computes them.
double FixedStepsPerUpdate(const Scene& scene, const RayCaster& caster, FieldOptions options,
                           const Rig& rig, double move) {
  options.time_phases = true;
  FieldEvaluator evaluator(scene, caster, options);
  evaluator.Update(rig);
  double seconds = 0;
  int count = 0;
  MoveEachCamera(rig, move, [&](const Rig& edited) {
    evaluator.Update(edited);
    const FieldStats::Phases& p = evaluator.fields().stats.phases;
    seconds += p.eigenvalues + p.angles;
    ++count;
  });
  return count > 0 ? seconds / count : 0.0;
}

}  // namespace

int RunIncrementalBench(const BenchArgs& args) {
  const auto study = LoadStudyWithVoxelSize(args.scene, args.voxel_size);
  const Scene& scene = study->scene();
  const Rig& rig = study->FindRig(args.rig, "--rig");
  scene.CheckLength(args.move, "--move", "the distance each camera moves");
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string json_path = args.json_out.empty() ? "" : output.Stage(args.json_out, "--json");
  const RayCaster* caster = &study->caster();
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));

  FieldOptions options;
  options.solid_trees = &study->solid_trees();
  options.scene_path = scene.path;
  if (!std::isnan(args.voxel_size)) options.voxel_size_option = "--voxel-size";
  options.fields = scene.study.fields;  // the study's own workload
  options.memory_budget_bytes = scene.study.memory_budget_bytes;

  // Held optionally so that it goes before FixedStepsPerUpdate builds another (kept state twice).
  std::optional<FieldEvaluator> evaluator(std::in_place, scene, *caster, options);
  const FieldUpdate first = evaluator->Update(rig);
  const int n = static_cast<int>(rig.cameras.size());

  double best_full = std::numeric_limits<double>::infinity();
  double best_full_cpu = std::numeric_limits<double>::infinity();
  std::vector<double> updates, updates_cpu;
  std::int64_t dirty_voxels = 0, update_rays = 0, region_voxels = 0, full_rays = 0;
  for (int r = 0; r < args.repeat; ++r) {
    const std::clock_t cpu0 = std::clock();
    const Fields full = EvaluateFields(scene, rig, *caster, options);
    best_full_cpu = std::min(best_full_cpu, double(std::clock() - cpu0) / CLOCKS_PER_SEC);
    best_full = std::min(best_full, full.stats.seconds);
    region_voxels = full.stats.active_set.region_voxels;
    full_rays = full.stats.rays;
    MoveEachCamera(rig, args.move, [&](const Rig& edited) {
      const std::clock_t u0 = std::clock();
      const FieldUpdate u = evaluator->Update(edited);
      updates_cpu.push_back(double(std::clock() - u0) / CLOCKS_PER_SEC);
      updates.push_back(u.seconds);
      dirty_voxels += u.dirty_voxels;
      update_rays += u.rays;
    });
  }
  const double mean = std::accumulate(updates.begin(), updates.end(), 0.0) / updates.size();
  const double median = Median(updates);
  const double worst = *std::max_element(updates.begin(), updates.end());
  const double mean_cpu =
      std::accumulate(updates_cpu.begin(), updates_cpu.end(), 0.0) / updates_cpu.size();
  const double dirty_share = double(dirty_voxels) / double(updates.size()) / double(region_voxels);
  const double ray_share = double(update_rays) / double(updates.size()) / double(full_rays);
  const double ratio = mean / best_full;
  const double ratio_cpu = mean_cpu / best_full_cpu;
  const double state_mib = evaluator->state_bytes() / 1048576.0;
  evaluator.reset();
  const double fixed_mean = FixedStepsPerUpdate(scene, *caster, options, rig, args.move);

  std::printf(
      "pandora bench --incremental: %s, rig %s (%d cameras), voxel %.4g m, %zu fields, %d "
      "threads\n",
      scene.path.c_str(), rig.name.c_str(), n, scene.study.voxel_size, options.fields.size(),
      threads);
  std::printf("  region voxels %lld, rays of a full evaluation %lld\n", (long long)region_voxels,
              (long long)full_rays);
  std::printf("  %-52s %9.4f s\n", "full evaluation (EvaluateFields, best of runs)", best_full);
  std::printf("  %-52s %9.4f s  (keeps %.1f MiB for updates)\n",
              "first update of the incremental evaluator", first.seconds, state_mib);
  std::printf("  %-52s %9.4f s  median %.4f s, worst %.4f s (%zu updates)\n",
              "update after moving one camera: mean", mean, median, worst, updates.size());
  std::printf(
      "  an update re-casts %.1f%% of a full evaluation's rays and re-derives %.1f%% of its "
      "voxels\n",
      100.0 * ray_share, 100.0 * dirty_share);
  std::printf("  ratio update / full = %.3f wall, %.3f CPU (ideal about 1/%d = %.3f)\n", ratio,
              ratio_cpu, n, 1.0 / n);
  std::printf("  edit-to-updated-fields latency: median %.1f ms, worst %.1f ms\n", 1e3 * median,
              1e3 * worst);
  if (fixed_mean > 0)
    std::printf(
        "  of an update, its dirty voxels' eigenvalues and best pairs: mean %.4f s = %.3f of a "
        "full evaluation (a floor for the ratio while they are computed as in one)\n",
        fixed_mean, fixed_mean / best_full);

  if (!args.json_out.empty()) {
    nlohmann::json j{{"scene", scene.path},
                     {"rig", rig.name},
                     {"cameras", n},
                     {"voxel_size_m", scene.study.voxel_size},
                     {"fields", options.fields},
                     {"threads", threads},
                     {"repeat", args.repeat},
                     {"move_m", args.move},
                     {"region_voxels", region_voxels},
                     {"full_seconds", best_full},
                     {"full_cpu_seconds", best_full_cpu},
                     {"first_update_seconds", first.seconds},
                     {"state_mib", state_mib},
                     {"update_mean_seconds", mean},
                     {"update_median_seconds", median},
                     {"update_worst_seconds", worst},
                     {"update_mean_cpu_seconds", mean_cpu},
                     {"ray_share", ray_share},
                     {"dirty_voxel_share", dirty_share},
                     {"ratio", ratio},
                     {"update_fixed_step_seconds", fixed_mean},
                     {"ratio_cpu", ratio_cpu}};
    WriteFileAtomically(json_path, j.dump(2) + "\n");
    output.Commit();
  }
  return 0;
}

}  // namespace pandora::app
