// Field evaluation: exact agreement with an uncull'd brute-force loop over every voxel, solids,
// closed forms for a single pinhole, budgets, field selection, and the .vdb round trip.
#include <gtest/gtest.h>
#include <openvdb/io/File.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/primitives.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "tests/fixtures.h"
#include "tests/random_scene.h"
#include "volume/fields_test_util.h"
#include "volume/fields_vdb.h"
#include "volume/robustness.h"
#include "volume/summary.h"
#include "volume/vdb_io.h"

namespace pandora {
namespace {

Camera MakeCamera(const Vec3& position, const Vec3& target, double hfov_deg, LensModel model,
                  double k1 = 0, double k2 = 0, const Vec3& up = Vec3(0, 0, 1)) {
  Camera cam = testing::WithIntrinsics(
      testing::TestCamera("cam", position, target, hfov_deg, 640, 480, model, up),
      [&](Intrinsics& k) {
        k.k1 = k1;
        k.k2 = k2;
      });
  cam.name.clear();
  cam.near = 0.05;
  cam.far = 20;
  return cam;
}

SceneObject Object(const std::string& name, TriangleMesh mesh, const Vec3& at, bool solid) {
  for (Vec3& v : mesh.vertices) v += at;
  SceneObject o;
  o.name = name;
  o.mesh = std::move(mesh);
  o.solid = solid;
  return o;
}

Scene TestScene() {
  Scene scene;
  scene.path = "test.json";
  scene.objects.push_back(Object("ball", MakeSphere(0.3, 24), Vec3(0.1, 0.0, 0.1), true));
  scene.objects.push_back(Object("post", MakeBox(Vec3(0.1, 0.1, 1.5)), Vec3(-0.5, 0.6, 0), true));
  scene.objects.push_back(Object("sheet", MakePlane(Vec2(0.6, 0.6)), Vec3(0.5, -0.5, 0.4), false));
  Rig rig;
  rig.name = "mixed";
  rig.cameras.push_back(MakeCamera(Vec3(3, 0, 1), Vec3(0, 0, 0), 50, LensModel::kPinhole));
  rig.cameras.push_back(
      MakeCamera(Vec3(0, 3, 2), Vec3(0, 0, 0), 70, LensModel::kBrownConrady, -0.25, 0.05));
  rig.cameras.push_back(
      MakeCamera(Vec3(-2, -2, 1.5), Vec3(0, 0, 0), 190, LensModel::kFisheye, 0.02, -0.005));
  rig.cameras.push_back(MakeCamera(Vec3(0, 0, 4), Vec3(0.2, 0.1, 0), 30, LensModel::kPinhole));
  rig.cameras.push_back(
      MakeCamera(Vec3(-3, 0, 0.5), Vec3(-4, 0, 0), 60, LensModel::kPinhole));  // away
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) rig.cameras[i].id = "c" + std::to_string(i);
  scene.rigs.push_back(rig);
  scene.study.region.box.min = Vec3(-1, -1, -0.5);
  scene.study.region.box.max = Vec3(1, 1, 0.8);
  scene.study.voxel_size = 0.05;
  return scene;
}

// The reference: every voxel of the lattice, every camera, no culling, no blocks.
struct Reference {
  std::int64_t region = 0, solid = 0;
  std::vector<std::int64_t> per_camera;
  std::map<std::tuple<int, int, int>, std::pair<int, std::uint64_t>> seen;
};

Reference BruteForce(const Scene& scene, const Rig& rig, const RayCaster& caster) {
  Reference ref;
  ref.per_camera.assign(rig.cameras.size(), 0);
  const VoxelLattice lat = MakeLattice(scene.study.region.box, scene.study.voxel_size, "x");
  std::vector<std::unique_ptr<InsideMesh>> solids;
  for (const SceneObject& o : scene.objects)
    if (o.solid) solids.push_back(std::make_unique<InsideMesh>(o.mesh));
  const VisibilityTester vis(rig.cameras, caster, scene.ContentBounds().diagonal());
  for (int i = 0; i < lat.dims.x(); ++i)
    for (int j = 0; j < lat.dims.y(); ++j)
      for (int k = 0; k < lat.dims.z(); ++k) {
        const Vec3 p = lat.Center(i, j, k);
        bool inside = false;
        for (const auto& s : solids) inside = inside || s->Inside(p);
        if (inside) {
          ++ref.solid;
          continue;
        }
        ++ref.region;
        int count = 0;
        std::uint64_t mask = 0;
        for (std::size_t c = 0; c < rig.cameras.size(); ++c)
          if (vis.Test(static_cast<int>(c), p) == ViewResult::kSeen) {
            ++count;
            mask |= std::uint64_t{1} << c;
            ++ref.per_camera[c];
          }
        if (count) ref.seen[{i, j, k}] = {count, mask};
      }
  return ref;
}

// The cameras that see voxel xyz as a bitmask, from the per-camera grids (test rigs have < 64).
std::uint64_t MaskAt(const Fields::Impl& g, const openvdb::Coord& xyz) {
  std::uint64_t mask = 0;
  for (std::size_t c = 0; c < g.visible.size(); ++c)
    if (g.visible[c]->tree().isValueOn(xyz)) mask |= std::uint64_t{1} << c;
  return mask;
}

// Voxels seen by at least one camera: the union of the per-camera grids.
std::int64_t SeenVoxels(const Fields::Impl& g) {
  openvdb::BoolTree all(false);
  for (const auto& grid : g.visible) all.topologyUnion(grid->tree());
  return static_cast<std::int64_t>(all.activeVoxelCount());
}

TEST(Fields, MatchBruteForceVoxelByVoxel) {
  const Scene scene = TestScene();
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  const Fields fields = EvaluateFields(scene, rig, *caster, options);
  const Reference ref = BruteForce(scene, rig, *caster);

  const FieldStats& st = fields.stats;
  EXPECT_EQ(st.active_set.region_voxels, ref.region);
  EXPECT_EQ(st.active_set.solid_voxels, ref.solid);
  EXPECT_EQ(st.seen_voxels, static_cast<std::int64_t>(ref.seen.size()));
  EXPECT_EQ(st.per_camera_seen, ref.per_camera);
  EXPECT_EQ(st.per_camera_seen[4], 0);  // looks away from the region
  EXPECT_GT(ref.solid, 0);
  EXPECT_LT(st.rays, st.point_camera_tests);  // culling and projection save rays

  const Fields::Impl& g = fields.impl();
  ASSERT_TRUE(g.coverage && g.Float("resolution"));
  ASSERT_EQ(g.visible.size(), rig.cameras.size());
  EXPECT_EQ(static_cast<std::int64_t>(g.coverage->activeVoxelCount()), ref.region);
  EXPECT_EQ(SeenVoxels(g), static_cast<std::int64_t>(ref.seen.size()));
  EXPECT_EQ(std::int64_t(g.Float("resolution")->activeVoxelCount()), SeenVoxels(g));
  for (std::size_t c = 0; c < rig.cameras.size(); ++c)
    EXPECT_EQ(std::int64_t(g.visible[c]->activeVoxelCount()), ref.per_camera[c]) << c;
  auto cov = g.coverage->getConstAccessor();
  for (const auto& [ijk, value] : ref.seen) {
    const openvdb::Coord xyz(std::get<0>(ijk), std::get<1>(ijk), std::get<2>(ijk));
    ASSERT_EQ(cov.getValue(xyz), value.first);
    ASSERT_EQ(MaskAt(g, xyz), value.second);
  }
  // The world transform puts voxel (i, j, k) at its lattice centre.
  const openvdb::Vec3d w = g.coverage->transform().indexToWorld(openvdb::Coord(3, 4, 5));
  const Vec3 c = fields.lattice.Center(3, 4, 5);
  EXPECT_NEAR(w.x(), c.x(), 1e-12);
  EXPECT_NEAR(w.y(), c.y(), 1e-12);
  EXPECT_NEAR(w.z(), c.z(), 1e-12);
}

TEST(Fields, UncertaintyMatchesPerPointComputation) {
  Scene scene = TestScene();
  scene.study.motion = MotionModel{0.5, 30.0};
  scene.study.max_sigma_mm = 5.0;
  scene.rigs[0].cameras[1].pixel_sigma = 1.5;  // one camera noisier than the study's 0.5 px
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage",         "cameras",          "sigma_max",
                    "sigma_mean",       "condition",        "triangulation_angle",
                    "sigma_max_steady", "sigma_mean_steady"};
  const Fields fields = EvaluateFields(scene, rig, *caster, options);
  const Fields::Impl& g = fields.impl();
  for (const char* name : {"sigma_max", "sigma_mean", "condition", "triangulation_angle",
                           "sigma_max_steady", "sigma_mean_steady"})
    ASSERT_TRUE(g.Float(name)) << name;
  EXPECT_FALSE(g.Float("resolution"));

  // Every voxel seen by >= 2 cameras is triangulable here; the uncertainty grids hold exactly
  // those.
  const std::int64_t two_or_more = fields.stats.seen_voxels - fields.stats.coverage_histogram[1];
  EXPECT_EQ(fields.stats.triangulable_voxels + fields.stats.unobservable_voxels, two_or_more);
  EXPECT_EQ(static_cast<std::int64_t>(g.Float("sigma_max")->activeVoxelCount()),
            fields.stats.triangulable_voxels);
  EXPECT_GT(fields.stats.triangulable_voxels, 1000);

  auto smax = g.Float("sigma_max")->getConstAccessor();
  auto smean = g.Float("sigma_mean")->getConstAccessor();
  auto cond = g.Float("condition")->getConstAccessor();
  auto angle = g.Float("triangulation_angle")->getConstAccessor();
  auto steady_max = g.Float("sigma_max_steady")->getConstAccessor();
  auto steady_mean = g.Float("sigma_mean_steady")->getConstAccessor();
  int checked = 0;
  for (auto it = g.Float("sigma_max")->cbeginValueOn(); it; ++it) {
    if (++checked % 7 != 0) continue;  // a sample
    const openvdb::Coord xyz = it.getCoord();
    const Vec3 X = fields.lattice.Center(xyz.x(), xyz.y(), xyz.z());
    const auto mask = MaskAt(g, xyz);
    InformationBuilder builder;
    std::vector<Vec3> directions;
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
      if (!(mask >> c & 1)) continue;
      Mat23 J;
      ASSERT_TRUE(rig.cameras[c].Project(X, &J).has_value());
      builder.Add(J, c == 1 ? 1.5 : 0.5);
      directions.push_back((X - rig.cameras[c].center()).normalized());
    }
    const Information info = builder.Decompose();
    const StaticUncertainty s = StaticFromInformation(info, builder.cameras());
    ASSERT_TRUE(s.triangulable);
    EXPECT_NEAR(*it, 1e3 * s.sigma_max, 1e-6 * 1e3 * s.sigma_max);
    EXPECT_NEAR(smean.getValue(xyz), 1e3 * s.sigma_mean, 1e-6 * 1e3 * s.sigma_mean);
    EXPECT_NEAR(cond.getValue(xyz), s.condition, 1e-6 * s.condition);
    // Float grid (6e-8) and an atan polynomial good to 2.1e-8: 3e-7 relative.
    const double reference = MaxTriangulationAngle(directions) * 180 / kPi;
    EXPECT_NEAR(angle.getValue(xyz), reference, 3e-7 * reference);
    const SteadyUncertainty st =
        SteadyFromInformation(info, builder.cameras(), *scene.study.motion);
    EXPECT_NEAR(steady_max.getValue(xyz), 1e3 * st.sigma_max, 1e-6 * 1e3 * st.sigma_max);
    EXPECT_NEAR(steady_mean.getValue(xyz), 1e3 * st.sigma_mean, 1e-6 * 1e3 * st.sigma_mean);
    EXPECT_LT(st.sigma_max, s.sigma_max);  // filtering over frames helps
  }
  EXPECT_GT(checked, 1000);

  // The summary's percentiles are ranks of the grid's values.
  std::vector<float> values;
  for (auto it = g.Float("sigma_max")->cbeginValueOn(); it; ++it) values.push_back(*it);
  std::sort(values.begin(), values.end());
  const nlohmann::json summary = MakeSummary(scene, rig, fields, options.fields, 1);
  const auto& u = summary["uncertainty"];
  EXPECT_DOUBLE_EQ(u["sigma_max_mm"]["p50"].get<double>(),
                   values[static_cast<std::size_t>(std::ceil(0.5 * values.size())) - 1]);
  EXPECT_DOUBLE_EQ(u["sigma_max_mm"]["p99"].get<double>(),
                   values[static_cast<std::size_t>(std::ceil(0.99 * values.size())) - 1]);
  const double meets =
      double(std::count_if(values.begin(), values.end(), [](float v) { return v <= 5.0f; })) /
      double(fields.stats.active_set.region_voxels);
  EXPECT_DOUBLE_EQ(u["meets_max_sigma"].get<double>(), meets);
  EXPECT_DOUBLE_EQ(u["triangulable"].get<double>(), double(fields.stats.triangulable_voxels) /
                                                        fields.stats.active_set.region_voxels);
  EXPECT_TRUE(u.contains("sigma_max_steady_mm"));
}

TEST(Fields, SteadyFieldsNeedAMotionModel) {
  const Scene scene = TestScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "sigma_max_steady"};
  try {
    EvaluateFields(scene, scene.rigs[0], *caster, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "$.study.fields[1]");
  }
}

TEST(Fields, OptionsCheckNamesWhereTheFieldsCameFrom) {
  const Scene scene = TestScene();
  const auto fault = [&scene](const FieldOptions& options) {
    try {
      options.Check(scene);
    } catch (const InputError& e) {
      return e.file() + " " + e.json_path() + " " + e.reason();
    }
    return std::string("no error");
  };
  FieldOptions options;
  options.scene_path = "scene.json";
  EXPECT_EQ(fault(options), "no error");
  options.fields = {"coverage", "sigma_maxx"};
  EXPECT_EQ(fault(options), "scene.json $.study.fields[1] unknown field 'sigma_maxx'");
  options.fields_option = "{fields}";
  EXPECT_EQ(fault(options), "{fields}  unknown field 'sigma_maxx'");
  options.fields = {};
  EXPECT_EQ(fault(options), "{fields}  no field requested");
  options.fields = {"coverage"};
  options.memory_budget_bytes = 0;
  EXPECT_EQ(fault(options), "scene.json $.study.memory_budget_mb the memory budget must be > 0");
  options.memory_budget_bytes = 1e9;
  options.partition_count = 2;
  options.partition_rank = 2;
  EXPECT_EQ(fault(options), "{partition_count}  partition 2 of 2 does not exist");
  options.partition_rank = 1;
  EXPECT_EQ(fault(options), "no error");
}

TEST(Fields, SinglePinholeClosedForm) {
  // Camera 2 m above a small region, looking straight down; nothing in the way: every voxel is seen
  // once, and the resolution is f/Z (1 + r^2)^(1/4) with r the normalized image radius.
  Scene scene;
  scene.path = "single.json";
  Rig rig;
  rig.name = "one";
  rig.cameras.push_back(
      MakeCamera(Vec3(0, 0, 2), Vec3(0, 0, 0), 60, LensModel::kPinhole, 0, 0, Vec3(0, 1, 0)));
  scene.rigs.push_back(rig);
  scene.study.region.box.min = Vec3(-0.2, -0.2, -0.2);
  scene.study.region.box.max = Vec3(0.2, 0.2, 0.2);
  scene.study.voxel_size = 0.02;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Fields fields = EvaluateFields(scene, scene.rigs[0], *caster, FieldOptions{});
  EXPECT_EQ(fields.stats.active_set.region_voxels, 20 * 20 * 20);
  EXPECT_EQ(fields.stats.seen_voxels, 20 * 20 * 20);
  EXPECT_EQ(fields.stats.coverage_histogram[1], 8000);
  EXPECT_EQ(fields.stats.rays, 8000);

  // Widen the region far beyond the frustum: the new blocks are culled whole, cast no ray, and are
  // stored as tiles of coverage 0.
  scene.study.region.box.min = Vec3(-4, -4, -0.2);
  scene.study.region.box.max = Vec3(4, 4, 0.2);
  const Fields wide = EvaluateFields(scene, scene.rigs[0], *caster, FieldOptions{});
  EXPECT_GT(wide.stats.active_set.culled_blocks, wide.stats.active_set.blocks / 2);
  EXPECT_EQ(wide.stats.active_set.region_voxels, 400 * 400 * 20);
  EXPECT_EQ(static_cast<std::int64_t>(wide.impl().coverage->activeVoxelCount()), 400 * 400 * 20);
  EXPECT_GT(wide.impl().coverage->tree().activeTileCount(), 0u);
  // The frustum at depth Z spans +-Z tan(30 deg) x +-0.75 Z tan(30 deg).
  std::int64_t expected = 0;
  for (int i = 0; i < 400; ++i)
    for (int j = 0; j < 400; ++j)
      for (int k = 0; k < 20; ++k) {
        const Vec3 p = wide.lattice.Center(i, j, k);
        const double Z = 2.0 - p.z();
        const double x = -p.x() / Z, y = p.y() / Z;  // camera x = world -x, y = world +y here
        const double fx = rig.cameras[0].model.intrinsics().fx;
        const double u = fx * x + 319.5, v = fx * y + 239.5;
        if (u >= -0.5 && u <= 639.5 && v >= -0.5 && v <= 479.5) ++expected;
      }
  EXPECT_EQ(wide.stats.seen_voxels, expected);
  const double f = rig.cameras[0].model.intrinsics().fx;
  auto res = fields.impl().Float("resolution")->getConstAccessor();
  for (const auto& ijk :
       {Eigen::Vector3i(0, 0, 0), Eigen::Vector3i(10, 3, 19), Eigen::Vector3i(19, 19, 7)}) {
    const Vec3 p = fields.lattice.Center(ijk.x(), ijk.y(), ijk.z());
    const double Z = 2.0 - p.z();
    const double r2 = (p.x() * p.x() + p.y() * p.y()) / (Z * Z);
    EXPECT_NEAR(res.getValue(openvdb::Coord(ijk.x(), ijk.y(), ijk.z())),
                f / Z * std::pow(1 + r2, 0.25), 1e-4 * f / Z);
  }
}

TEST(Fields, VoxelCentresBeyondTheRegionBoxAreLeftOut) {
  // Extent 1.0 at voxel 0.3: the lattice has 4 voxels per axis (centres 0.15 .. 1.05), but only 3
  // centres per axis lie inside the box; a solid lid just above the box is never counted.
  Scene scene = TestScene();
  scene.objects.clear();
  scene.objects.push_back(Object("lid", MakeBox(Vec3(2, 2, 0.2)), Vec3(0.5, 0.5, 1.12), true));
  scene.study.region.box.min = Vec3(0, 0, 0);
  scene.study.region.box.max = Vec3(1.0, 1.0, 1.0);
  scene.study.voxel_size = 0.3;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Fields f = EvaluateFields(scene, scene.rigs[0], *caster, FieldOptions{});
  EXPECT_EQ(f.lattice.dims, Eigen::Vector3i(4, 4, 4));
  EXPECT_EQ(f.stats.active_set.region_voxels, 27);
  EXPECT_EQ(f.stats.active_set.solid_voxels, 0);
  EXPECT_EQ(static_cast<std::int64_t>(f.impl().coverage->activeVoxelCount()), 27);
  // An extent that is a whole number of voxels keeps its last layer (centre within round-off).
  scene.study.region.box.max = Vec3(0.9, 0.9, 0.9);
  const Fields g = EvaluateFields(scene, scene.rigs[0], *caster, FieldOptions{});
  EXPECT_EQ(g.stats.active_set.region_voxels, 27);
}

TEST(Fields, OnlyRequestedFieldsAreBuilt) {
  const Scene scene = TestScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage"};
  const Fields fields = EvaluateFields(scene, scene.rigs[0], *caster, options);
  EXPECT_TRUE(fields.impl().coverage);
  EXPECT_TRUE(fields.impl().visible.empty());
  EXPECT_FALSE(fields.impl().Float("resolution"));
  options.fields = {"coverage", "bogus"};
  try {
    EvaluateFields(scene, scene.rigs[0], *caster, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "$.study.fields[1]");
  }
}

TEST(Fields, MemoryBudgetIsCheckedBeforeAllocating) {
  Scene scene = TestScene();
  scene.study.voxel_size = 1e-4;  // 2e4 x 2e4 x 1.3e4 voxels: terabytes
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.memory_budget_bytes = 1e9;
  try {
    EvaluateFields(scene, scene.rigs[0], *caster, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "$.study.voxel_size");
    EXPECT_NE(e.hint().find("voxel_size >="), std::string::npos) << e.what();
  }
  const VoxelLattice lat = MakeLattice(scene.study.region.box, 1e-4, "x");
  EXPECT_GT(EstimateFieldBytes(lat, {"coverage"}, 5), 1e12);
}

// The budget counts the blocks that hold free voxels: a solid filling most of the region leaves
// most of its box out, so a budget below the box's estimate but above the kept blocks' passes, and
// one below the kept blocks' is refused naming the voxel size.
TEST(Fields, MemoryBudgetCountsTheBlocksWithFreeVoxels) {
  Scene scene = TestScene();
  scene.study.voxel_size = 0.02;
  // x from -1.3 to 0.7 over the whole region in y and z: free only for x > 0.7 (3 of 13 block
  // columns).
  scene.objects.push_back(Object("block", MakeBox(Vec3(2.0, 2.6, 1.8)), Vec3(-0.3, 0, 0.15), true));
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "resolution"};
  const VoxelLattice lattice = MakeLattice(scene.study.region.box, scene.study.voxel_size, "x");
  const double box = EstimateFieldBytes(lattice, options.fields, 0);
  options.memory_budget_bytes = 1e12;
  const Fields all = EvaluateFields(scene, scene.rigs[0], *caster, options);
  const double kept = all.stats.estimated_bytes;
  EXPECT_LT(kept, 0.5 * box);  // most of the box is inside the block
  EXPECT_GT(kept, 512.0 * all.stats.active_set.blocks * 8.0);  // at least the two grids' bytes
  options.memory_budget_bytes = 0.5 * (kept + box);
  const Fields fits = EvaluateFields(scene, scene.rigs[0], *caster, options);
  EXPECT_EQ(fits.stats.active_set.region_voxels, all.stats.active_set.region_voxels);
  options.memory_budget_bytes = 0.9 * kept;
  try {
    EvaluateFields(scene, scene.rigs[0], *caster, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "$.study.voxel_size");
    EXPECT_NE(std::string(e.what()).find("over the budget"), std::string::npos) << e.what();
  }
}

TEST(Fields, VdbRoundTrip) {
  const Scene scene = TestScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const Fields fields = EvaluateFields(scene, scene.rigs[0], *caster, FieldOptions{});
  const auto dir = std::filesystem::temp_directory_path() / "pandora_vdb_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "fields.vdb").string();
  WriteFieldsVdb(fields, path, {{"units", "m"}, {"scene_sha256", "abc"}});
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));

  // The layout docs/fields.md describes: coverage as floats, one BoolGrid per camera.
  openvdb::io::File file(path);
  file.open();
  EXPECT_EQ(file.getMetadata()->metaValue<std::string>("scene_sha256"), "abc");
  openvdb::GridPtrVecPtr grids = file.getGrids();
  file.close();
  // Without rig metadata the cameras are named by index, one grid per camera of the rig (the
  // test scene's last camera looks away: its grid is empty).
  const int cameras = int(scene.rigs[0].cameras.size());
  ASSERT_EQ(int(grids->size()), 2 + cameras);
  std::map<std::string, openvdb::GridBase::Ptr> by_name;
  for (const auto& g : *grids) by_name[g->getName()] = g;
  auto coverage = openvdb::gridPtrCast<openvdb::FloatGrid>(by_name["coverage"]);
  auto resolution = openvdb::gridPtrCast<openvdb::FloatGrid>(by_name["resolution"]);
  ASSERT_TRUE(coverage && resolution);
  EXPECT_EQ(coverage->metaValue<std::string>("value_units"), "cameras");
  EXPECT_EQ(coverage->metaValue<std::string>("units"), "m");
  EXPECT_EQ(resolution->metaValue<std::string>("value_units"), "px/m");
  EXPECT_EQ(coverage->metaValue<std::string>("scene_sha256"), "abc");
  EXPECT_EQ(coverage->activeVoxelCount(), fields.impl().coverage->activeVoxelCount());
  EXPECT_EQ(coverage->tree().activeTileCount(), fields.impl().coverage->tree().activeTileCount());
  EXPECT_NEAR(coverage->voxelSize().x(), 0.05, 1e-15);
  auto cov = fields.impl().coverage->getConstAccessor();
  for (auto it = coverage->cbeginValueOn(); it; ++it)
    ASSERT_EQ(*it, float(cov.getValue(it.getCoord())));
  // Camera c's grid in the file is its grid in memory.
  for (int c = 0; c < cameras; ++c) {
    auto seen = openvdb::gridPtrCast<openvdb::BoolGrid>(by_name["visible/" + std::to_string(c)]);
    ASSERT_TRUE(seen) << c;
    EXPECT_EQ(seen->metaValue<std::int64_t>("camera_index"), c);
    EXPECT_EQ(seen->metaValue<std::string>("camera_id"), std::to_string(c));
    EXPECT_EQ(seen->activeVoxelCount(), fields.impl().visible[c]->activeVoxelCount()) << c;
    EXPECT_TRUE(seen->tree().hasSameTopology(fields.impl().visible[c]->tree())) << c;
  }

  // ReadFieldsVdb gives the in-memory grids back exactly.
  const Fields back = ReadFieldsVdb(path);
  ASSERT_TRUE(back.impl().coverage && back.impl().Float("resolution"));
  ASSERT_EQ(back.impl().visible.size(), fields.impl().visible.size());
  EXPECT_EQ(back.impl().coverage->activeVoxelCount(), fields.impl().coverage->activeVoxelCount());
  EXPECT_TRUE(back.impl().coverage->tree().hasSameTopology(fields.impl().coverage->tree()));
  for (auto it = back.impl().coverage->cbeginValueOn(); it; ++it)
    ASSERT_EQ(*it, cov.getValue(it.getCoord()));
  for (std::size_t c = 0; c < back.impl().visible.size(); ++c)
    EXPECT_TRUE(back.impl().visible[c]->tree().hasSameTopology(fields.impl().visible[c]->tree()));
  auto a = fields.impl().Float("resolution")->getConstAccessor();
  for (auto it = back.impl().Float("resolution")->cbeginValueOn(); it; ++it)
    ASSERT_EQ(*it, a.getValue(it.getCoord()));
  EXPECT_EQ(back.lattice.voxel_size, fields.lattice.voxel_size);
  EXPECT_EQ(back.lattice.origin, fields.lattice.origin);

  // An unwritable destination is an InputError naming the file, and leaves nothing behind.
  EXPECT_THROW(WriteFieldsVdb(fields, "/proc/pandora/nope.vdb", {}), InputError);
  std::filesystem::remove_all(dir);
}

// The bytes of a .vdb file, the header's random UUID (36 characters after the magic number,
// the file and library versions and the grid-offsets flag) blanked.
std::string BytesButTheUuid(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() > 57) bytes.replace(21, 36, 36, '-');
  return bytes;
}

// `pandora analyze` keeps the float fields out of memory: their leaves go to a temporary file block
// by block, the analyses read each grid back when they need it (Load), and fields.vdb is written a
// grid at a time. The file is the one the evaluation holding every grid writes, byte for byte; the
// spilled grids are not among the fields' floats meanwhile, and the statistics, the summary and
// the N-1 table are the same.
TEST(Fields, SpilledFieldsWriteTheSameFile) {
  const Scene scene = TestScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions held;
  held.fields = {"coverage",  "cameras",    "resolution",
                 "sigma_max", "sigma_mean", "triangulation_angle",
                 "condition"};
  const auto dir = std::filesystem::temp_directory_path() / "pandora_spill_test";
  std::filesystem::create_directories(dir);
  FieldOptions spilled = held;
  spilled.spilled_fields = {"sigma_max", "triangulation_angle", "condition", "sigma_mean",
                            "resolution"};
  spilled.spill_folder = dir.string();
  spilled.spill_blame = "--out";
  const Fields a = EvaluateFields(scene, scene.rigs[0], *caster, held);
  Fields b = EvaluateFields(scene, scene.rigs[0], *caster, spilled);
  EXPECT_TRUE(b.impl().floats.empty());
  ASSERT_EQ(b.impl().spilled.size(), 5u);
  EXPECT_FALSE(b.impl().Float("sigma_max"));
  EXPECT_TRUE(b.impl().Has("sigma_max"));
  EXPECT_FALSE(b.impl().Has("sigma_max_steady"));
  const SpilledGrid& sigma = b.impl().spilled.at("sigma_max");
  EXPECT_EQ(sigma.grid->tree().leafCount(), 0u);
  EXPECT_EQ(sigma.leaves->leaves(), std::int64_t(a.impl().Float("sigma_max")->tree().leafCount()));
  EXPECT_GT(sigma.leaves->leaves(), 10);
  testing::ExpectSameGrid(*a.impl().Float("sigma_max"), *sigma.Read(), "sigma_max read back");
  EXPECT_EQ(a.stats.triangulable_voxels, b.stats.triangulable_voxels);
  EXPECT_EQ(a.stats.coverage_histogram, b.stats.coverage_histogram);
  EXPECT_EQ(a.stats.sigma_max_mm, b.stats.sigma_max_mm);
  const auto without_timing = [](nlohmann::json j) {
    j.erase("timing");
    return j;
  };
  EXPECT_EQ(without_timing(Summarize(scene, scene.rigs[0], a, held.fields, 1, {})),
            without_timing(Summarize(scene, scene.rigs[0], b, held.fields, 1, {})));
  nlohmann::json n1_a = ComputeCriticality(scene, scene.rigs[0], a, *caster, 2),
                 n1_b = ComputeCriticality(scene, scene.rigs[0], b, *caster, 2);
  n1_a.erase("seconds");
  n1_b.erase("seconds");
  EXPECT_EQ(n1_a, n1_b);
  EXPECT_FALSE(n1_a["per_camera"][0]["sigma_max_p50_mm"].is_null());
  const std::map<std::string, std::string> meta{{"units", "m"}, {"scene_sha256", "abc"}};
  const std::string path_a = (dir / "held.vdb").string(), path_b = (dir / "spilled.vdb").string();
  WriteFieldsVdb(a, path_a, meta);
  WriteFieldsVdb(std::move(b), path_b, meta);
  EXPECT_TRUE(b.impl().spilled.empty());  // NOLINT(bugprone-use-after-move): consumed
  const std::string bytes_a = BytesButTheUuid(path_a);
  EXPECT_GT(bytes_a.size(), 10000u);
  EXPECT_TRUE(bytes_a == BytesButTheUuid(path_b));
  // A spill folder that cannot hold a file: one InputError naming what to change.
  spilled.spill_folder = (dir / "missing" / "folder").string();
  try {
    EvaluateFields(scene, scene.rigs[0], *caster, spilled);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "--out");
    EXPECT_NE(std::string(e.what()).find("temporary file"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pandora
