// N-1 criticality (volume/robustness.h) against removing each camera and recomputing: for every
// enabled camera of three rigs, the row computed from the per-voxel camera sets equals a full
// EvaluateFields of the rig with that camera disabled — coverage shares, triangulable voxels and
// sigma_max percentiles exactly (the same contribution, exact sum and eigen solver as the fields).
#include "volume/robustness.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "tests/fixtures.h"
#include "volume/fields.h"
#include "volume/fields_vdb.h"
#include "volume/summary.h"

namespace pandora {
namespace {

double AtLeast(const FieldStats& st, int j) {
  std::int64_t n = 0;
  for (std::size_t c = static_cast<std::size_t>(j); c < st.coverage_histogram.size(); ++c)
    n += st.coverage_histogram[c];
  return st.active_set.region_voxels > 0 ? double(n) / double(st.active_set.region_voxels) : 0.0;
}

// The same rows, field for field.
void ExpectSameTable(const CriticalityTable& a, const CriticalityTable& b) {
  EXPECT_EQ(a.ge_k, b.ge_k);
  EXPECT_EQ(a.worst, b.worst);
  EXPECT_EQ(a.mean_ge_k, b.mean_ge_k);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  for (std::size_t r = 0; r < a.rows.size(); ++r) {
    SCOPED_TRACE(a.rows[r].id);
    EXPECT_EQ(a.rows[r].seen_voxels, b.rows[r].seen_voxels);
    EXPECT_EQ(a.rows[r].ge1, b.rows[r].ge1);
    EXPECT_EQ(a.rows[r].ge2, b.rows[r].ge2);
    EXPECT_EQ(a.rows[r].ge3, b.rows[r].ge3);
    EXPECT_EQ(a.rows[r].ge_k, b.rows[r].ge_k);
    EXPECT_EQ(a.rows[r].triangulable, b.rows[r].triangulable);
    EXPECT_EQ(a.rows[r].triangulable_voxels, b.rows[r].triangulable_voxels);
    EXPECT_EQ(a.rows[r].sigma_max_p50_mm, b.rows[r].sigma_max_p50_mm);
    EXPECT_EQ(a.rows[r].sigma_max_p90_mm, b.rows[r].sigma_max_p90_mm);
  }
}

// Checks every row of ComputeCriticality against a full evaluation without that camera, and
// returns the table. The lists spilled to disk in parts of about a leaf each give the same table.
CriticalityTable ExpectRowsEqualRecompute(const Scene& scene, const Rig& rig,
                                          const FieldOptions& options, int k) {
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Fields fields = EvaluateFields(scene, rig, *caster, options);
  const CriticalityTable table = ComputeCriticality(scene, rig, fields, *caster, k);
  EXPECT_EQ(table.k, k);
  EXPECT_EQ(table.region_voxels, fields.stats.active_set.region_voxels);
  EXPECT_EQ(table.ge_k, AtLeast(fields.stats, k));
  EXPECT_EQ(int(table.rows.size()), rig.enabled_count());
  const bool sigma =
      std::find(options.fields.begin(), options.fields.end(), "sigma_max") != options.fields.end();
  EXPECT_EQ(table.uncertainty, sigma);
  EXPECT_EQ(table.spilled_bytes, 0.0);
  ListMemory tiny;
  tiny.bytes = 4.0 * 8 * 512;  // parts of one leaf seen by one camera
  const CriticalityTable spilled = ComputeCriticality(scene, rig, fields, *caster, k, tiny);
  EXPECT_EQ(spilled.spilled_bytes > 0, sigma && fields.stats.triangulable_voxels > 0);
  ExpectSameTable(table, spilled);
  for (const CriticalityRow& row : table.rows) {
    SCOPED_TRACE(scene.path + " " + rig.name + " without " + row.id);
    Rig without = rig;
    without.cameras[row.camera].enabled = false;
    const Fields after = EvaluateFields(scene, without, *caster, options);
    EXPECT_EQ(row.seen_voxels, fields.stats.per_camera_seen[row.camera]);
    EXPECT_EQ(row.ge1, AtLeast(after.stats, 1));
    EXPECT_EQ(row.ge2, AtLeast(after.stats, 2));
    EXPECT_EQ(row.ge3, AtLeast(after.stats, 3));
    EXPECT_EQ(row.ge_k, AtLeast(after.stats, k));
    if (!sigma) {
      EXPECT_FALSE(row.triangulable);
      EXPECT_FALSE(row.sigma_max_p50_mm);
      continue;
    }
    EXPECT_EQ(row.triangulable_voxels, after.stats.triangulable_voxels);
    EXPECT_EQ(row.triangulable.value_or(-1), double(after.stats.triangulable_voxels) /
                                                 double(after.stats.active_set.region_voxels));
    // Bit for bit: nearest-rank percentiles are values of the list.
    EXPECT_EQ(row.sigma_max_p50_mm, NearestRankPercentile(after.stats.sigma_max_mm, 50));
    EXPECT_EQ(row.sigma_max_p90_mm, NearestRankPercentile(after.stats.sigma_max_mm, 90));
  }
  // The worst failure is the row with the lowest ge_k, and the mean is the rows' mean.
  if (!table.rows.empty()) {
    double lowest = 1, sum = 0;
    for (const CriticalityRow& row : table.rows) {
      lowest = std::min(lowest, row.ge_k);
      sum += row.ge_k;
    }
    EXPECT_EQ(table.rows[table.worst].ge_k, lowest);
    EXPECT_DOUBLE_EQ(table.mean_ge_k, sum / table.rows.size());
    EXPECT_EQ(table.worst_loss(), table.ge_k - lowest);
  }
  return table;
}

TEST(Robustness, EachRowEqualsRemovingThatCameraInTheLab) {
  Scene scene = LoadScene("tests/data/lab_7x5.json");
  scene.study.voxel_size = 0.1;
  FieldOptions options;
  options.fields = {"coverage", "cameras", "resolution", "sigma_max"};
  const CriticalityTable table =
      ExpectRowsEqualRecompute(scene, scene.FindRig("lab10"), options, 3);
  // Not a trivial table: every camera sees part of the region, losing one costs coverage >= 3
  // somewhere, and the re-derived uncertainty differs from the intact one for some camera.
  const Fields intact = [&] {
    const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
    return EvaluateFields(scene, scene.FindRig("lab10"), *caster, options);
  }();
  // The lab is redundant at 10 cm: every voxel stays seen by >= 3 cameras after any one fails, so
  // the worst failure is the one that raises sigma_max p90 most. Where every voxel stays
  // triangulable, a voxel's information can only shrink, so no percentile improves.
  const auto p50 = NearestRankPercentile(intact.stats.sigma_max_mm, 50);
  const auto p90 = NearestRankPercentile(intact.stats.sigma_max_mm, 90);
  bool sigma_changed = false;
  for (const CriticalityRow& row : table.rows) {
    EXPECT_GT(row.seen_voxels, 0) << row.id;
    EXPECT_LE(row.ge3, AtLeast(intact.stats, 3)) << row.id;
    EXPECT_EQ(row.triangulable_voxels, intact.stats.triangulable_voxels) << row.id;
    EXPECT_GE(*row.sigma_max_p50_mm, *p50) << row.id;
    EXPECT_GE(*row.sigma_max_p90_mm, *p90) << row.id;
    EXPECT_LE(*row.sigma_max_p90_mm, *table.rows[table.worst].sigma_max_p90_mm) << row.id;
    sigma_changed |= row.sigma_max_p90_mm != p90;
  }
  EXPECT_TRUE(sigma_changed);
  EXPECT_EQ(table.worst_loss(), 0.0);
}

TEST(Robustness, EachRowEqualsRemovingThatCameraWithDistortionDisabledCamerasAndK4) {
  // The 14-camera lab rig: a distorted wide corner camera, a door camera looking up, cameras
  // without a far range; c3 disabled beforehand (no row for it), k = 4.
  Scene scene = LoadScene("tests/data/lab_7x5.json");
  scene.study.voxel_size = 0.12;
  Rig rig = scene.FindRig("lab");
  rig.cameras[2].enabled = false;
  FieldOptions options;
  options.fields = {"coverage", "cameras", "sigma_max", "condition"};
  const CriticalityTable table = ExpectRowsEqualRecompute(scene, rig, options, 4);
  for (const CriticalityRow& row : table.rows) EXPECT_NE(row.id, "c3");
}

TEST(Robustness, EachRowEqualsRemovingThatCameraInTheTraumaRoom) {
  Scene scene = LoadScene("examples/trauma_room/scene.json");
  scene.study.voxel_size = 0.008;
  FieldOptions options;
  options.fields = scene.study.fields;  // all nine, the steady ones included
  const CriticalityTable table =
      ExpectRowsEqualRecompute(scene, scene.FindRig("octagon"), options, 3);
  EXPECT_EQ(table.rows.size(), 8u);
}

// The exact information sums round each contribution on a grid set by the voxel's largest one,
// in bands of 32 binades (volume/information_sum.h). Two near cameras (1.6 s away) and four far
// ones (25 s away, the same lens) around a post give contributions about 250 times apart: at
// s = 1e-3 on both sides of the band boundary 2^33 (near about 5e11 / m^2, far 2e9), at s = 150
// of the boundary 2 (near about 20, far 0.09). Where one near camera is the only one in the
// top band, its failure moves the voxel to the far cameras' band and the sum is rebuilt from them;
// where both see the voxel, its contribution is subtracted. Every scale: exact.
TEST(Robustness, EachRowEqualsRemovingThatCameraAtExtremeScales) {
  for (const double s : {1e-3, 1.0, 150.0, 1e6}) {
    SCOPED_TRACE("scale " + std::to_string(s));
    Scene scene;
    scene.path = "synthetic.json";
    scene.objects.push_back(testing::TestObject("post", MakeBox(s * Vec3(0.15, 0.15, 0.9)),
                                                s * Vec3(0.1, 0, 0.45), true));
    scene.study.region.box.min = s * Vec3(-0.5, -0.5, 0);
    scene.study.region.box.max = s * Vec3(0.5, 0.5, 1);
    scene.study.voxel_size = 0.08 * s;
    const Vec3 centre = s * Vec3(0, 0, 0.5);
    Rig rig;
    rig.name = "near_far";
    rig.cameras.push_back(testing::TestCamera("n0", s * Vec3(1.6, 0, 1.2), centre, 60));
    rig.cameras.push_back(testing::TestCamera("n1", s * Vec3(0, 1.6, 1.9), centre, 60));
    rig.cameras.push_back(testing::TestCamera("f0", s * Vec3(25, 0, 5), centre, 60));
    rig.cameras.push_back(testing::TestCamera("f1", s * Vec3(0, 25, 8), centre, 60));
    rig.cameras.push_back(testing::TestCamera("f2", s * Vec3(-25, 0, 5), centre, 60));
    rig.cameras.push_back(testing::TestCamera("f3", s * Vec3(0, -25, 8), centre, 60));
    scene.rigs.push_back(rig);
    FieldOptions options;
    options.fields = {"coverage", "cameras", "sigma_max"};
    const CriticalityTable table = ExpectRowsEqualRecompute(scene, rig, options, 3);
    EXPECT_EQ(table.rows.size(), 6u);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

TEST(Robustness, CoverageOnlyHasNoUncertaintyColumns) {
  Scene scene = LoadScene("tests/data/lab_7x5.json");
  scene.study.voxel_size = 0.15;
  FieldOptions options;
  options.fields = {"coverage", "cameras"};
  const CriticalityTable table =
      ExpectRowsEqualRecompute(scene, scene.FindRig("lab10"), options, 2);
  nlohmann::json j = table;
  ASSERT_EQ(j["per_camera"].size(), 10u);
  EXPECT_TRUE(j["per_camera"][0]["sigma_max_p50_mm"].is_null());
  EXPECT_EQ(j["k"], 2);
  EXPECT_EQ(j["worst"]["camera"], table.rows[table.worst].id);
  EXPECT_TRUE(j["worst"]["loss"].is_number());
}

TEST(Robustness, NeedsTheCameraSets) {
  Scene scene = LoadScene("tests/data/lab_7x5.json");
  scene.study.voxel_size = 0.2;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage"};
  const Fields fields = EvaluateFields(scene, scene.FindRig("lab10"), *caster, options);
  EXPECT_FALSE(HasCameraSets(fields));
  EXPECT_THROW(ComputeCriticality(scene, scene.FindRig("lab10"), fields, *caster, 3),
               std::invalid_argument);
}

TEST(Robustness, CoverageN1GridIsCoverageLessOne) {
  Scene scene = LoadScene("tests/data/lab_7x5.json");
  scene.study.voxel_size = 0.1;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "cameras"};
  Fields fields = EvaluateFields(scene, scene.FindRig("lab10"), *caster, options);
  AddCoverageN1Grid(&fields);
  const auto& g = fields.impl();
  ASSERT_TRUE(g.extra.count("coverage_n1"));
  const openvdb::FloatGrid& n1 = *g.extra.at("coverage_n1");
  EXPECT_EQ(n1.activeVoxelCount(), g.coverage->activeVoxelCount());
  auto acc = n1.getConstAccessor();
  std::int64_t checked = 0;
  for (auto it = g.coverage->cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue()) continue;
    ASSERT_TRUE(acc.isValueOn(it.getCoord()));
    ASSERT_EQ(acc.getValue(it.getCoord()), float(std::max(*it - 1, 0)));
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(Robustness, FormatNamesTheWorstCamera) {
  CriticalityTable t;
  t.k = 3;
  t.ge_k = 0.8;
  t.uncertainty = true;
  CriticalityRow a, b;
  a.id = "a";
  a.ge1 = 1;
  a.ge_k = 0.7;
  a.triangulable = 0.9;
  a.sigma_max_p50_mm = 1.5;
  b.id = "b";
  b.ge_k = 0.5;
  b.triangulable = 0.8;
  t.rows = {a, b};
  t.worst = t.MostCritical().front();
  EXPECT_EQ(t.worst, 1);
  const std::string text = FormatCriticality(t);
  EXPECT_NE(text.find("worst b 50.0% (-30.0 points)"), std::string::npos) << text;
  EXPECT_NE(text.find("1.5 / -"), std::string::npos) << text;
}

}  // namespace
}  // namespace pandora
