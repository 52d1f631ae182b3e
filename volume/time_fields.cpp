#include "volume/time_fields.h"

#include <algorithm>
#include <chrono>
#include <limits>

#include "analysis/geometry/ray_caster.h"
#include "analysis/util/error.h"
#include "volume/fields_vdb.h"
#include "volume/summary.h"

namespace pandora {

SceneChange MovedBounds(const Scene& before, const Scene& after) {
  SceneChange out;
  const std::size_t n = std::min(before.objects.size(), after.objects.size());
  for (std::size_t o = 0; o < n; ++o) {
    const TriangleMesh& a = before.objects[o].mesh;
    const TriangleMesh& b = after.objects[o].mesh;
    if (a.vertices == b.vertices && a.triangles == b.triangles) continue;
    out.before.push_back(a.Bounds());
    out.after.push_back(b.Bounds());
  }
  for (std::size_t o = n; o < before.objects.size(); ++o)
    out.before.push_back(before.objects[o].mesh.Bounds());
  for (std::size_t o = n; o < after.objects.size(); ++o)
    out.after.push_back(after.objects[o].mesh.Bounds());
  return out;
}

void EvaluateSamples(
    const Scene& scene, const Rig& rig, const RigidPartsRayCaster& parts,
    const std::vector<TimeSample>& samples, const FieldOptions& options,
    const std::function<void(std::size_t, const Fields&, const SampleCost&)>& visit) {
  using Clock = std::chrono::steady_clock;
  // The evaluator keeps the previous sample's scene and caster until the next one replaces them.
  std::unique_ptr<Scene> previous;
  std::unique_ptr<RayCaster> previous_caster;
  std::unique_ptr<FieldEvaluator> evaluator;
  bool keep = true;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const auto t0 = Clock::now();
    auto at = std::make_unique<Scene>(SceneAtSample(scene, samples[s]));
    std::unique_ptr<RayCaster> caster = CasterAtSample(parts, scene, samples[s]);
    SampleCost cost;
    if (!evaluator || !keep) {
      cost.full = true;
      // Kept state when it fits the budget (an InputError from the first update), else none.
      for (;;) {
        evaluator = std::make_unique<FieldEvaluator>(*at, *caster, options, keep);
        try {
          const FieldUpdate u = evaluator->Update(rig);
          cost.dirty_blocks = u.dirty_blocks;
          cost.rays = u.rays;
          break;
        } catch (const InputError&) {
          if (!keep) throw;
          keep = false;
        }
      }
    } else {
      const FieldUpdate u = evaluator->UpdateScene(*at, *caster, MovedBounds(*previous, *at));
      cost.full = u.full;
      cost.dirty_blocks = u.dirty_blocks;
      cost.rays = u.rays;
    }
    previous = std::move(at);
    previous_caster = std::move(caster);
    cost.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    visit(s, evaluator->fields(), cost);
    if (options.cancel && options.cancel->load()) return;  // the caller drops what it has
  }
}

FieldOptions OverTimeOptions(FieldOptions options) {
  options.partition_count = 1;
  options.partition_rank = 0;
  bool uncertainty = false;
  for (const std::string& f : options.fields)
    uncertainty |= f != "coverage" && f != "cameras" && f != "resolution";
  options.fields = {"coverage"};
  if (uncertainty) options.fields.push_back("sigma_max");
  return options;
}

TimeFieldsResult EvaluateFieldsOverTime(const Scene& scene, const Rig& rig,
                                        const RigidPartsRayCaster& parts,
                                        const std::vector<TimeSample>& samples,
                                        const FieldOptions& options_in, int min_cameras) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  TimeFieldsResult result;
  TimeSummary& out = result.summary;
  out.min_cameras = min_cameras;
  FieldOptions options = options_in;
  if (std::find(options.fields.begin(), options.fields.end(), "coverage") == options.fields.end())
    options.fields.insert(options.fields.begin(), "coverage");
  const std::function<void(double)> progress = options.progress;
  openvdb::Int32Grid::Ptr min_grid = openvdb::Int32Grid::create(std::numeric_limits<int>::max());
  openvdb::Int32Grid::Ptr free_grid = openvdb::Int32Grid::create(0),
                          good_grid = openvdb::Int32Grid::create(0);
  auto min_acc = min_grid->getAccessor();
  auto free_acc = free_grid->getAccessor();
  auto good_acc = good_grid->getAccessor();
  std::vector<float> sigma_all;
  openvdb::math::Transform::Ptr transform;
  std::int64_t good_pairs = 0, free_pairs = 0;
  std::size_t current = 0;  // the sample being evaluated, for the progress
  if (progress)
    options.progress = [&](double f) { progress((double(current) + f) / double(samples.size())); };
  const auto visit = [&](std::size_t s, const Fields& f, const SampleCost& cost) {
    TimeSampleSummary row;
    row.label = samples[s].label;
    row.time = samples[s].time;
    const std::vector<std::int64_t>& hist = f.stats.coverage_histogram;
    std::int64_t total = 0;
    for (std::int64_t v : hist) total += v;
    row.region_voxels = total;
    auto share = [&](int k) {
      std::int64_t n = 0;
      for (std::size_t j = std::size_t(k); j < hist.size(); ++j) n += hist[j];
      return total > 0 ? double(n) / double(total) : 0.0;
    };
    row.ge1 = share(1);
    row.ge2 = share(2);
    row.ge3 = share(3);
    row.ge_k = share(min_cameras);
    if (!f.stats.sigma_max_mm.empty()) {
      row.sigma_max_p50 = NearestRankPercentile(f.stats.sigma_max_mm, 50);
      row.sigma_max_p90 = NearestRankPercentile(f.stats.sigma_max_mm, 90);
      sigma_all.insert(sigma_all.end(), f.stats.sigma_max_mm.begin(), f.stats.sigma_max_mm.end());
    }
    // Per voxel: the fewest cameras, the free samples and those with >= k (tiles voxel by voxel).
    const openvdb::Int32Grid::Ptr& coverage = f.impl().coverage;
    if (coverage) {
      if (!transform) transform = coverage->transformPtr()->copy();
      ForEachActiveVoxel(*coverage, [&](const openvdb::Coord& c, int value) {
        if (value < min_acc.getValue(c))
          min_acc.setValue(c, value);
        else
          min_acc.setValueOn(c);
        free_acc.setValue(c, free_acc.getValue(c) + 1);
        if (value >= min_cameras) good_acc.setValue(c, good_acc.getValue(c) + 1);
        ++free_pairs;
        good_pairs += value >= min_cameras;
      });
    }
    row.seconds = cost.seconds;
    out.samples.push_back(row);
    current = s + 1;
  };
  EvaluateSamples(scene, rig, parts, samples, options, visit);
  // The combined grids, active on every voxel free in some sample.
  openvdb::FloatGrid::Ptr min_out = openvdb::FloatGrid::create(0.0f),
                          share_out = openvdb::FloatGrid::create(0.0f);
  auto mo = min_out->getAccessor();
  auto so = share_out->getAccessor();
  std::int64_t voxels = 0, always = 0;
  for (auto it = free_grid->cbeginValueOn(); it; ++it) {
    const openvdb::Coord c = it.getCoord();
    const int free = *it;
    const int least = min_acc.getValue(c);
    const int good = good_acc.getValue(c);
    mo.setValue(c, float(least));
    so.setValue(c, free > 0 ? float(double(good) / free) : 0.0f);
    ++voxels;
    always += least >= min_cameras;
  }
  if (transform) {
    min_out->setTransform(transform);
    share_out->setTransform(transform->copy());
  }
  min_out->setName("coverage_min");
  share_out->setName("coverage_time_share");
  min_out->pruneGrid();
  share_out->pruneGrid();
  result.grids.impl().extra["coverage_min"] = min_out;
  result.grids.impl().extra["coverage_time_share"] = share_out;
  out.voxels = voxels;
  out.always = voxels > 0 ? double(always) / double(voxels) : 0.0;
  out.mean = free_pairs > 0 ? double(good_pairs) / double(free_pairs) : 0.0;
  out.worst_sample = 0;
  for (std::size_t s = 1; s < out.samples.size(); ++s)
    if (out.samples[s].ge_k < out.samples[out.worst_sample].ge_k) out.worst_sample = int(s);
  if (!sigma_all.empty()) {
    out.sigma_max_p50 = NearestRankPercentile(sigma_all, 50);
    out.sigma_max_p90 = NearestRankPercentile(sigma_all, 90);
    out.sigma_max_p99 = NearestRankPercentile(sigma_all, 99);
  }
  out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

void AddTimeGrids(Fields* fields, TimeFieldsResult* result) {
  for (auto& [name, grid] : result->grids.impl().extra) fields->impl().extra[name] = grid;
  result->grids.impl().extra.clear();
}

}  // namespace pandora
