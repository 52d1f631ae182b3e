#include "volume/time_fields.h"

#include <algorithm>
#include <chrono>
#include <limits>

#include "analysis/geometry/ray_caster.h"
#include "volume/fields_vdb.h"
#include "volume/summary.h"

namespace pandora {

FieldOptions OverTimeOptions(FieldOptions options) {
  options.partition_count = 1;
  options.partition_rank = 0;
  options.fields.erase(std::remove(options.fields.begin(), options.fields.end(), "cameras"),
                       options.fields.end());
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
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const auto t0 = Clock::now();
    const Scene at = SceneAtSample(scene, samples[s]);
    const auto caster = CasterAtSample(parts, scene, samples[s]);
    if (progress)
      options.progress = [&, s](double f) { progress((double(s) + f) / double(samples.size())); };
    const Fields f = EvaluateFields(at, rig, *caster, options);
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
    row.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    out.samples.push_back(row);
  }
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
