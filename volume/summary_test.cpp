// The typed summary (volume/summary.h) against closed forms and brute force: nearest-rank
// percentiles of known lists, the free-voxel count of a box region around a solid cube, coverage
// and per-camera counts from VisibilityTester on every voxel centre, the sigma_max and resolution
// percentiles from the per-point evaluation (analysis/geometry/uncertainty.h), and summary.json as
// the typed value's JSON form.
#include "volume/summary.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "tests/fixtures.h"
#include "volume/active_set.h"
#include "volume/summary_parts.h"
#include "volume/value_spill.h"

namespace pandora {
namespace {

TEST(NearestRankPercentile, KnownLists) {
  std::vector<float> v{10, 1, 9, 2, 8, 3, 7, 4, 6, 5};  // 1..10 shuffled
  EXPECT_EQ(*NearestRankPercentile(v, 50), 5.0);        // ceil(0.5 * 10) = 5th smallest
  EXPECT_EQ(*NearestRankPercentile(v, 90), 9.0);
  EXPECT_EQ(*NearestRankPercentile(v, 99), 10.0);  // ceil(9.9) = 10th
  EXPECT_EQ(*NearestRankPercentile(v, 0), 1.0);    // at least the first
  EXPECT_EQ(*NearestRankPercentile(v, 100), 10.0);
  EXPECT_EQ(*NearestRankPercentile({0.25f}, 50), 0.25);
  EXPECT_FALSE(NearestRankPercentile({}, 50));
}

// A streamed run's percentiles (volume/value_spill.h) equal NearestRankPercentile over the same
// values: 700,000 values (three read chunks) appended in uneven pieces, with many ties, values that
// share their upper 16 bits, negatives, both zeros and a wide range of magnitudes.
TEST(ValueSpill, EqualsNearestRankPercentileAndCounts) {
  ValueSpill empty(std::filesystem::temp_directory_path().string(), "test");
  EXPECT_EQ(empty.size(), 0);
  EXPECT_FALSE(empty.Percentiles({50})[0]);
  EXPECT_EQ(empty.CountAtMost(1.0), 0);

  std::mt19937_64 rng(7);
  std::vector<float> all;
  ValueSpill spill(std::filesystem::temp_directory_path().string(), "test");
  // The same values split over two spills (two processes of `--stream --mpi`).
  ValueSpill part_a(std::filesystem::temp_directory_path().string(), "test");
  ValueSpill part_b(std::filesystem::temp_directory_path().string(), "test");
  std::size_t piece = 1;
  while (all.size() < 700000) {
    std::vector<float> part;
    for (std::size_t i = 0; i < piece; ++i) {
      const int kind = int(rng() % 5);
      float v = 0;
      if (kind == 0) v = float(rng() % 40) * 0.25f;           // ties
      if (kind == 1) v = 1.0f + float(rng() % 1000) * 1e-7f;  // same upper 16 bits
      if (kind == 2) v = std::ldexp(float(rng() % 1000 + 1), int(rng() % 60) - 30);  // magnitudes
      if (kind == 3) v = -float(rng() % 1000) * 0.125f;                              // negatives
      if (kind == 4) v = (rng() % 2) ? 0.0f : -0.0f;                                 // both zeros
      part.push_back(v);
    }
    spill.Append(part);
    (piece % 2 ? part_a : part_b).Append(part);
    all.insert(all.end(), part.begin(), part.end());
    piece = piece * 3 + 1;
  }
  ASSERT_EQ(spill.size(), std::int64_t(all.size()));
  const std::vector<double> ps{0, 0.001, 1, 10, 33.3, 50, 90, 99, 99.99, 100};
  const std::vector<std::optional<double>> got = spill.Percentiles(ps);
  for (std::size_t i = 0; i < ps.size(); ++i) {
    SCOPED_TRACE(ps[i]);
    ASSERT_TRUE(got[i]);
    EXPECT_EQ(*got[i], *NearestRankPercentile(all, ps[i]));
  }
  // Counts summed over the parts select and resolve the same values.
  const auto add = [](std::vector<std::int64_t> x, const std::vector<std::int64_t>& y) {
    for (std::size_t i = 0; i < x.size(); ++i) x[i] += y[i];
    return x;
  };
  const PercentileBins selection =
      SelectPercentileBins(add(part_a.HighCounts(), part_b.HighCounts()), ps);
  const std::vector<std::optional<double>> merged = ResolvePercentiles(
      selection, add(part_a.LowCounts(selection.bins), part_b.LowCounts(selection.bins)),
      ps.size());
  for (std::size_t i = 0; i < ps.size(); ++i) EXPECT_EQ(merged[i], got[i]) << ps[i];
  EXPECT_GT(part_a.size(), 1000);
  EXPECT_GT(part_b.size(), 1000);
  for (double limit : {-1e9, -3.0, 0.0, 1.0000001, 2.5, 1e9})
    EXPECT_EQ(spill.CountAtMost(limit),
              std::count_if(all.begin(), all.end(), [&](float v) { return double(v) <= limit; }));
}

// A multiset difference's percentiles (N-1: the rig's values, less those a camera sees, plus their
// values without it), in memory and from parts spilled tile by tile, against NearestRankPercentile
// of the explicit multiset; a query taking out values it does not hold is refused.
TEST(SummaryParts, SignedPercentilesEqualTheExplicitMultiset) {
  std::mt19937_64 rng(11);
  const auto value = [&] { return float(rng() % 5000) * 0.01f + float(rng() % 3) * 1e-6f; };
  // Three "tiles": each with its intact list, a removed subset of it and added values.
  std::vector<SummaryParts> tiles(3);
  std::vector<float> expected;
  for (SummaryParts& t : tiles) {
    t.lists.resize(3);
    t.counts = {std::int64_t(rng() % 100)};
    for (int i = 0; i < 20000; ++i) {
      const float v = value();
      t.lists[0].push_back(v);
      if (rng() % 3 == 0)
        t.lists[1].push_back(v);  // taken out
      else
        expected.push_back(v);
    }
    for (int i = 0; i < 5000; ++i)
      t.lists[2].push_back(value()), expected.push_back(t.lists[2].back());
  }
  const std::vector<double> ps{0, 10, 50, 90, 99.9, 100};
  const std::vector<ListTerm> terms{{0, 1}, {1, -1}, {2, 1}};
  SummaryParts whole;
  for (const SummaryParts& t : tiles) whole.Add(t);
  EXPECT_EQ(whole.counts[0], tiles[0].counts[0] + tiles[1].counts[0] + tiles[2].counts[0]);
  InMemoryPercentiles memory(whole.lists);
  SpilledParts spilled(std::filesystem::temp_directory_path().string(), "test");
  for (SummaryParts t : tiles) spilled.Add(std::move(t));
  spilled.Reduce();
  EXPECT_EQ(spilled.Counts(), whole.counts);
  for (PercentileSource* source :
       {static_cast<PercentileSource*>(&memory), static_cast<PercentileSource*>(&spilled)}) {
    for (int repeat = 0; repeat < 2; ++repeat) {  // the in-memory upper counts are kept
      const ListPercentiles got = source->Percentiles(terms, ps);
      ASSERT_EQ(got.count, std::int64_t(expected.size()));
      for (std::size_t i = 0; i < ps.size(); ++i)
        EXPECT_EQ(got.values[i], NearestRankPercentile(expected, ps[i])) << ps[i];
    }
    const ListPercentiles one = source->Percentiles(2, {50});
    EXPECT_EQ(one.count, 15000);
    EXPECT_EQ(one.values[0], NearestRankPercentile(whole.lists[2], 50));
    EXPECT_EQ(source->Percentiles(7, {50}).count, 0);  // a list no part has: empty
    EXPECT_FALSE(source->Percentiles(7, {50}).values[0]);
    EXPECT_THROW(source->Percentiles({{2, 1}, {1, -1}}, {50}), std::logic_error);
  }
}

// The fixed-point sum of values in [0, 1]: the same in any order and split, within 2^-64 per
// value of the exact sum.
TEST(SummaryParts, FixedLimbsAddInAnyOrder) {
  std::mt19937_64 rng(5);
  std::vector<double> values;
  for (int i = 0; i < 100000; ++i) values.push_back(double(float(double(rng() % 1000001) / 1e6)));
  values.push_back(1.0);
  values.push_back(0.0);
  std::int64_t forward[kFixedLimbs] = {}, backward[kFixedLimbs] = {}, a[kFixedLimbs] = {},
               b[kFixedLimbs] = {};
  long double exact = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    AddFixedLimbs(values[i], forward);
    AddFixedLimbs(values[values.size() - 1 - i], backward);
    AddFixedLimbs(values[i], i % 2 ? a : b);
    exact += values[i];
  }
  for (int k = 0; k < kFixedLimbs; ++k) a[k] += b[k];
  EXPECT_EQ(FixedLimbsToDouble(forward), FixedLimbsToDouble(backward));
  EXPECT_EQ(FixedLimbsToDouble(forward), FixedLimbsToDouble(a));
  EXPECT_NEAR(FixedLimbsToDouble(forward), double(exact), 1e-9);
  EXPECT_THROW(AddFixedLimbs(1.5, forward), std::invalid_argument);
  EXPECT_THROW(AddFixedLimbs(std::nan(""), forward), std::invalid_argument);
}

// The box room with a solid cube in the middle of a 1 m region at 0.1 m voxels, a ring of six
// cameras and a seventh that is disabled.
struct RoomSetup {
  Scene scene;
  Rig rig;
  std::unique_ptr<RayCaster> caster;
  RoomSetup() {
    scene = testing::BoxRoom(Vec3(4, 4, 2.5), 0.1);
    scene.objects.push_back(
        testing::TestObject("cube", MakeBox(Vec3(0.35, 0.35, 0.35)), Vec3(0, 0, 0.5), true));
    scene.study.pixel_sigma = 0.5;
    scene.study.max_sigma_mm = 2.0;
    rig = testing::RingRig(6, 1.8, 1.2, Vec3(0, 0, 0.5), 70);
    rig.cameras.push_back(testing::TestCamera("off", Vec3(0, 1.8, 1.5), Vec3(0, 0, 0.5)));
    rig.cameras.back().enabled = false;
    rig.name = "ring";
    scene.rigs = {rig};
    caster = MakeEmbreeRayCaster(scene.AllTriangles());
  }
};

TEST(Summarize, CountsAndPercentilesMatchBruteForce) {
  const RoomSetup s;
  const std::vector<std::string> names{"coverage", "cameras", "resolution", "sigma_max"};
  FieldOptions options;
  options.fields = names;
  const Fields fields = EvaluateFields(s.scene, s.rig, *s.caster, options);
  const Summary summary = Summarize(s.scene, s.rig, fields, names, 3);

  // Closed form: 10 x 10 x 10 centres, of which 4 x 4 x 4 lie inside the 0.35 m cube.
  EXPECT_EQ(summary.region_dims, Eigen::Vector3i(10, 10, 10));
  EXPECT_EQ(summary.solid_voxels, 64);
  EXPECT_EQ(summary.region_voxels, 1000 - 64);
  EXPECT_EQ(summary.cameras, 6);
  EXPECT_EQ(summary.rig, "ring");
  EXPECT_EQ(summary.timing.threads, 3);

  // Brute force over every free voxel centre with the exact visibility rules.
  std::vector<Camera> enabled(s.rig.cameras.begin(), s.rig.cameras.begin() + 6);
  const VisibilityTester tester(enabled, *s.caster, s.scene.ContentBounds().diagonal());
  const VoxelLattice lattice = MakeLattice(s.scene.study.region.box, 0.1, s.scene.path);
  const Aabb cube{Vec3(-0.175, -0.175, 0.325), Vec3(0.175, 0.175, 0.675)};
  std::int64_t free = 0, at_least[4] = {0, 0, 0, 0};
  std::vector<std::int64_t> seen_by(7, 0);
  std::vector<float> sigma_mm, resolution;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k) {
        const Vec3 X = lattice.Center(i, j, k);
        if (cube.Contains(X)) continue;
        ++free;
        int count = 0;
        double best = 0;
        InformationBuilder info;
        for (int c = 0; c < 6; ++c) {
          Mat23 A;
          if (tester.Test(c, X, nullptr, &A) != ViewResult::kSeen) continue;
          ++count;
          ++seen_by[c];
          best = std::max(best, PixelDensity(A));
          info.Add(A, 0.5);
        }
        for (int m = 1; m <= 3; ++m) at_least[m] += count >= m;
        if (count > 0) resolution.push_back(static_cast<float>(best));
        const StaticUncertainty u = StaticFromInformation(info.Decompose(), info.cameras());
        if (u.triangulable) sigma_mm.push_back(static_cast<float>(1e3 * u.sigma_max));
      }
  ASSERT_EQ(free, summary.region_voxels);
  EXPECT_GT(at_least[2], 0);
  EXPECT_LT(at_least[3], free);  // the cube hides some voxels from most cameras
  EXPECT_DOUBLE_EQ(summary.coverage.ge1, double(at_least[1]) / free);
  EXPECT_DOUBLE_EQ(summary.coverage.ge2, double(at_least[2]) / free);
  EXPECT_DOUBLE_EQ(summary.coverage.ge3, double(at_least[3]) / free);
  ASSERT_EQ(summary.per_camera.size(), 7u);
  for (int c = 0; c < 6; ++c) {
    EXPECT_EQ(summary.per_camera[c].visible_voxels, seen_by[c]) << c;
    EXPECT_DOUBLE_EQ(summary.per_camera[c].visible_fraction, double(seen_by[c]) / free);
    EXPECT_TRUE(summary.per_camera[c].enabled);
  }
  EXPECT_FALSE(summary.per_camera[6].enabled);
  EXPECT_EQ(summary.per_camera[6].visible_voxels, 0);
  EXPECT_EQ(summary.per_camera[6].id, "off");
  // A pinhole's effective FOV is its nominal one: 70 degrees across.
  EXPECT_NEAR(summary.per_camera[0].lens.hfov_deg, 70.0, 1e-9);

  // Percentiles from the per-point evaluation (the fields' fast path agrees to round-off).
  ASSERT_TRUE(summary.uncertainty);
  EXPECT_EQ(summary.uncertainty->triangulable_voxels, static_cast<std::int64_t>(sigma_mm.size()));
  for (auto [p, value] : {std::pair{50, summary.uncertainty->sigma_max_mm.p50},
                          std::pair{90, summary.uncertainty->sigma_max_mm.p90},
                          std::pair{99, summary.uncertainty->sigma_max_mm.p99}}) {
    ASSERT_TRUE(value) << p;
    EXPECT_NEAR(*value, *NearestRankPercentile(sigma_mm, p), 1e-5 * *value) << p;
  }
  const double meets =
      std::count_if(sigma_mm.begin(), sigma_mm.end(), [](float v) { return v <= 2.0; });
  EXPECT_NEAR(*summary.uncertainty->meets_max_sigma, meets / free, 2.0 / free);
  EXPECT_FALSE(summary.uncertainty->motion);
  ASSERT_TRUE(summary.resolution_px_per_m);
  EXPECT_NEAR(*summary.resolution_px_per_m->p50, *NearestRankPercentile(resolution, 50),
              1e-5 * *summary.resolution_px_per_m->p50);
  EXPECT_NEAR(*summary.resolution_px_per_m->p10, *NearestRankPercentile(resolution, 10),
              1e-5 * *summary.resolution_px_per_m->p10);
}

TEST(Summarize, JsonIsTheTypedValue) {
  RoomSetup s;
  s.scene.study.motion = MotionModel{1.0, 60.0};
  const std::vector<std::string> names{"coverage", "sigma_max", "sigma_max_steady"};
  FieldOptions options;
  options.fields = names;
  const Fields fields = EvaluateFields(s.scene, s.rig, *s.caster, options);
  std::vector<Warning> warnings{
      {Warning::Kind::kSeesNoRegion, "c9", "$.rigs[0].cameras[9]", "sees nothing"}};
  const Summary typed = Summarize(s.scene, s.rig, fields, names, 2, warnings);
  const nlohmann::json j = MakeSummary(s.scene, s.rig, fields, names, 2, warnings);
  EXPECT_EQ(j, nlohmann::json(typed));
  EXPECT_EQ(j["region_voxels"].get<std::int64_t>(), typed.region_voxels);
  EXPECT_EQ(j["coverage"]["ge2"].get<double>(), typed.coverage.ge2);
  EXPECT_EQ(j["coverage"]["histogram"].get<std::vector<std::int64_t>>(), typed.coverage.histogram);
  EXPECT_FALSE(j.contains("resolution_px_per_m"));  // not asked for
  const nlohmann::json& u = j["uncertainty"];
  EXPECT_EQ(u["sigma_max_mm"]["p90"].get<double>(), *typed.uncertainty->sigma_max_mm.p90);
  EXPECT_EQ(u["motion"]["rate_hz"].get<double>(), 60.0);
  EXPECT_EQ(u["motion"]["covariance"], "posterior");
  EXPECT_EQ(u["sigma_max_steady_mm"]["p50"].get<double>(),
            *typed.uncertainty->sigma_max_steady_mm.p50);
  EXPECT_EQ(u["max_sigma_mm"].get<double>(), 2.0);
  EXPECT_TRUE(u.contains("meets_max_sigma_steady"));
  // The steady state is tighter than one frame.
  EXPECT_LT(*typed.uncertainty->sigma_max_steady_mm.p50, *typed.uncertainty->sigma_max_mm.p50);
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_EQ(j["warnings"][0]["kind"], "sees_no_region");
  EXPECT_EQ(j["warnings"][0]["camera"], "c9");
  EXPECT_EQ(j["per_camera"][6]["enabled"], false);
  EXPECT_EQ(j["region"]["dims"], nlohmann::json({10, 10, 10}));
  EXPECT_EQ(j["timing"]["threads"], 2);

  // No triangulable voxel: the percentiles are null, the steady keys still there.
  RoomSetup one;
  one.rig.cameras.resize(1);
  one.scene.study.motion = MotionModel{1.0, 60.0};
  const Fields single = EvaluateFields(one.scene, one.rig, *one.caster, options);
  const nlohmann::json j1 = MakeSummary(one.scene, one.rig, single, names, 1);
  EXPECT_TRUE(j1["uncertainty"]["sigma_max_mm"]["p50"].is_null());
  EXPECT_TRUE(j1["uncertainty"]["sigma_max_steady_mm"]["p99"].is_null());
  EXPECT_EQ(j1["uncertainty"]["meets_max_sigma_steady"], 0.0);
}

}  // namespace
}  // namespace pandora

namespace pandora {
namespace {

// An evaluation that leaves the sigma lists out (FieldOptions::value_lists false, as `pandora
// analyze` runs) has the same summary: its percentiles and max_sigma shares come from the grids.
TEST(Summarize, FromTheGridsWithoutTheLists) {
  RoomSetup s;
  s.scene.study.motion = MotionModel{1.0, 60.0};
  const std::vector<std::string> names{"coverage", "sigma_max", "sigma_max_steady"};
  FieldOptions options;
  options.fields = names;
  const Fields with = EvaluateFields(s.scene, s.rig, *s.caster, options);
  options.value_lists = false;
  const Fields without = EvaluateFields(s.scene, s.rig, *s.caster, options);
  ASSERT_GT(with.stats.triangulable_voxels, 100);
  EXPECT_EQ(with.stats.sigma_max_mm.size(), std::size_t(with.stats.triangulable_voxels));
  EXPECT_TRUE(without.stats.sigma_max_mm.empty());
  EXPECT_TRUE(without.stats.sigma_max_steady_mm.empty());
  s.scene.study.max_sigma_mm = *NearestRankPercentile(with.stats.sigma_max_mm, 50);  // half meet
  const nlohmann::json a = MakeSummary(s.scene, s.rig, with, names, 2, {});
  nlohmann::json b = MakeSummary(s.scene, s.rig, without, names, 2, {});
  b["timing"] = a["timing"];
  EXPECT_EQ(a, b);
  // Some voxels meet the limit and some do not: the shares are counted, not trivially 0 or 1.
  const double meets = a["uncertainty"]["meets_max_sigma"].get<double>();
  EXPECT_GT(meets, 0.0);
  EXPECT_LT(meets, a["uncertainty"]["triangulable"].get<double>());
  // Without the grid (sigma_mean only) the list is kept whatever the option says.
  options.fields = {"coverage", "sigma_mean"};
  EXPECT_FALSE(EvaluateFields(s.scene, s.rig, *s.caster, options).stats.sigma_max_mm.empty());
}

TEST(FormatSummary, TheTableAnalyzePrints) {
  Summary s;
  s.rig = "ring";
  s.cameras = 1;
  s.voxel_size_m = 0.05;
  s.region_voxels = 1000;
  s.solid_voxels = 64;
  s.coverage.ge1 = 0.9;
  s.coverage.ge2 = 0.5;
  s.coverage.ge3 = 0.125;
  s.resolution_px_per_m = ResolutionPercentiles{1134.4, 1229.0, std::nullopt};
  UncertaintySummary u;
  u.triangulable = 0.5;
  u.sigma_max_mm = {0.991, 3.48, 4.72};
  s.uncertainty = u;
  CameraSummary on, off;
  on.id = "c0";
  on.name = "left";
  on.visible_fraction = 0.595;
  on.lens.hfov_deg = 40.4;
  on.lens.vfov_deg = 30.7;
  on.lens.nominal_hfov_deg = 40;
  on.lens.nominal_vfov_deg = 30.5;
  off = on;
  off.id = "c1";
  off.enabled = false;
  s.per_camera = {on, off};
  s.timing.seconds = 0.5;
  s.timing.rays = 1000000;
  s.timing.point_camera_tests = 2000000;
  const std::string t = FormatSummary(s);
  EXPECT_EQ(
      t,
      "rig ring: 1 cameras, voxel 0.05 m, 1000 free region voxels (and 64 inside solids)\n"
      "coverage  >=1  90.0%   >=2  50.0%   >=3  12.5%\n"
      "resolution px/m    p10    1134  p50    1229  p90       -   (voxels seen by >= 1 camera, "
      "best camera)\n"
      "sigma_max mm       p50   0.991  p90    3.48  p99    4.72   (triangulable voxels: 50.0% of "
      "the region)\n"
      "camera       name                     sees   FOV h x v deg   (nominal, no distortion)\n"
      "c0           left                    59.5%   40.4 x 30.7     (40.0 x 30.5)\n"
      "c1           left                    59.5%   40.4 x 30.7     (40.0 x 30.5)  (disabled)\n"
      "0.500 s, 1e+06 rays (2e+06 rays/s), 2e+06 point-camera tests\n");
  // Without the resolution and uncertainty fields their lines are left out.
  s.resolution_px_per_m.reset();
  s.uncertainty.reset();
  const std::string bare = FormatSummary(s);
  EXPECT_EQ(bare.find("resolution"), std::string::npos);
  EXPECT_EQ(bare.find("sigma_max"), std::string::npos);
}

}  // namespace
}  // namespace pandora
