#include "volume/robustness.h"

#include <openvdb/openvdb.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <stdexcept>

#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/text.h"
#include "volume/fields_vdb.h"
#include "volume/information_sum.h"
#include "volume/summary.h"

namespace pandora {
namespace {

using namespace information;

constexpr int kWords = 8;  // 512 voxels of a leaf as bits
using Bits = std::array<std::uint64_t, kWords>;

double Fraction(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

// The coverage thresholds of a row: >= 1, 2, 3 and k.
struct Thresholds {
  std::array<int, 4> j;
};

// What one thread gathers over its leaves.
struct Partial {
  std::array<std::int64_t, 4> at_least{};  // intact voxels seen by >= j[t] cameras
  // Per rig camera: voxels it sees with exactly j[t] cameras (they drop below j[t] when it fails).
  std::vector<std::array<std::int64_t, 4>> exactly;
  std::vector<std::int64_t> seen;
  // Per rig camera: the intact sigma_max (mm) of the voxels it sees that are triangulable intact
  // (removed when it fails) and sigma_max where they are after it fails (added).
  std::vector<std::vector<float>> removed;
  std::vector<std::vector<float>> added;
  explicit Partial(std::size_t cameras)
      : exactly(cameras), seen(cameras, 0), removed(cameras), added(cameras) {}
};

}  // namespace

bool HasCameraSets(const Fields& fields) { return !fields.impl().visible.empty(); }

std::vector<int> CriticalityTable::MostCritical() const {
  std::vector<int> order(rows.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    const CriticalityRow& x = rows[a];
    const CriticalityRow& y = rows[b];
    if (x.ge_k != y.ge_k) return x.ge_k < y.ge_k;
    const double tx = x.triangulable.value_or(0), ty = y.triangulable.value_or(0);
    if (tx != ty) return tx < ty;
    const double px = x.sigma_max_p90_mm.value_or(0), py = y.sigma_max_p90_mm.value_or(0);
    return px > py;
  });
  return order;
}

namespace {

// The leaves seen by some enabled camera, ascending.
std::vector<openvdb::Coord> SeenLeafOrigins(const Rig& rig, const Fields::Impl& g) {
  const std::size_t camera_count = rig.cameras.size();
  std::vector<openvdb::Coord> origins;
  for (std::size_t c = 0; c < camera_count; ++c) {
    if (!rig.cameras[c].enabled || !g.visible[c]) continue;
    for (auto it = g.visible[c]->tree().cbeginLeaf(); it; ++it) origins.push_back(it->origin());
  }
  std::sort(origins.begin(), origins.end());
  origins.erase(std::unique(origins.begin(), origins.end()), origins.end());
  return origins;
}

// Where each leaf's triangulable voxels start among all of `origins`' (base[i], leaf by leaf, base
// of size origins + 1); refuses a sigma_max field outside the camera sets.
std::vector<std::int64_t> IntactSigmaBase(const openvdb::FloatGrid& sigma_grid,
                                          const std::vector<openvdb::Coord>& origins) {
  std::vector<std::int64_t> base(origins.size() + 1, 0);
  for (std::size_t i = 0; i < origins.size(); ++i) {
    const auto* leaf = sigma_grid.tree().probeConstLeaf(origins[i]);
    base[i + 1] = base[i] + (leaf ? static_cast<std::int64_t>(leaf->onVoxelCount()) : 0);
  }
  // sigma_max is active only where >= 2 cameras see a voxel, so inside these leaves.
  if (base.back() != static_cast<std::int64_t>(sigma_grid.activeVoxelCount()))
    throw std::invalid_argument(
        "ComputeCriticality: the sigma_max field does not match the camera sets");
  return base;
}

// What every leaf's work reads (the rig, its fields, the thresholds, the prepared cameras) and
// where it puts the intact sigma_max values.
struct CriticalityInputs {
  const Rig& rig;
  const Fields& fields;
  const Fields::Impl& g;
  Thresholds th;
  bool uncertainty;
  const openvdb::FloatGrid* sigma_grid;
  const VisibilityTester* tester;
  const std::vector<std::array<double, 9>>& whitened;
  const std::array<BandScale, 64>& scales;
  const std::vector<std::int64_t>& base;
  std::vector<float>& intact;
};

// One thread's work over its leaves: its scratch buffers and the steps on each leaf.
struct LeafWorker {
  const CriticalityInputs& in;
  Partial& part;
  std::vector<std::int32_t> cams;
  std::vector<Bits> bits;
  std::array<std::int32_t, 512> count{};
  std::vector<double> contribution;  // 6 per camera of a voxel
  std::vector<std::uint8_t> band;
  std::vector<std::array<double, 6>> upper_rows;
  std::vector<std::int32_t> failed, seeing;
  std::vector<Int128> fixed;
  std::array<std::vector<double>, 6> upper;
  std::array<std::vector<double>, 3> eigen;
  std::array<std::vector<double>, kStatRows> stats;
  std::vector<unsigned char> converged;

  LeafWorker(const CriticalityInputs& inputs, Partial& partial) : in(inputs), part(partial) {}
  void Leaf(std::size_t i, const openvdb::Coord& origin);
  void GatherCameras(const openvdb::Coord& origin);
  void CountCoverage();
  void Uncertainty(std::size_t i, const openvdb::Coord& origin);
  void Contributions(int o, const openvdb::Coord& origin);
  void WithoutEachCamera();
  void FailedStatistics();
};

// Adds leaf i (at `origin`) to the thread's partial sums.
void LeafWorker::Leaf(std::size_t i, const openvdb::Coord& origin) {
  GatherCameras(origin);
  if (cams.empty()) return;
  CountCoverage();
  if (!in.uncertainty) return;
  Uncertainty(i, origin);
}

// The enabled cameras that see part of the leaf (ascending) and the voxels each sees.
void LeafWorker::GatherCameras(const openvdb::Coord& origin) {
  const Rig& rig = in.rig;
  const Fields::Impl& g = in.g;
  const std::size_t camera_count = rig.cameras.size();
  cams.clear();
  bits.clear();
  for (std::size_t c = 0; c < camera_count; ++c) {
    if (!rig.cameras[c].enabled || !g.visible[c]) continue;
    const auto* leaf = g.visible[c]->tree().probeConstLeaf(origin);
    if (!leaf) continue;
    Bits b{};
    bool any = false;
    for (auto it = leaf->cbeginValueOn(); it; ++it)
      if (*it) {
        const int o = static_cast<int>(it.pos());
        b[o >> 6] |= std::uint64_t{1} << (o & 63);
        any = true;
      }
    if (!any) continue;
    cams.push_back(static_cast<std::int32_t>(c));
    bits.push_back(b);
  }
}

// The leaf's coverage counts: voxels seen by >= j[t] cameras, and per camera the voxels it sees
// with exactly j[t].
void LeafWorker::CountCoverage() {
  const Thresholds& th = in.th;
  const std::size_t n_cams = cams.size();
  count.fill(0);
  for (const Bits& b : bits)
    for (int w = 0; w < kWords; ++w)
      for (std::uint64_t x = b[w]; x; x &= x - 1) ++count[64 * w + __builtin_ctzll(x)];
  for (int o = 0; o < 512; ++o)
    for (int t = 0; t < 4; ++t) part.at_least[t] += count[o] >= th.j[t] ? 1 : 0;
  for (std::size_t e = 0; e < n_cams; ++e) {
    auto& ex = part.exactly[cams[e]];
    for (int w = 0; w < kWords; ++w)
      for (std::uint64_t x = bits[e][w]; x; x &= x - 1) {
        const int o = 64 * w + __builtin_ctzll(x);
        ++part.seen[cams[e]];
        for (int t = 0; t < 4; ++t) ex[t] += count[o] == th.j[t] ? 1 : 0;
      }
  }
}

// The leaf's uncertainty: the intact sigma_max values, the voxels each camera's failure removes,
// and the sigma_max after each failure where >= 3 cameras see a voxel.
void LeafWorker::Uncertainty(std::size_t i, const openvdb::Coord& origin) {
  const std::size_t n_cams = cams.size();
  // The uncertainty: at every voxel, the intact sigma_max leaves with each camera that sees it;
  // where >= 3 see it, the information without each of them is re-derived.
  const auto* sigma_leaf = in.sigma_grid->tree().probeConstLeaf(origin);
  upper_rows.clear();
  failed.clear();
  std::int64_t index = in.base[i];
  for (int o = 0; o < 512; ++o) {
    if (sigma_leaf && sigma_leaf->isValueOn(o)) {  // triangulable intact
      const float sigma = sigma_leaf->getValue(o);
      in.intact[static_cast<std::size_t>(index)] = sigma;
      for (std::size_t e = 0; e < n_cams; ++e)
        if (bits[e][o >> 6] >> (o & 63) & 1) part.removed[cams[e]].push_back(sigma);
      ++index;
    }
    if (count[o] < 3) continue;
    Contributions(o, origin);
    WithoutEachCamera();
  }
  FailedStatistics();
}

// The information contributions of the cameras that see voxel `o`, with their bands.
void LeafWorker::Contributions(int o, const openvdb::Coord& origin) {
  const std::size_t n_cams = cams.size();
  // The seeing cameras' contributions, ascending camera (the evaluator's view order).
  const int x = origin.x() + (o >> 6), y = origin.y() + ((o >> 3) & 7), z = origin.z() + (o & 7);
  const Vec3 p = in.fields.lattice.Center(x, y, z);
  contribution.clear();
  band.clear();
  seeing.clear();
  for (std::size_t e = 0; e < n_cams; ++e) {
    if (!(bits[e][o >> 6] >> (o & 63) & 1)) continue;
    Ray segment;
    Mat23 jacobian;
    if (in.tester->TestGeometryCameraFrame(cams[e], p, nullptr, &segment, &jacobian) !=
        ViewResult::kSeen)
      throw std::invalid_argument("ComputeCriticality: the fields were evaluated for another rig");
    double c6[6] = {0, 0, 0, 0, 0, 0};
    AddCameraInformation(jacobian, in.whitened[cams[e]].data(), c6);
    contribution.insert(contribution.end(), c6, c6 + 6);
    band.push_back(Band(c6));
    seeing.push_back(cams[e]);
  }
}

// Per seeing camera, the voxel's information without it (as Derive sums it) into upper_rows.
void LeafWorker::WithoutEachCamera() {
  const std::array<BandScale, 64>& scales = in.scales;
  const int m = static_cast<int>(seeing.size());
  // The whole set's band and how many contributions lie in it, and its exact sum there.
  std::uint8_t top = 0;
  int top_count = 0;
  for (int a = 0; a < m; ++a) {
    if (band[a] > top) {
      top = band[a];
      top_count = 1;
    } else if (band[a] == top) {
      ++top_count;
    }
  }
  Sum6 full{};
  const bool full_exact = top != kNotExact && m - 1 <= kMaxExactCameras;
  if (full_exact) {
    fixed.resize(6 * m);
    for (int a = 0; a < m; ++a)
      for (int q = 0; q < 6; ++q) {
        fixed[6 * a + q] = ToFixed(contribution[6 * a + q], scales[top].q);
        full.v[q] += fixed[6 * a + q];
      }
  }
  for (int f = 0; f < m; ++f) {
    std::array<double, 6> row;
    if (full_exact && (band[f] < top || top_count > 1)) {
      // The others' band is still `top`: the exact sum less f's rounded contribution.
      for (int q = 0; q < 6; ++q)
        row[q] = ToDouble(full.v[q] - fixed[6 * f + q]) * scales[top].up[0] * scales[top].up[1];
    } else {
      // As Derive re-sums a voxel: the others' largest band, or in double in rig order.
      std::uint8_t b = 0;
      for (int a = 0; a < m; ++a)
        if (a != f) b = std::max(b, band[a]);
      if (b == kNotExact || m - 1 > kMaxExactCameras) {
        row.fill(0.0);
        for (int a = 0; a < m; ++a)
          if (a != f)
            for (int q = 0; q < 6; ++q) row[q] += contribution[6 * a + q];
      } else {
        Sum6 s{};
        for (int a = 0; a < m; ++a)
          if (a != f) Accumulate(s, &contribution[6 * a], scales[b], true);
        for (int q = 0; q < 6; ++q) row[q] = ToDouble(s.v[q]) * scales[b].up[0] * scales[b].up[1];
      }
    }
    upper_rows.push_back(row);
    failed.push_back(seeing[f]);
  }
}

// The sigma_max of every row of upper_rows, added to its failed camera's list where observable.
void LeafWorker::FailedStatistics() {
  const std::size_t n = upper_rows.size();
  if (n == 0) return;
  for (int q = 0; q < 6; ++q) {
    upper[q].resize(n);
    for (std::size_t r = 0; r < n; ++r) upper[q][r] = upper_rows[r][q];
  }
  for (auto& v : eigen) v.resize(n);
  for (auto& v : stats) v.resize(n);
  converged.resize(n);
  const double* upper_ptr[6];
  for (int q = 0; q < 6; ++q) upper_ptr[q] = upper[q].data();
  double* eigen_ptr[3] = {eigen[0].data(), eigen[1].data(), eigen[2].data()};
  double* stats_ptr[kStatRows];
  for (int r = 0; r < kStatRows; ++r) stats_ptr[r] = stats[r].data();
  SymmetricEigenvalues3(upper_ptr, eigen_ptr, converged.data(), n);
  StaticStatistics(static_cast<int>(n), eigen_ptr, stats_ptr);
  for (std::size_t r = 0; r < n; ++r)
    if (stats[kObservable][r] != 0.0)
      part.added[failed[r]].push_back(static_cast<float>(stats[kSigmaMaxMm][r]));
}

// The threads' partial sums joined (in a Partial of the totals).
Partial JoinPartials(tbb::enumerable_thread_specific<Partial>& partials, std::size_t camera_count) {
  Partial total(camera_count);
  std::array<std::int64_t, 4>& at_least = total.at_least;
  std::vector<std::array<std::int64_t, 4>>& exactly = total.exactly;
  std::vector<std::int64_t>& seen = total.seen;
  std::vector<std::vector<float>>& removed = total.removed;
  std::vector<std::vector<float>>& added = total.added;
  for (Partial& p : partials) {
    for (int t = 0; t < 4; ++t) at_least[t] += p.at_least[t];
    for (std::size_t c = 0; c < camera_count; ++c) {
      for (int t = 0; t < 4; ++t) exactly[c][t] += p.exactly[c][t];
      seen[c] += p.seen[c];
    }
  }
  // The per-camera lists hold about 8 bytes per (triangulable voxel, camera that sees it): joined
  // camera by camera, each thread's part freed as soon as it is copied, so that they are never
  // held twice (a camera's list at most).
  for (std::size_t c = 0; c < camera_count; ++c) {
    std::size_t n_removed = 0, n_added = 0;
    for (const Partial& p : partials)
      n_removed += p.removed[c].size(), n_added += p.added[c].size();
    removed[c].reserve(n_removed);
    added[c].reserve(n_added);
    for (Partial& p : partials) {
      removed[c].insert(removed[c].end(), p.removed[c].begin(), p.removed[c].end());
      added[c].insert(added[c].end(), p.added[c].begin(), p.added[c].end());
      std::vector<float>().swap(p.removed[c]);
      std::vector<float>().swap(p.added[c]);
    }
  }
  return total;
}

}  // namespace

// The parts' layout: counts [has sigma_max, >= 1, 2, 3, k cameras, then per camera its exactly
// 1, 2, 3, k and seen]; lists [intact sigma_max, per camera removed, per camera added].
constexpr std::size_t kCountsBefore = 5, kPerCamera = 5;

namespace {

// What every part of one criticality computation shares: the checked inputs, the leaves seen by
// some enabled camera, and (with sigma_max) where each leaf's triangulable voxels start and the
// cameras prepared as the field evaluation prepares its rig (FieldEvaluator::State::Prepare): the
// Jacobian in the camera frame and the whitened rotation.
struct CriticalitySetup {
  const Rig& rig;
  const Fields& fields;
  const Fields::Impl& g;
  Thresholds th;
  openvdb::FloatGrid::Ptr sigma_grid;
  std::vector<openvdb::Coord> origins;
  std::vector<std::int64_t> base;  // IntactSigmaBase (with sigma_max)
  std::unique_ptr<VisibilityTester> tester;
  std::vector<std::array<double, 9>> whitened;

  CriticalitySetup(const Scene& scene, const Rig& r, const Fields& f, const RayCaster& caster,
                   int k)
      : rig(r), fields(f), g(f.impl()), th{{1, 2, 3, k}} {
    if (!HasCameraSets(fields))
      throw std::invalid_argument("ComputeCriticality: the fields hold no per-camera sets");
    if (g.visible.size() != rig.cameras.size())
      throw std::invalid_argument("ComputeCriticality: the fields were evaluated for another rig");
    if (k < 1) throw std::invalid_argument("ComputeCriticality: k must be at least 1");
    sigma_grid = g.Load("sigma_max");
    origins = SeenLeafOrigins(rig, g);
    const std::size_t camera_count = rig.cameras.size();
    whitened.resize(camera_count);
    if (!sigma_grid) return;
    base = IntactSigmaBase(*sigma_grid, origins);
    tester =
        std::make_unique<VisibilityTester>(rig.cameras, caster, scene.ContentBounds().diagonal());
    for (std::size_t c = 0; c < camera_count; ++c) {
      const Camera& cam = rig.cameras[c];
      const double sigma = cam.pixel_sigma > 0 ? cam.pixel_sigma : scene.study.pixel_sigma;
      WhitenedRotation(tester->camera_rotation(int(c)), sigma, whitened[c].data());
    }
  }
};

// The parts of the leaves origins[begin, end) of `setup`.
SummaryParts PartsOfLeaves(const CriticalitySetup& setup, std::size_t begin, std::size_t end) {
  const Rig& rig = setup.rig;
  const std::size_t camera_count = rig.cameras.size();
  const bool uncertainty = setup.sigma_grid != nullptr;
  const std::vector<openvdb::Coord> origins(setup.origins.begin() + std::ptrdiff_t(begin),
                                            setup.origins.begin() + std::ptrdiff_t(end));
  const std::array<BandScale, 64>& scales = BandScales();
  // Every triangulable voxel's sigma_max, leaf by leaf in `origins` order (ascending offset within
  // a leaf): base[i] is where leaf i's values start.
  std::vector<std::int64_t> base(origins.size() + 1, 0);
  std::vector<float> intact;
  if (uncertainty) {
    for (std::size_t i = 0; i < base.size(); ++i)
      base[i] = setup.base[begin + i] - setup.base[begin];
    intact.resize(static_cast<std::size_t>(base.back()));
  }

  const CriticalityInputs in{rig,
                             setup.fields,
                             setup.g,
                             setup.th,
                             uncertainty,
                             setup.sigma_grid.get(),
                             setup.tester.get(),
                             setup.whitened,
                             scales,
                             base,
                             intact};
  tbb::enumerable_thread_specific<Partial> partials([&] { return Partial(camera_count); });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, origins.size(), 4), [&](const auto& range) {
    LeafWorker worker(in, partials.local());
    for (std::size_t i = range.begin(); i != range.end(); ++i) worker.Leaf(i, origins[i]);
  });

  Partial total = JoinPartials(partials, camera_count);
  SummaryParts out;
  out.counts.reserve(kCountsBefore + kPerCamera * camera_count);
  out.counts.push_back(uncertainty ? 1 : 0);
  for (int t = 0; t < 4; ++t) out.counts.push_back(total.at_least[t]);
  for (std::size_t c = 0; c < camera_count; ++c) {
    for (int t = 0; t < 4; ++t) out.counts.push_back(total.exactly[c][t]);
    out.counts.push_back(total.seen[c]);
  }
  out.lists.resize(1 + 2 * camera_count);
  out.lists[0] = std::move(intact);
  for (std::size_t c = 0; c < camera_count; ++c) {
    out.lists[1 + c] = std::move(total.removed[c]);
    out.lists[1 + camera_count + c] = std::move(total.added[c]);
  }
  return out;
}

// The (voxel, enabled camera) pairs of each leaf of `setup`: what its lists hold, 8 bytes each.
std::vector<std::int64_t> PairsPerLeaf(const CriticalitySetup& setup) {
  std::vector<std::int64_t> pairs(setup.origins.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs.size(), 64), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i)
      for (std::size_t c = 0; c < setup.rig.cameras.size(); ++c) {
        if (!setup.rig.cameras[c].enabled || !setup.g.visible[c]) continue;
        if (const auto* leaf = setup.g.visible[c]->tree().probeConstLeaf(setup.origins[i]))
          pairs[i] += static_cast<std::int64_t>(leaf->onVoxelCount());
      }
  });
  return pairs;
}

// The parts of `setup`'s leaves, each part's lists at most about `part_bytes` (by `pairs`), added
// to `into` one after the other.
void AddPartsOfLeaves(const CriticalitySetup& setup, const std::vector<std::int64_t>& pairs,
                      double part_bytes, SpilledParts& into) {
  const std::size_t leaves = setup.origins.size();
  for (std::size_t begin = 0, end = 0; begin < leaves; begin = end) {
    double bytes = 0;
    while (end < leaves && (end == begin || bytes + 8.0 * double(pairs[end]) <= part_bytes))
      bytes += 8.0 * double(pairs[end++]);
    into.Add(PartsOfLeaves(setup, begin, end));
  }
}

}  // namespace

void AddCriticalityParts(const Scene& scene, const Rig& rig, const Fields& fields,
                         const RayCaster& caster, int k, SpilledParts& into, double part_bytes) {
  const auto t0 = std::chrono::steady_clock::now();
  const CriticalitySetup setup(scene, rig, fields, caster, k);
  const std::vector<std::int64_t> pairs =
      setup.sigma_grid ? PairsPerLeaf(setup) : std::vector<std::int64_t>(setup.origins.size(), 0);
  AddPartsOfLeaves(setup, pairs, part_bytes, into);
  // The time it took, as a part of its own (timings add up over tiles and processes).
  SummaryParts timing;
  timing.seconds = {std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
  into.Add(std::move(timing));
}

SummaryParts CriticalityParts(const Scene& scene, const Rig& rig, const Fields& fields,
                              const RayCaster& caster, int k) {
  const CriticalitySetup setup(scene, rig, fields, caster, k);
  return PartsOfLeaves(setup, 0, setup.origins.size());
}

CriticalityTable FinishCriticality(const Rig& rig, int k, std::int64_t region_voxels,
                                   const std::vector<std::int64_t>& counts,
                                   PercentileSource& lists) {
  const std::size_t camera_count = rig.cameras.size();
  if (counts.size() != kCountsBefore + kPerCamera * camera_count)
    throw std::invalid_argument("FinishCriticality: the parts are of another rig");
  CriticalityTable table;
  table.k = k;
  table.region_voxels = region_voxels;
  table.uncertainty = counts[0] > 0;
  const std::int64_t region = region_voxels;
  const std::int64_t* at_least = &counts[1];
  table.ge_k = Fraction(at_least[3], region);
  for (std::size_t c = 0; c < camera_count; ++c) {
    if (!rig.cameras[c].enabled) continue;
    const std::int64_t* exactly = &counts[kCountsBefore + kPerCamera * c];
    CriticalityRow row;
    row.camera = static_cast<int>(c);
    row.id = rig.cameras[c].id;
    row.seen_voxels = exactly[4];
    row.ge1 = Fraction(at_least[0] - exactly[0], region);
    row.ge2 = Fraction(at_least[1] - exactly[1], region);
    row.ge3 = Fraction(at_least[2] - exactly[2], region);
    row.ge_k = Fraction(at_least[3] - exactly[3], region);
    if (table.uncertainty) {
      // The multiset intact - removed + added: the sigma_max list of the rig without this camera.
      const ListPercentiles after =
          lists.Percentiles({{0, 1}, {1 + c, -1}, {1 + camera_count + c, 1}}, {50, 90});
      row.triangulable_voxels = after.count;
      row.triangulable = Fraction(after.count, region);
      row.sigma_max_p50_mm = after.values[0];
      row.sigma_max_p90_mm = after.values[1];
    }
    table.rows.push_back(row);
  }
  double sum = 0;
  for (const CriticalityRow& row : table.rows) sum += row.ge_k;
  table.mean_ge_k = table.rows.empty() ? table.ge_k : sum / static_cast<double>(table.rows.size());
  if (!table.rows.empty()) table.worst = table.MostCritical().front();
  return table;
}

CriticalityTable ComputeCriticality(const Scene& scene, const Rig& rig, const Fields& fields,
                                    const RayCaster& caster, int k, const ListMemory& memory) {
  const auto t0 = std::chrono::steady_clock::now();
  const CriticalitySetup setup(scene, rig, fields, caster, k);
  const std::int64_t region = fields.stats.active_set.region_voxels;
  const std::size_t leaves = setup.origins.size();
  // The lists hold about 8 bytes per (triangulable voxel, camera that sees it).
  const std::vector<std::int64_t> pairs =
      setup.sigma_grid ? PairsPerLeaf(setup) : std::vector<std::int64_t>();
  double list_bytes = 0;
  for (std::int64_t n : pairs) list_bytes += 8.0 * double(n);
  CriticalityTable table;
  if (list_bytes <= memory.bytes) {
    const SummaryParts parts = PartsOfLeaves(setup, 0, leaves);
    InMemoryPercentiles lists(parts.lists);
    table = FinishCriticality(rig, k, region, parts.counts, lists);
  } else {
    // Part by part, each part's lists written to disk and freed: a part's lists, their threads'
    // copies and the growth of those take up to about four times the lists' own bytes.
    const std::string folder =
        memory.folder.empty() ? std::filesystem::temp_directory_path().string() : memory.folder;
    SpilledParts spilled(folder, memory.blame.empty() ? folder : memory.blame);
    AddPartsOfLeaves(setup, pairs, std::max(1.0, memory.bytes / 4.0), spilled);
    table = FinishCriticality(rig, k, region, spilled.Counts(), spilled);
    table.spilled_bytes = list_bytes;
  }
  table.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return table;
}

void AddCoverageN1Grid(Fields* fields) {
  Fields::Impl& g = fields->impl();
  if (!g.coverage) return;
  openvdb::FloatGrid::Ptr out = openvdb::FloatGrid::create(0.0f);
  out->setName("coverage_n1");
  out->setTransform(g.coverage->transform().copy());
  auto acc = out->getAccessor();
  for (auto it = g.coverage->cbeginValueOn(); it; ++it) {
    const float v = static_cast<float>(std::max(*it - 1, 0));
    if (it.isVoxelValue()) {
      acc.setValueOn(it.getCoord(), v);
    } else {
      openvdb::CoordBBox box;
      it.getBoundingBox(box);
      out->tree().fill(box, v, true);
    }
  }
  g.extra["coverage_n1"] = out;
}

void to_json(nlohmann::json& j, const CriticalityTable& t) {
  const auto value = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json();
  };
  nlohmann::json rows = nlohmann::json::array();
  for (const CriticalityRow& r : t.rows)
    rows.push_back({{"id", r.id},
                    {"seen_voxels", r.seen_voxels},
                    {"ge1", r.ge1},
                    {"ge2", r.ge2},
                    {"ge3", r.ge3},
                    {"ge_k", r.ge_k},
                    {"triangulable", value(r.triangulable)},
                    {"sigma_max_p50_mm", value(r.sigma_max_p50_mm)},
                    {"sigma_max_p90_mm", value(r.sigma_max_p90_mm)}});
  nlohmann::json worst;
  if (t.worst >= 0)
    worst = {
        {"camera", t.rows[t.worst].id}, {"ge_k", t.rows[t.worst].ge_k}, {"loss", t.worst_loss()}};
  j = {{"k", t.k},
       {"ge_k", t.ge_k},
       {"worst", worst},
       {"mean_ge_k", t.mean_ge_k},
       {"seconds", t.seconds},
       {"per_camera", rows}};
}

std::string FormatCriticality(const CriticalityTable& t, int rows) {
  std::string out;
  if (t.worst < 0) return "N-1: no enabled camera\n";
  out += Format(
      "N-1 (one camera fails), seen by >= %d: intact %.1f%%, worst %s %.1f%% (-%.1f points), mean "
      "%.1f%%\n",
      t.k, 100 * t.ge_k, t.rows[t.worst].id.c_str(), 100 * t.rows[t.worst].ge_k,
      100 * t.worst_loss(), 100 * t.mean_ge_k);
  const std::vector<int> order = t.MostCritical();
  const bool k_column = t.k > 3;  // ge1..ge3 already show k <= 3
  out += Format("  %-12s %7s %7s %7s%s%s\n", "fails", ">=1", ">=2", ">=3",
                k_column ? Format(" %7s", Format(">=%d", t.k).c_str()).c_str() : "",
                t.uncertainty ? "  triangulable  sigma_max p50 / p90 mm" : "");
  for (int i = 0; i < rows && i < static_cast<int>(order.size()); ++i) {
    const CriticalityRow& r = t.rows[order[i]];
    std::string line = Format("  %-12s %6.1f%% %6.1f%% %6.1f%%", r.id.c_str(), 100 * r.ge1,
                              100 * r.ge2, 100 * r.ge3);
    if (k_column) line += Format(" %6.1f%%", 100 * r.ge_k);
    if (t.uncertainty) {
      const auto cell = [](const std::optional<double>& v) {
        return v ? Format("%.3g", *v) : std::string("-");
      };
      line += Format("  %11.1f%%  %s / %s", 100 * r.triangulable.value_or(0),
                     cell(r.sigma_max_p50_mm).c_str(), cell(r.sigma_max_p90_mm).c_str());
    }
    out += line + "\n";
  }
  return out;
}

}  // namespace pandora
