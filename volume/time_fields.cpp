#include "volume/time_fields.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>

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
  options.value_lists = true;      // the samples' lists are the time summary's parts
  options.spilled_fields.clear();  // the samples' grids are read as they are made
  bool uncertainty = false;
  for (const std::string& f : options.fields)
    uncertainty |= f != "coverage" && f != "cameras" && f != "resolution";
  options.fields = {"coverage"};
  if (uncertainty) options.fields.push_back("sigma_max");
  return options;
}

namespace {

// The parts' layout: counts [voxels, always, good pairs, free pairs, then per sample its free
// region voxels and those seen by >= 1, 2, 3, min_cameras]; lists: per sample, its sigma_max
// values; seconds: per sample.
constexpr std::size_t kTimeCounts = 4, kPerSample = 5;

}  // namespace

SummaryParts TimeFieldsParts(const Scene& scene, const Rig& rig, const RigidPartsRayCaster& parts,
                             const std::vector<TimeSample>& samples, const FieldOptions& options_in,
                             int min_cameras, Fields* grids) {
  SummaryParts out;
  out.counts.assign(kTimeCounts + kPerSample * samples.size(), 0);
  out.lists.resize(samples.size());
  out.seconds.assign(samples.size(), 0.0);
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
  openvdb::math::Transform::Ptr transform;
  std::int64_t& good_pairs = out.counts[2];
  std::int64_t& free_pairs = out.counts[3];
  std::size_t current = 0;  // the sample being evaluated, for the progress
  if (progress)
    options.progress = [&](double f) { progress((double(current) + f) / double(samples.size())); };
  const auto visit = [&](std::size_t s, const Fields& f, const SampleCost& cost) {
    std::int64_t* row = &out.counts[kTimeCounts + kPerSample * s];
    const std::vector<std::int64_t>& hist = f.stats.coverage_histogram;
    const int at_least[4] = {1, 2, 3, min_cameras};
    for (std::size_t j = 0; j < hist.size(); ++j) {
      row[0] += hist[j];
      for (int t = 0; t < 4; ++t) row[1 + t] += j >= std::size_t(at_least[t]) ? hist[j] : 0;
    }
    out.lists[s] = f.stats.sigma_max_mm;
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
    out.seconds[s] = cost.seconds;
    current = s + 1;
  };
  EvaluateSamples(scene, rig, parts, samples, options, visit);
  // The combined grids, active on every voxel free in some sample.
  openvdb::FloatGrid::Ptr min_out = openvdb::FloatGrid::create(0.0f),
                          share_out = openvdb::FloatGrid::create(0.0f);
  auto mo = min_out->getAccessor();
  auto so = share_out->getAccessor();
  for (auto it = free_grid->cbeginValueOn(); it; ++it) {
    const openvdb::Coord c = it.getCoord();
    const int free = *it;
    const int least = min_acc.getValue(c);
    const int good = good_acc.getValue(c);
    mo.setValue(c, float(least));
    so.setValue(c, free > 0 ? float(double(good) / free) : 0.0f);
    ++out.counts[0];
    out.counts[1] += least >= min_cameras;
  }
  if (!grids) return out;
  if (transform) {
    min_out->setTransform(transform);
    share_out->setTransform(transform->copy());
  }
  min_out->setName("coverage_min");
  share_out->setName("coverage_time_share");
  min_out->pruneGrid();
  share_out->pruneGrid();
  grids->impl().extra["coverage_min"] = min_out;
  grids->impl().extra["coverage_time_share"] = share_out;
  return out;
}

TimeSummary FinishTimeFields(const std::vector<TimeSample>& samples, int min_cameras,
                             const std::vector<std::int64_t>& counts,
                             const std::vector<double>& seconds, PercentileSource& lists) {
  if (counts.size() != kTimeCounts + kPerSample * samples.size())
    throw std::invalid_argument("FinishTimeFields: the parts are of other samples");
  TimeSummary out;
  out.min_cameras = min_cameras;
  const auto share = [](std::int64_t part, std::int64_t whole) {
    return whole > 0 ? double(part) / double(whole) : 0.0;
  };
  std::vector<ListTerm> every;
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const std::int64_t* row = &counts[kTimeCounts + kPerSample * s];
    TimeSampleSummary r;
    r.label = samples[s].label;
    r.time = samples[s].time;
    r.region_voxels = row[0];
    r.ge1 = share(row[1], row[0]);
    r.ge2 = share(row[2], row[0]);
    r.ge3 = share(row[3], row[0]);
    r.ge_k = share(row[4], row[0]);
    const ListPercentiles sigma = lists.Percentiles(s, {50, 90});
    if (sigma.count > 0) {
      r.sigma_max_p50 = sigma.values[0];
      r.sigma_max_p90 = sigma.values[1];
    }
    r.seconds = s < seconds.size() ? seconds[s] : 0.0;
    out.samples.push_back(r);
    every.push_back({s, 1});
  }
  out.voxels = counts[0];
  out.always = share(counts[1], counts[0]);
  out.mean = share(counts[2], counts[3]);
  out.worst_sample = 0;
  for (std::size_t s = 1; s < out.samples.size(); ++s)
    if (out.samples[s].ge_k < out.samples[out.worst_sample].ge_k) out.worst_sample = int(s);
  const ListPercentiles all = lists.Percentiles(every, {50, 90, 99});
  if (all.count > 0) {
    out.sigma_max_p50 = all.values[0];
    out.sigma_max_p90 = all.values[1];
    out.sigma_max_p99 = all.values[2];
  }
  return out;
}

TimeFieldsResult EvaluateFieldsOverTime(const Scene& scene, const Rig& rig,
                                        const RigidPartsRayCaster& parts,
                                        const std::vector<TimeSample>& samples,
                                        const FieldOptions& options, int min_cameras) {
  const auto start = std::chrono::steady_clock::now();
  TimeFieldsResult result;
  const SummaryParts p =
      TimeFieldsParts(scene, rig, parts, samples, options, min_cameras, &result.grids);
  InMemoryPercentiles lists(p.lists);
  result.summary = FinishTimeFields(samples, min_cameras, p.counts, p.seconds, lists);
  result.summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void AddTimeGrids(Fields* fields, TimeFieldsResult* result) {
  for (auto& [name, grid] : result->grids.impl().extra) fields->impl().extra[name] = grid;
  result->grids.impl().extra.clear();
}

}  // namespace pandora
