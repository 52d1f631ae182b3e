// The incremental field evaluator against a full recompute: after every one of 200 random edits
// (moves, re-aims, enable/disable, intrinsics, pixel noise, cameras added and removed) on two
// scenes, every grid equals EvaluateFields' voxel for voxel and bit for bit (values, active states,
// tree topology), and so do the summary statistics. Also: cancellation keeps the previous fields,
// and the evaluator takes rigs of any size.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <map>
#include <random>

#include "analysis/geometry/primitives.h"
#include "analysis/util/error.h"
#include "tests/fixtures.h"
#include "volume/fields.h"
#include "volume/fields_test_util.h"
#include "volume/fields_transfer.h"
#include "volume/fields_vdb.h"
#include "volume/solid_trees.h"

namespace pandora {
namespace {

using testing::ExpectSameFields;

// A 320 x 240 test camera (tests/fixtures.h) with a working range and, for distorting lenses, k1.
Camera MakeCamera(const std::string& id, const Vec3& position, const Vec3& target, double hfov_deg,
                  LensModel model, double k1 = 0, double scale = 1) {
  Camera cam =
      testing::WithIntrinsics(testing::TestCamera(id, position, target, hfov_deg, 320, 240, model),
                              [&](Intrinsics& k) { k.k1 = k1; });
  cam.near = 0.05 * scale;
  cam.far = 20 * scale;
  return cam;
}

// A room with solids (a ball, a post), a loose sheet, and six cameras of three lens models; every
// length times `s`.
Scene SyntheticScene(double s = 1) {
  Scene scene;
  scene.path = "synthetic.json";
  auto add = [&](const std::string& name, TriangleMesh mesh, const Vec3& at, bool solid) {
    scene.objects.push_back(testing::TestObject(name, std::move(mesh), s * at, solid));
  };
  add("ball", MakeSphere(0.3 * s, 20), Vec3(0.1, 0.0, 0.1), true);
  add("post", MakeBox(s * Vec3(0.1, 0.1, 1.5)), Vec3(-0.5, 0.6, 0), true);
  add("sheet", MakePlane(s * Vec2(0.6, 0.6)), Vec3(0.5, -0.5, 0.4), false);
  Rig rig;
  rig.name = "six";
  const auto camera = [&](const std::string& id, const Vec3& at, const Vec3& target, double hfov,
                          LensModel model, double k1) {
    rig.cameras.push_back(MakeCamera(id, s * at, s * target, hfov, model, k1, s));
  };
  camera("a", Vec3(3, 0, 1), Vec3(0, 0, 0), 50, LensModel::kPinhole, 0);
  camera("b", Vec3(0, 3, 2), Vec3(0, 0, 0), 70, LensModel::kBrownConrady, -0.2);
  camera("c", Vec3(-2, -2, 1.5), Vec3(0, 0, 0), 190, LensModel::kFisheye, 0.02);
  camera("d", Vec3(0, 0, 4), Vec3(0.2, 0.1, 0), 30, LensModel::kPinhole, 0);
  camera("e", Vec3(-3, 0, 0.5), Vec3(0, 0, 0.2), 60, LensModel::kPinhole, 0);
  camera("f", Vec3(2, -2, 2), Vec3(0, 0, 0), 80, LensModel::kPinhole, 0);
  scene.rigs.push_back(rig);
  scene.study.region.box.min = s * Vec3(-1, -1, -0.5);
  scene.study.region.box.max = s * Vec3(1, 1, 0.8);
  scene.study.voxel_size = 0.06 * s;
  scene.study.motion = MotionModel{0.5 * s * s, 30.0};
  return scene;
}

// One random edit of the kinds a person makes in a session.
std::string RandomEdit(std::mt19937_64& rng, Rig* rig, const Camera& spare, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = static_cast<int>(rig->cameras.size());
  const int c = static_cast<int>(rng() % n);
  Camera& cam = rig->cameras[c];
  switch (rng() % 10) {
    case 0:
    case 1:
    case 2: {  // move
      cam.world_from_camera.translation() += 0.3 * scale * Vec3(u(rng), u(rng), u(rng));
      return "move " + cam.id;
    }
    case 3:
    case 4: {  // re-aim (a small rotation)
      const Eigen::AngleAxisd turn(0.2 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized());
      cam.world_from_camera.linear() = cam.world_from_camera.linear() * turn.toRotationMatrix();
      return "turn " + cam.id;
    }
    case 5:  // enable / disable
      cam.enabled = !cam.enabled;
      return std::string(cam.enabled ? "enable " : "disable ") + cam.id;
    case 6: {  // zoom and distortion
      Intrinsics k = cam.model.intrinsics();
      k.fx *= 1.0 + 0.2 * u(rng);
      k.fy = k.fx;
      if (k.model == LensModel::kBrownConrady) k.k1 = 0.1 * u(rng);
      cam.model = CameraModel(k);
      return "zoom " + cam.id;
    }
    case 7:  // pixel noise: information changes, visibility does not
      cam.pixel_sigma = 0.25 + 0.5 * (u(rng) + 1.0);
      return "noise " + cam.id;
    case 8:  // two cameras at once
      cam.world_from_camera.translation() += 0.2 * scale * Vec3(u(rng), u(rng), u(rng));
      rig->cameras[(c + 1) % n].enabled = !rig->cameras[(c + 1) % n].enabled;
      return "move " + cam.id + " and toggle the next";
    default:  // a camera added at the end, or the last one removed
      if (n > 3 && rng() % 2) {
        rig->cameras.pop_back();
        return "remove the last camera";
      }
      rig->cameras.push_back(spare);
      rig->cameras.back().id = "spare" + std::to_string(n);
      return "add a camera";
  }
}

void RunRandomEdits(const Scene& scene, const Rig& start, int steps, std::uint64_t seed,
                    double scale = 1) {
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = scene.study.fields.empty() ? FieldNames() : scene.study.fields;
  if (!scene.study.motion) {
    options.fields.erase(
        std::remove_if(options.fields.begin(), options.fields.end(),
                       [](const std::string& f) { return f.find("steady") != std::string::npos; }),
        options.fields.end());
  }
  FieldEvaluator evaluator(scene, *caster, options);
  Rig rig = start;
  FieldUpdate first = evaluator.Update(rig);
  EXPECT_TRUE(first.full);
  ExpectSameFields(evaluator.fields(), EvaluateFields(scene, rig, *caster, options), "start");
  std::mt19937_64 rng(seed);
  const Camera spare = start.cameras[rng() % start.cameras.size()];
  std::int64_t dirty_voxels = 0, full_voxels = 0;
  for (int step = 0; step < steps; ++step) {
    const std::string edit = RandomEdit(rng, &rig, spare, scale);
    const FieldUpdate u = evaluator.Update(rig);
    EXPECT_FALSE(u.full);
    EXPECT_FALSE(u.cancelled);
    const Fields full = EvaluateFields(scene, rig, *caster, options);
    dirty_voxels += u.dirty_voxels;
    full_voxels += full.stats.active_set.region_voxels;
    ExpectSameFields(evaluator.fields(), full, "step " + std::to_string(step) + " (" + edit + ")");
    if (::testing::Test::HasFatalFailure()) return;
  }
  std::printf("%s: %d edits, re-derived %.1f %% of the voxels a full evaluation computes\n",
              scene.path.c_str(), steps, 100.0 * double(dirty_voxels) / double(full_voxels));
}

// A study's kept solid trees (volume/solid_trees.h) give the fields an evaluation building its own
// gives, bit for bit, at two voxel sizes (the trees built once, then reused); a scene whose solid
// moved is not served from them.
TEST(FieldEvaluator, KeptSolidTreesGiveTheSameFields) {
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const SolidTrees trees(scene);
  FieldOptions own;
  own.fields = {"coverage", "cameras", "resolution", "sigma_max"};
  FieldOptions kept = own;
  kept.solid_trees = &trees;
  int solids = 0;
  for (const SceneObject& o : scene.objects) solids += o.solid ? 1 : 0;
  ASSERT_GE(solids, 2);
  for (double factor : {1.0, 0.5}) {
    Scene copy = scene;  // another voxel size: a copy, the same meshes
    copy.study.voxel_size *= factor;
    const Fields a = EvaluateFields(copy, copy.rigs[0], *caster, own);
    const Fields b = EvaluateFields(copy, copy.rigs[0], *caster, kept);
    ExpectSameFields(b, a, "voxel x" + std::to_string(factor));
    EXPECT_EQ(a.stats.active_set.solid_voxels, b.stats.active_set.solid_voxels);
    EXPECT_GT(b.stats.active_set.solid_voxels, 0);
    EXPECT_EQ(trees.built(), solids);  // built by the first evaluation, reused by the second
  }
  Scene moved = scene;
  for (SceneObject& o : moved.objects)
    if (o.solid) {
      for (Vec3& v : o.mesh.vertices) v += Vec3(0.01, 0, 0);
      EXPECT_EQ(trees.Object(moved, std::size_t(&o - moved.objects.data())), nullptr);
    }
}

// A voxel filter (coarse-to-fine refinement) evaluates exactly the voxels it keeps, with the
// values the full evaluation gives them, and nothing else.
TEST(FieldEvaluator, VoxelFilterEvaluatesExactlyTheKeptVoxels) {
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions all;
  all.fields = {"coverage", "resolution", "sigma_max", "triangulation_angle"};
  FieldOptions some = all;
  some.voxel_filter = [](int i, int j, int k) { return (i / 3 + j / 5 + k) % 4 == 0 || i < 6; };
  const Fields full = EvaluateFields(scene, scene.rigs[0], *caster, all);
  const Fields part = EvaluateFields(scene, scene.rigs[0], *caster, some);
  const Fields::Impl& a = full.impl();
  const Fields::Impl& b = part.impl();
  auto full_cov = a.coverage->getConstAccessor();
  std::int64_t kept = 0, in_full = 0;
  ForEachActiveVoxel(*b.coverage, [&](const openvdb::Coord& c, std::int32_t v) {
    ASSERT_TRUE(some.voxel_filter(c.x(), c.y(), c.z()));
    ASSERT_TRUE(full_cov.isValueOn(c));
    EXPECT_EQ(v, full_cov.getValue(c));
    ++kept;
  });
  ForEachActiveVoxel(*a.coverage, [&](const openvdb::Coord& c, std::int32_t) {
    in_full += some.voxel_filter(c.x(), c.y(), c.z()) ? 1 : 0;
  });
  EXPECT_EQ(kept, in_full);
  EXPECT_GT(kept, 1000);
  EXPECT_EQ(part.stats.active_set.region_voxels, kept);
  for (const char* name : {"resolution", "sigma_max", "triangulation_angle"}) {
    auto full_acc = a.Float(name)->getConstAccessor();
    std::int64_t n = 0, expected = 0;
    ForEachActiveVoxel(*b.Float(name), [&](const openvdb::Coord& c, float v) {
      ASSERT_TRUE(full_acc.isValueOn(c)) << name;
      EXPECT_EQ(v, full_acc.getValue(c)) << name;
      ++n;
    });
    ForEachActiveVoxel(*a.Float(name), [&](const openvdb::Coord& c, float) {
      expected += some.voxel_filter(c.x(), c.y(), c.z()) ? 1 : 0;
    });
    EXPECT_EQ(n, expected) << name;
  }
}

// A streamed evaluation (`pandora analyze --stream`): the tiles PlanTiles makes cover every block
// column once, each tile's voxels get the full evaluation's values, no voxel is in two tiles, and
// the tiles' statistics add up to the full evaluation's (the sigma_max lists as multisets).
TEST(FieldEvaluator, TilesAddUpToTheFullEvaluation) {
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions all;
  all.fields = {"coverage", "resolution", "sigma_max", "triangulation_angle"};
  const Fields full = EvaluateFields(scene, scene.rigs[0], *caster, all);
  const VoxelLattice& lattice = full.lattice;
  const int nbx = (lattice.dims.x() + 7) / 8, nby = (lattice.dims.y() + 7) / 8;
  ASSERT_GT(nbx * nby, 4);

  // Budget mode: a budget of a few columns gives several tiles, each within half of it.
  VoxelLattice column = lattice;
  column.dims = Eigen::Vector3i(8, 8, lattice.dims.z());
  const double per_column = EstimateFieldBytes(column, all.fields, 0);
  const std::vector<BlockColumns> by_budget =
      PlanTiles(lattice, all.fields, 2 * 3.5 * per_column, 0);
  EXPECT_GE(by_budget.size(), std::size_t(nbx * nby / 3));
  EXPECT_EQ(PlanTiles(lattice, all.fields, 1e15, 0).size(), 1u);  // all fits: one tile
  for (const int most : {3, 9}) {  // columns per tile: the budget's 3.5, or 3 x 3 blocks of side
    const std::vector<BlockColumns> tiles =
        most == 3 ? by_budget : PlanTiles(lattice, all.fields, 0, 3 * 8 * lattice.voxel_size);
    std::vector<int> seen(nbx * nby, 0);
    for (const BlockColumns& t : tiles) {
      EXPECT_LE((t.x1 - t.x0) * (t.y1 - t.y0), most);
      for (int x = t.x0; x < t.x1; ++x)
        for (int y = t.y0; y < t.y1; ++y) ++seen[x * nby + y];
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), nbx * nby);
  }

  const std::vector<BlockColumns> tiles =
      PlanTiles(lattice, all.fields, 0, 3 * 8 * lattice.voxel_size);
  ASSERT_GT(tiles.size(), 2u);
  FieldStats sum;
  std::map<std::string, std::int64_t> voxels;
  for (const BlockColumns& tile : tiles) {
    FieldOptions options = all;
    options.tile = tile;
    const Fields part = EvaluateFields(scene, scene.rigs[0], *caster, options);
    const Fields::Impl& a = full.impl();
    const Fields::Impl& b = part.impl();
    const auto inside = [&](const openvdb::Coord& c) {
      return c.x() >= 8 * tile.x0 && c.x() < 8 * tile.x1 && c.y() >= 8 * tile.y0 &&
             c.y() < 8 * tile.y1;
    };
    auto full_cov = a.coverage->getConstAccessor();
    ForEachActiveVoxel(*b.coverage, [&](const openvdb::Coord& c, std::int32_t v) {
      ASSERT_TRUE(inside(c));
      ASSERT_TRUE(full_cov.isValueOn(c));
      EXPECT_EQ(v, full_cov.getValue(c));
      ++voxels["coverage"];
    });
    for (const char* name : {"resolution", "sigma_max", "triangulation_angle"}) {
      auto full_acc = a.Float(name)->getConstAccessor();
      ForEachActiveVoxel(*b.Float(name), [&](const openvdb::Coord& c, float v) {
        ASSERT_TRUE(inside(c)) << name;
        ASSERT_TRUE(full_acc.isValueOn(c)) << name;
        EXPECT_EQ(v, full_acc.getValue(c)) << name;
        ++voxels[name];
      });
    }
    const FieldStats& st = part.stats;
    AddFieldStats(&sum, st);
  }
  std::vector<float>& sigma = sum.sigma_max_mm;
  const FieldStats& st = full.stats;
  EXPECT_EQ(voxels["coverage"], std::int64_t(full.impl().coverage->activeVoxelCount()));
  for (const char* name : {"resolution", "sigma_max", "triangulation_angle"})
    EXPECT_EQ(voxels[name], std::int64_t(full.impl().Float(name)->activeVoxelCount())) << name;
  EXPECT_EQ(sum.active_set.region_voxels, st.active_set.region_voxels);
  EXPECT_EQ(sum.active_set.solid_voxels, st.active_set.solid_voxels);
  EXPECT_EQ(sum.active_set.blocks, st.active_set.blocks);
  EXPECT_EQ(sum.seen_voxels, st.seen_voxels);
  EXPECT_EQ(sum.triangulable_voxels, st.triangulable_voxels);
  EXPECT_GT(sum.triangulable_voxels, 1000);
  EXPECT_EQ(sum.rays, st.rays);
  EXPECT_EQ(sum.point_camera_tests, st.point_camera_tests);
  EXPECT_EQ(sum.coverage_histogram, st.coverage_histogram);
  EXPECT_EQ(sum.per_camera_seen, st.per_camera_seen);
  std::vector<float> expected = st.sigma_max_mm;
  std::sort(sigma.begin(), sigma.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(sigma, expected);
}

TEST(FieldEvaluator, IncrementalEqualsFullRecomputeOnASyntheticScene) {
  const Scene scene = SyntheticScene();
  RunRandomEdits(scene, scene.rigs[0], 200, 1);
}

// The exact information sums (volume/fields.cpp, Sum6) round each contribution on a grid set by
// the voxel's largest one, in bands of 32 binades. At a millimetre scale (voxels of 60 um; OpenVDB
// takes none below about 15 um) the contributions are 1e9 to 1e11 / m^2, across the band boundary
// 2^33, so edits move voxels up and down a band and re-sum them (thousands of times here); at
// 150 m they are near the boundary 2; at 1e6 m about 1e-8 / m^2. Every case, with every field,
// equals a full recompute bit for bit.
TEST(FieldEvaluator, IncrementalEqualsFullRecomputeAtExtremeScales) {
  for (const double scale : {1e-3, 1.0, 150.0, 1e6}) {
    SCOPED_TRACE("scale " + std::to_string(scale));
    Scene scene = SyntheticScene(scale);
    scene.study.fields = FieldNames();  // every field, the uncertainty ones included
    RunRandomEdits(scene, scene.rigs[0], 40, 3, scale);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

TEST(FieldEvaluator, IncrementalEqualsFullRecomputeOnTheTraumaRoom) {
  Scene scene = LoadScene("examples/trauma_room/scene.json");
  scene.study.voxel_size = 0.008;  // 8 mm keeps 200 full recomputes under a few seconds
  RunRandomEdits(scene, scene.FindRig("grid4x2"), 200, 2);
}

// triangulation_angle tries the camera pairs whose angle bound can still win, largest bound first
// (volume/fields.cpp, OrderPairs): on 16 cameras (a ring of ten more around the synthetic scene,
// one of them inside the region, where its cone is the whole sphere, and two at the same place,
// whose pairs tie exactly) the fields equal an exhaustive all-pairs search bit for bit, after a
// full evaluation and after each of 40 edits, while computing a fraction of the dot products.
TEST(FieldEvaluator, PrunedAnglePairsEqualTheExhaustiveSearch) {
  Scene scene = SyntheticScene();
  scene.study.fields = FieldNames();
  Rig rig = scene.rigs[0];
  for (int i = 0; i < 10; ++i) {
    const double a = 2 * kPi * i / 10.0;
    const Vec3 at = i == 9 ? Vec3(0.6, 0.6, 0.5) : Vec3(3 * std::cos(a), 3 * std::sin(a), 1.2);
    rig.cameras.push_back(MakeCamera("ring" + std::to_string(i), at, Vec3(0, 0, 0.1),
                                     i == 9 ? 120 : 60, LensModel::kPinhole));
  }
  rig.cameras[rig.cameras.size() - 2].world_from_camera = rig.cameras[6].world_from_camera;
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions pruned;
  pruned.fields = scene.study.fields;
  FieldOptions exhaustive = pruned;
  exhaustive.exhaustive_angle_pairs = true;
  FieldEvaluator evaluator(scene, *caster, pruned);
  evaluator.Update(rig);
  const Fields all = EvaluateFields(scene, rig, *caster, exhaustive);
  ExpectSameFields(evaluator.fields(), all, "start");
  const FieldStats& st = evaluator.fields().stats;
  EXPECT_EQ(all.stats.angle_pairs_tried, all.stats.angle_pairs_all);
  EXPECT_EQ(st.angle_pairs_all, all.stats.angle_pairs_all);
  EXPECT_LT(st.angle_pairs_tried, st.angle_pairs_all / 2);
  std::printf("pairs tried: %.1f %% of all\n",
              100.0 * double(st.angle_pairs_tried) / double(st.angle_pairs_all));
  std::mt19937_64 rng(16);
  const Camera spare = rig.cameras[12];
  for (int step = 0; step < 40; ++step) {
    const std::string edit = RandomEdit(rng, &rig, spare, 1.0);
    evaluator.Update(rig);
    ExpectSameFields(evaluator.fields(), EvaluateFields(scene, rig, *caster, exhaustive),
                     "step " + std::to_string(step) + " (" + edit + ")");
    if (::testing::Test::HasFatalFailure()) return;
  }
}

// FieldOptions::time_phases (pandora bench's floor) times the uncertainty fields' own steps and
// changes nothing: the same fields bit for bit; each step timed, within the evaluation's wall
// time on one thread; nothing timed without it or without uncertainty fields.
TEST(FieldEvaluator, TimedPhasesChangeNothing) {
  const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions plain;
  plain.fields = FieldNames();
  FieldOptions timed = plain;
  timed.time_phases = true;
  const Fields a = EvaluateFields(scene, scene.rigs[0], *caster, plain);
  const Fields b = EvaluateFields(scene, scene.rigs[0], *caster, timed);
  ExpectSameFields(a, b, "timed");
  const FieldStats::Phases& p = b.stats.phases;
  EXPECT_GT(p.contributions, 0);
  EXPECT_GT(p.sums, 0);
  EXPECT_GT(p.eigenvalues, 0);
  EXPECT_GT(p.angles, 0);
  EXPECT_LT(p.Total(), b.stats.seconds);
  EXPECT_EQ(a.stats.phases.Total(), 0.0);
  timed.fields = {"coverage", "cameras", "resolution"};
  EXPECT_EQ(EvaluateFields(scene, scene.rigs[0], *caster, timed).stats.phases.Total(), 0.0);
}

// A session keeps every camera's per-block entries for incremental updates: that state is bounded
// by the budget too. The smallest budget (doubling from 64 kB) at which one evaluation fits refuses
// the same rig with kept state, naming it (its upper bound: every candidate camera seeing every
// free voxel, 12 times the one evaluation here); 32 times more holds both.
TEST(FieldEvaluator, KeptStateIsHeldToTheBudget) {
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "resolution", "sigma_max"};
  double budget = 65536;
  for (;; budget *= 2) {
    ASSERT_LT(budget, 1e10);
    options.memory_budget_bytes = budget;
    try {
      FieldEvaluator once(scene, *caster, options, /*keep_state=*/false);
      once.Update(scene.rigs[0]);
      break;
    } catch (const InputError&) {
    }
  }
  FieldEvaluator kept(scene, *caster, options, /*keep_state=*/true);
  try {
    kept.Update(scene.rigs[0]);
    ADD_FAILURE() << "kept state over the budget of " << budget << " bytes was allowed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("incremental updates of rig"), std::string::npos)
        << e.what();
  }
  options.memory_budget_bytes = 32 * budget;
  FieldEvaluator roomy(scene, *caster, options, /*keep_state=*/true);
  EXPECT_NO_THROW(roomy.Update(scene.rigs[0]));
}

TEST(FieldEvaluator, NothingChangedCostsNothing) {
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldEvaluator evaluator(scene, *caster, FieldOptions{});
  Rig rig = scene.rigs[0];
  evaluator.Update(rig);
  rig.cameras[2].name = "renamed";  // names and colours do not enter the fields
  rig.cameras[2].color = Vec3(1, 0, 0);
  const FieldUpdate u = evaluator.Update(rig);
  EXPECT_EQ(u.changed_cameras, 0);
  EXPECT_EQ(u.dirty_blocks, 0);
  EXPECT_EQ(u.rays, 0);
}

TEST(FieldEvaluator, OneMovedCameraRecastsOnlyItsOwnRays) {
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldEvaluator evaluator(scene, *caster, FieldOptions{});
  Rig rig = scene.rigs[0];
  evaluator.Update(rig);
  rig.cameras[3].world_from_camera.translation() += Vec3(0.1, 0, 0);
  const FieldUpdate u = evaluator.Update(rig);
  EXPECT_EQ(u.changed_cameras, 1);
  // Only camera 3 casts, and only as many segments as it alone casts in a full evaluation.
  Rig alone = rig;
  for (std::size_t c = 0; c < alone.cameras.size(); ++c) alone.cameras[c].enabled = c == 3;
  EXPECT_EQ(u.rays, EvaluateFields(scene, alone, *caster, FieldOptions{}).stats.rays);
  EXPECT_GT(u.rays, 0);
}

TEST(FieldEvaluator, CancelledUpdateKeepsThePreviousFields) {
  const Scene scene = SyntheticScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  std::atomic<bool> cancel{false};
  options.cancel = &cancel;
  FieldEvaluator evaluator(scene, *caster, options);
  const Rig before = scene.rigs[0];
  evaluator.Update(before);
  Rig after = before;
  after.cameras[0].world_from_camera.translation() += Vec3(0, 0.5, 0);
  cancel = true;
  const FieldUpdate u = evaluator.Update(after);
  EXPECT_TRUE(u.cancelled);
  ExpectSameFields(evaluator.fields(), EvaluateFields(scene, before, *caster, FieldOptions{}),
                   "cancelled");
  cancel = false;
  evaluator.Update(after);  // the edit is still pending: the next update applies it
  ExpectSameFields(evaluator.fields(), EvaluateFields(scene, after, *caster, FieldOptions{}),
                   "after");
}

// A rig of 1000 cameras on a dome: the per-camera sets are sparse grids, the coverage is the count
// of those grids voxel by voxel, and a change of one camera updates like any other.
TEST(FieldEvaluator, AThousandCameras) {
  Scene scene = SyntheticScene();
  scene.study.voxel_size = 0.1;
  Rig rig;
  rig.name = "dome";
  for (int i = 0; i < 1000; ++i) {
    const double z = 0.2 + 2.5 * (i + 0.5) / 1000.0;  // a spiral on a dome of radius ~4 m
    const double a = i * 2.399963;                    // the golden angle
    const double r = std::sqrt(std::max(0.5, 16.0 - z * z));
    rig.cameras.push_back(MakeCamera("cam" + std::to_string(i),
                                     Vec3(r * std::cos(a), r * std::sin(a), z), Vec3(0, 0, 0.1),
                                     40 + (i % 5) * 10, LensModel::kPinhole));
  }
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "cameras", "resolution", "sigma_max"};
  FieldEvaluator evaluator(scene, *caster, options);
  evaluator.Update(rig);
  const Fields& f = evaluator.fields();
  ASSERT_EQ(f.impl().visible.size(), 1000u);
  // Coverage is the number of camera grids holding the voxel.
  auto cov = f.impl().coverage->getConstAccessor();
  int checked = 0, most = 0;
  for (auto it = f.impl().coverage->cbeginValueOn(); it && checked < 300; ++it, ++checked) {
    int count = 0;
    for (const auto& grid : f.impl().visible) count += grid->tree().isValueOn(it.getCoord());
    ASSERT_EQ(count, *it) << it.getCoord();
    most = std::max(most, count);
  }
  EXPECT_GT(most, 64);  // beyond the old 64-bit mask
  EXPECT_EQ(f.stats.coverage_histogram.size(), 1001u);
  rig.cameras[500].world_from_camera.translation() += Vec3(0.3, 0, 0);
  evaluator.Update(rig);
  ExpectSameFields(evaluator.fields(), EvaluateFields(scene, rig, *caster, options), "moved");
}

// A distributed evaluation (`pandora analyze --mpi`): every partition of 1..7 evaluated alone,
// serialized and merged into partition 0's fields gives the single-process fields voxel for voxel,
// bit for bit, with the same topology and statistics (the sigma lists as multisets: the merge
// joins them partition by partition). Each block is evaluated by exactly one partition, and the
// largest partition's cost is within the longest-processing-time bound of 4/3 of the best.
void ExpectPartitionsMergeToTheWhole(const Scene& scene, const Rig& rig,
                                     const std::vector<std::string>& names) {
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = names;
  Fields whole = EvaluateFields(scene, rig, *caster, options);
  std::sort(whole.stats.sigma_max_mm.begin(), whole.stats.sigma_max_mm.end());
  std::sort(whole.stats.sigma_max_steady_mm.begin(), whole.stats.sigma_max_steady_mm.end());
  for (int count = 1; count <= 7; ++count) {
    SCOPED_TRACE(std::to_string(count) + " partitions");
    options.partition_count = count;
    options.partition_rank = 0;
    Fields merged = EvaluateFields(scene, rig, *caster, options);
    std::int64_t rays = merged.stats.rays;
    for (int rank = 1; rank < count; ++rank) {
      options.partition_rank = rank;
      const Fields part = EvaluateFields(scene, rig, *caster, options);
      rays += part.stats.rays;
      MergePartialFields(SerializePartialFields(part), &merged);
    }
    EXPECT_EQ(merged.stats.rays, rays);
    std::sort(merged.stats.sigma_max_mm.begin(), merged.stats.sigma_max_mm.end());
    std::sort(merged.stats.sigma_max_steady_mm.begin(), merged.stats.sigma_max_steady_mm.end());
    ExpectSameFields(merged, whole, "merged");
    if (::testing::Test::HasFatalFailure()) return;
  }
  const Fields part = EvaluateFields(scene, rig, *caster, options);
  EXPECT_THROW(MergePartialFields("not a partition", const_cast<Fields*>(&part)),
               std::runtime_error);
  std::string cut = SerializePartialFields(part);
  cut.resize(cut.size() / 2);
  EXPECT_THROW(MergePartialFields(cut, const_cast<Fields*>(&part)), std::runtime_error);
}

TEST(FieldEvaluator, PartitionsMergeToTheWholeOnASyntheticScene) {
  const Scene scene = SyntheticScene();
  ExpectPartitionsMergeToTheWhole(scene, scene.rigs[0], FieldNames());
}

TEST(FieldEvaluator, PartitionsMergeToTheWholeOnTheTraumaRoom) {
  Scene scene = LoadScene("examples/trauma_room/scene.json");
  scene.study.voxel_size = 0.008;
  ExpectPartitionsMergeToTheWhole(scene, scene.FindRig("octagon"), scene.study.fields);
}

TEST(FieldEvaluator, PartitionBlocksCoversEveryBlockOnceWithinTheLptBound) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Block> blocks(1 + rng() % 300);
    std::vector<std::vector<std::int32_t>> candidates(blocks.size());
    std::int64_t total = 0, largest = 0;
    std::vector<std::int64_t> cost(blocks.size());
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      blocks[b].free_voxels = 1 + int(rng() % 512);
      candidates[b].resize(rng() % 3 == 0 ? 0 : rng() % 24);
      cost[b] = std::int64_t(blocks[b].free_voxels) * std::int64_t(candidates[b].size() + 1) + 64;
      total += cost[b];
      largest = std::max(largest, cost[b]);
    }
    const int count = 1 + int(rng() % 8);
    std::vector<int> owners(blocks.size(), 0);
    std::int64_t worst = 0;
    for (int rank = 0; rank < count; ++rank) {
      const std::vector<std::uint8_t> mine = PartitionBlocks(blocks, candidates, count, rank);
      std::int64_t load = 0;
      for (std::size_t b = 0; b < blocks.size(); ++b)
        if (mine[b]) ++owners[b], load += cost[b];
      worst = std::max(worst, load);
    }
    for (int o : owners) ASSERT_EQ(o, 1);
    const double best_bound = std::max(double(total) / count, double(largest));
    EXPECT_LE(double(worst), 4.0 / 3.0 * best_bound + 1e-9) << trial;
  }
  EXPECT_THROW(PartitionBlocks({}, {}, 0, 0), std::logic_error);
  EXPECT_THROW(PartitionBlocks({}, {}, 2, 2), std::logic_error);
}

}  // namespace
}  // namespace pandora
