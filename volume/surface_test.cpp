// Surface samples: area-weighted uniform sampling (counts, positions on the triangles, normals,
// uniformity, determinism), per-sample values equal to the volume grids at voxel centres and to an
// independent brute-force loop on surfaces (back faces excluded), slices, and the PLY file read
// back byte by byte.
#include "volume/surface.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "analysis/geometry/primitives.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "tests/fixtures.h"
#include "tests/random_scene.h"
#include "volume/fields_vdb.h"
#include "volume/slice.h"

namespace pandora {
namespace {

// A 640 x 480 camera (tests/fixtures.h) with a working range of 5 cm to 20 m and an optional k1.
Camera MakeCamera(const std::string& id, const Vec3& position, const Vec3& target, double hfov_deg,
                  LensModel model = LensModel::kPinhole, double k1 = 0) {
  Camera cam =
      testing::WithIntrinsics(testing::TestCamera(id, position, target, hfov_deg, 640, 480, model),
                              [&](Intrinsics& k) { k.k1 = k1; });
  cam.near = 0.05;
  cam.far = 20;
  return cam;
}

// A floor sheet, a solid ball and a solid post; five cameras (one below the floor, one with
// distortion, one looking away).
Scene TestScene() {
  Scene scene;
  scene.path = "test.json";
  scene.objects.push_back(
      testing::TestObject("floor", MakePlane(Vec2(2.0, 2.0)), Vec3(0, 0, -0.01), false));
  scene.objects.push_back(
      testing::TestObject("ball", MakeSphere(0.3, 24), Vec3(0.1, 0.0, 0.35), true));
  scene.objects.push_back(
      testing::TestObject("post", MakeBox(Vec3(0.1, 0.1, 1.5)), Vec3(-0.5, 0.6, 0), true));
  Rig rig;
  rig.name = "mixed";
  rig.cameras.push_back(MakeCamera("c0", Vec3(3, 0, 1.5), Vec3(0, 0, 0), 50));
  rig.cameras.push_back(
      MakeCamera("c1", Vec3(0, 3, 2), Vec3(0, 0, 0), 70, LensModel::kBrownConrady, -0.2));
  rig.cameras.push_back(MakeCamera("c2", Vec3(-2, -2, 1.5), Vec3(0, 0, 0.2), 80));
  rig.cameras.push_back(
      MakeCamera("c3", Vec3(0.2, 0.1, -2), Vec3(0, 0, 0), 60));                   // below the floor
  rig.cameras.push_back(MakeCamera("c4", Vec3(-3, 0, 0.5), Vec3(-4, 0, 0), 60));  // looks away
  rig.cameras[1].pixel_sigma = 0.8;
  scene.rigs.push_back(rig);
  scene.study.region.box.min = Vec3(-1, -1, 0.0);
  scene.study.region.box.max = Vec3(1, 1, 0.8);
  scene.study.voxel_size = 0.05;
  return scene;
}

TEST(SurfaceSampling, CountsPositionsNormalsAndDeterminism) {
  const Scene scene = TestScene();
  const double spacing = 0.03;
  const std::vector<SurfaceSample> samples = SampleSurfaces(scene, spacing, 7);
  // Per triangle: floor(A / h^2) or one more.
  std::map<std::pair<int, int>, int> per_triangle;
  for (const SurfaceSample& s : samples) {
    ASSERT_GE(s.object, 0);
    const TriangleMesh& mesh = scene.objects[s.object].mesh;
    // Which triangle holds the point: barycentric coordinates all >= 0 and distance 0.
    int found = -1;
    for (std::size_t t = 0; t < mesh.triangles.size() && found < 0; ++t) {
      const Vec3& a = mesh.vertices[mesh.triangles[t][0]];
      const Vec3& b = mesh.vertices[mesh.triangles[t][1]];
      const Vec3& c = mesh.vertices[mesh.triangles[t][2]];
      const Vec3 n = (b - a).cross(c - a);
      if (n.norm() == 0) continue;
      const Vec3 unit = n.normalized();
      if (std::abs(unit.dot(s.position - a)) > 1e-12) continue;
      const double area2 = n.norm();
      const double u = (c - b).cross(s.position - b).dot(unit) / area2;
      const double v = (a - c).cross(s.position - c).dot(unit) / area2;
      const double w = 1 - u - v;
      if (u < -1e-12 || v < -1e-12 || w < -1e-12) continue;
      if ((unit - s.normal).norm() > 1e-12) continue;  // the normal is that triangle's
      found = static_cast<int>(t);
    }
    ASSERT_GE(found, 0) << "sample not on a triangle of its object with that normal";
    ++per_triangle[{s.object, found}];
    EXPECT_NEAR(s.normal.norm(), 1.0, 1e-12);
  }
  double expected_total = 0, variance = 0;
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const TriangleMesh& mesh = scene.objects[o].mesh;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Vec3& a = mesh.vertices[mesh.triangles[t][0]];
      const double e = 0.5 *
                       (mesh.vertices[mesh.triangles[t][1]] - a)
                           .cross(mesh.vertices[mesh.triangles[t][2]] - a)
                           .norm() /
                       (spacing * spacing);
      const int got = per_triangle[{int(o), int(t)}];
      EXPECT_TRUE(got == std::floor(e) || got == std::floor(e) + 1) << o << " " << t << " " << e;
      expected_total += e;
      variance += (e - std::floor(e)) * (1 - (e - std::floor(e)));
    }
  }
  EXPECT_NEAR(SurfaceArea(scene) / (spacing * spacing), expected_total, 1e-9 * expected_total);
  EXPECT_LE(std::abs(double(samples.size()) - expected_total), 5 * std::sqrt(variance) + 1);

  // Same seed, same samples; another seed, other positions.
  const std::vector<SurfaceSample> again = SampleSurfaces(scene, spacing, 7);
  ASSERT_EQ(again.size(), samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i)
    ASSERT_EQ(again[i].position, samples[i].position);
  const std::vector<SurfaceSample> other = SampleSurfaces(scene, spacing, 8);
  ASSERT_FALSE(other.empty());
  EXPECT_NE(other[0].position, samples[0].position);
}

TEST(SurfaceSampling, UniformOverAPlane) {
  // A 1 m square (two triangles): counts in 5 x 5 cells against a uniform density, chi-square with
  // 24 degrees of freedom below its 0.999 quantile (51.2). Sampling without the square root in the
  // barycentric map crowds the points towards one corner and fails this by far.
  Scene scene;
  scene.objects.push_back(
      testing::TestObject("plane", MakePlane(Vec2(1.0, 1.0)), Vec3(0, 0, 0), false));
  const std::vector<SurfaceSample> samples = SampleSurfaces(scene, 0.01, 3);
  ASSERT_NEAR(double(samples.size()), 10000.0, 3.0);
  std::vector<double> cells(25, 0.0);
  for (const SurfaceSample& s : samples) {
    const int i = std::clamp(int((s.position.x() + 0.5) * 5), 0, 4);
    const int j = std::clamp(int((s.position.y() + 0.5) * 5), 0, 4);
    cells[i * 5 + j] += 1;
    EXPECT_NEAR(s.normal.z(), 1.0, 1e-12);
  }
  const double expect = samples.size() / 25.0;
  double chi2 = 0;
  for (double c : cells) chi2 += (c - expect) * (c - expect) / expect;
  EXPECT_LT(chi2, 51.2);
}

// The default of `pandora export-surface`: only triangles whose front faces the region or a camera.
// A unit cube beside the region (x in [2, 3]; the region is [-1, 1]^3) shows it five faces: every
// one but the far face x = 3, whose front (+x) has no region point before it; a camera at x = 4
// brings that face back. Sheets (single-sided planes) facing into a room are kept, facing out not.
TEST(SurfaceSampling, FacingKeepsTheSidesTheRegionOrACameraCanSee) {
  Scene scene;
  scene.objects.push_back(
      testing::TestObject("cube", MakeBox(Vec3(1, 1, 1)), Vec3(2.5, 0, 0), true));
  scene.study.region.box.min = Vec3(-1, -1, -1);
  scene.study.region.box.max = Vec3(1, 1, 1);
  EXPECT_NEAR(SurfaceArea(scene, SurfaceSelection::kAll), 6.0, 1e-12);
  EXPECT_NEAR(SurfaceArea(scene, SurfaceSelection::kFacing), 5.0, 1e-12);
  const double spacing = 0.05;
  const std::vector<SurfaceSample> all = SampleSurfaces(scene, spacing, 5);
  const std::vector<SurfaceSample> facing =
      SampleSurfaces(scene, spacing, 5, "{spacing}", SurfaceSelection::kFacing);
  // Exactly the samples of `all` that are not on the far face, in the same order.
  std::vector<SurfaceSample> expected;
  for (const SurfaceSample& x : all)
    if (!(x.normal.x() > 0.5)) expected.push_back(x);
  ASSERT_EQ(facing.size(), expected.size());
  EXPECT_LT(facing.size(), all.size());
  for (std::size_t i = 0; i < facing.size(); ++i) {
    EXPECT_EQ(facing[i].position, expected[i].position);
    EXPECT_LT(facing[i].normal.x(), 0.5);
  }
  Rig rig;
  rig.cameras.push_back(MakeCamera("behind", Vec3(4, 0, 0), Vec3(2.5, 0, 0), 60));
  EXPECT_NEAR(SurfaceArea(scene, SurfaceSelection::kFacing, &rig), 6.0, 1e-12);
  rig.cameras[0].enabled = false;  // a disabled camera does not count
  EXPECT_NEAR(SurfaceArea(scene, SurfaceSelection::kFacing, &rig), 5.0, 1e-12);

  // Sheets (normal +z from counter-clockwise corners) against a room region [-1, 1]^2 x [0, 2].
  Region room;
  room.box.min = Vec3(-1, -1, 0);
  room.box.max = Vec3(1, 1, 2);
  const Vec3 a(-3, -3, 0), b(3, -3, 0), c(3, 3, 0), up(0, 0, 3);
  EXPECT_TRUE(FacesRegionOrViewpoints(room, {}, a, b, c));                  // the floor, facing up
  EXPECT_FALSE(FacesRegionOrViewpoints(room, {}, a, c, b));                 // its underside
  EXPECT_FALSE(FacesRegionOrViewpoints(room, {}, a + up, b + up, c + up));  // a ceiling's top
  EXPECT_TRUE(FacesRegionOrViewpoints(room, {}, a + up, c + up, b + up));   // its underside
  // Touching the region's top face from above, facing away: no point strictly in front.
  const Vec3 top(0, 0, 2);
  EXPECT_FALSE(FacesRegionOrViewpoints(room, {}, a + top, b + top, c + top));
  EXPECT_TRUE(FacesRegionOrViewpoints(room, {Vec3(0, 0, 2.5)}, a + top, b + top, c + top));
}

// No sample a camera sees is dropped: on the test scene (floor sheet, ball, post, five cameras, one
// below the floor) plus a crate beside the region, whose far side neither the region nor a camera
// faces, the facing selection drops samples, yet its seen samples are exactly those of all.
TEST(SurfaceSampling, FacingDropsNoSeenSample) {
  Scene scene = TestScene();
  scene.objects.push_back(
      testing::TestObject("crate", MakeBox(Vec3(1, 1, 1)), Vec3(0, -3, 0.5), true));
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const PointEvaluator evaluator(scene, rig, *caster);
  auto seen = [&](const std::vector<SurfaceSample>& samples) {
    std::vector<Vec3> out;
    const std::vector<PointValues> v = evaluator.EvaluateSamples(samples);
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (v[i].coverage > 0) out.push_back(samples[i].position);
    return out;
  };
  const std::vector<SurfaceSample> all = SampleSurfaces(scene, 0.03, 2);
  const std::vector<SurfaceSample> facing =
      SampleSurfaces(scene, 0.03, 2, "{spacing}", SurfaceSelection::kFacing, &rig);
  EXPECT_LT(facing.size() + 900, all.size());  // the crate's far side: 1 m^2 = 1111 samples
  const std::vector<Vec3> a = seen(all), f = seen(facing);
  EXPECT_GT(a.size(), 100u);
  EXPECT_EQ(a, f);
}

TEST(SurfaceSampling, BadSpacingIsAnInputError) {
  const Scene scene = TestScene();
  for (double bad : {0.0, -0.1, std::nan(""), std::numeric_limits<double>::infinity()}) {
    try {
      SampleSurfaces(scene, bad);
      FAIL() << "no error for spacing " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "{spacing}");
    }
  }
  try {
    SampleSurfaces(scene, 1e-5);
    FAIL() << "no error for 1e-5 m";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("over the limit"), std::string::npos) << e.what();
  }
}

TEST(PointEvaluator, EqualsTheVolumeGridsAtVoxelCentres) {
  Scene scene = TestScene();
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "cameras", "resolution", "sigma_max"};
  const Fields fields = EvaluateFields(scene, rig, *caster, options);
  const PointEvaluator evaluator(scene, rig, *caster);
  const Fields::Impl& g = fields.impl();
  auto cov = g.coverage->getConstAccessor();
  // The cameras that see voxel c, from the per-camera grids.
  const auto cameras_at = [&](const openvdb::Coord& c) {
    std::vector<std::int32_t> seen;
    for (std::size_t k = 0; k < g.visible.size(); ++k)
      if (g.visible[k]->tree().isValueOn(c)) seen.push_back(static_cast<std::int32_t>(k));
    return seen;
  };
  auto res = g.Float("resolution")->getConstAccessor();
  auto sig = g.Float("sigma_max")->getConstAccessor();
  std::int64_t checked = 0, triangulable = 0;
  float worst_resolution = 0, worst_sigma = 0;
  for (auto it = g.coverage->cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto ijk = box.begin(); ijk; ++ijk) {
      const openvdb::Coord c = *ijk;
      const PointValues v = evaluator.Evaluate(fields.lattice.Center(c.x(), c.y(), c.z()));
      ++checked;
      ASSERT_EQ(v.coverage, cov.getValue(c)) << c;
      if (v.coverage == 0) {
        EXPECT_TRUE(cameras_at(c).empty());
        continue;
      }
      ASSERT_EQ(v.cameras, cameras_at(c)) << c;
      // Same maths, stored as float: equal to within 2 float ulps (exactly equal today; the
      // margin lets the fields' hot loop reorder its arithmetic).
      const float r = res.getValue(c);
      worst_resolution = std::max(worst_resolution, std::abs(float(v.resolution) - r) / r);
      ASSERT_NEAR(float(v.resolution), r, 2.4e-7f * r) << c;
      ASSERT_EQ(v.triangulable, sig.isValueOn(c)) << c;
      if (v.triangulable) {
        ++triangulable;
        const float g = sig.getValue(c);
        worst_sigma = std::max(worst_sigma, std::abs(float(v.sigma_max_mm) - g) / g);
        ASSERT_NEAR(float(v.sigma_max_mm), g, 2.4e-7f * g) << c;
      }
    }
  }
  std::printf("voxel centres: %lld, largest relative difference resolution %.3g, sigma_max %.3g\n",
              static_cast<long long>(checked), worst_resolution, worst_sigma);
  EXPECT_EQ(checked, fields.stats.active_set.region_voxels);
  EXPECT_EQ(triangulable, fields.stats.triangulable_voxels);
  EXPECT_GT(triangulable, 1000);
}

// The reference for a surface point, written from the rules (docs/fields.md) with the
// double-precision brute-force caster: in front of the lens and in the image, within range, the
// normal facing the camera, the segment (shortened by the tolerance of docs/accuracy.md at both
// ends, VisibilityTester::Tolerance) free; the information
// matrix through InformationBuilder and the covariance through StaticFromInformation.
PointValues Reference(const Scene& scene, const Rig& rig, const RayCaster& brute, const Vec3& X,
                      const Vec3& n) {
  const VisibilityTester rules(rig.cameras, brute, scene.ContentBounds().diagonal());
  PointValues v;
  InformationBuilder builder;
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& cam = rig.cameras[c];
    const Vec3 d = X - cam.center();
    if (!cam.enabled || d.norm() < cam.near || d.norm() > cam.far) continue;
    Mat23 A;
    const auto px = cam.Project(X, &A);
    if (!px || !cam.model.InImage(*px)) continue;
    if (n.dot(-d) <= 0) continue;
    Ray ray;
    ray.origin = cam.center();
    ray.direction = d.normalized();
    ray.t_near = rules.Tolerance(static_cast<int>(c), d.norm());
    ray.t_far = d.norm() - ray.t_near;
    if (brute.Occluded(ray)) continue;
    ++v.coverage;
    v.cameras.push_back(static_cast<std::int32_t>(c));
    v.resolution = std::max(v.resolution, PixelDensity(A));
    const double sigma = cam.pixel_sigma > 0 ? cam.pixel_sigma : scene.study.pixel_sigma;
    builder.Add(A, sigma);
  }
  const StaticUncertainty u = StaticFromInformation(builder.Decompose(), v.coverage);
  v.triangulable = u.triangulable;
  v.sigma_max_mm = u.sigma_max * 1e3;
  return v;
}

TEST(PointEvaluator, SurfaceSamplesMatchABruteForceLoop) {
  const Scene scene = TestScene();
  const Rig& rig = scene.rigs[0];
  const TriangleMesh all = scene.AllTriangles();
  const auto brute = MakeBruteForceRayCaster(all);
  const auto embree = MakeEmbreeRayCaster(all);
  const std::vector<SurfaceSample> samples = SampleSurfaces(scene, 0.06, 11);
  ASSERT_GT(samples.size(), 1000u);
  const std::vector<PointValues> values =
      PointEvaluator(scene, rig, *embree).EvaluateSamples(samples);
  ASSERT_EQ(values.size(), samples.size());
  std::size_t mismatched = 0, triangulable = 0, floor_seen_from_below = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const PointValues ref = Reference(scene, rig, *brute, samples[i].position, samples[i].normal);
    const PointValues& v = values[i];
    if (v.cameras != ref.cameras) {
      // Embree (single precision) against double precision: each camera that differs must be
      // explained by the tolerance (docs/accuracy.md): a segment passing within it of a triangle
      // edge or ending within it of another triangle, or a surface seen within 0.6 degrees of its
      // own plane.
      ++mismatched;
      const VisibilityTester rules(rig.cameras, *brute, scene.ContentBounds().diagonal());
      for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
        if (v.Sees(int(c)) == ref.Sees(int(c))) continue;
        Ray seg;
        ASSERT_EQ(
            rules.TestGeometry(static_cast<int>(c), samples[i].position, &samples[i].normal, &seg),
            ViewResult::kSeen);
        const Vec3 a = seg.origin + seg.t_near * seg.direction;
        const Vec3 b = seg.origin + seg.t_far * seg.direction;
        const bool shallow = std::abs(samples[i].normal.normalized().dot(seg.direction)) < 0.01;
        EXPECT_TRUE(shallow || testing::IsGrazing(all, a, b, seg.t_near))
            << "sample " << i << " camera " << c << " is neither grazing nor shallow";
      }
      continue;
    }
    if (samples[i].object == 0 && v.Sees(3)) ++floor_seen_from_below;
    ASSERT_EQ(v.coverage, ref.coverage);
    ASSERT_NEAR(v.resolution, ref.resolution, 1e-6 * ref.resolution + 1e-9);
    ASSERT_EQ(v.triangulable, ref.triangulable);
    if (ref.triangulable) {
      ++triangulable;
      ASSERT_NEAR(v.sigma_max_mm, ref.sigma_max_mm, 1e-9 * ref.sigma_max_mm);
    }
  }
  std::printf("surface samples: %zu, visibility differing from the double-precision loop: %zu\n",
              samples.size(), mismatched);
  EXPECT_LE(mismatched, samples.size() / 200) << "of " << samples.size();
  EXPECT_GT(triangulable, samples.size() / 4);
  // The floor faces up: the camera under it never sees it (its voxel-centre view would).
  EXPECT_EQ(floor_seen_from_below, 0u);
  const PointEvaluator eval(scene, rig, *embree);
  const Vec3 on_floor(0.5, -0.5, -0.01), up(0, 0, 1);
  EXPECT_FALSE(eval.Evaluate(on_floor, &up).Sees(3));
  EXPECT_TRUE(eval.Evaluate(on_floor).Sees(3));
}

TEST(PointEvaluator, TwoOrthogonalPinholesClosedForm) {
  // Two ideal pinholes at distance d on the x and y axes looking at the origin: camera 0 constrains
  // y and z with f/d px/m each, camera 1 x and z, so J = diag(1, 1, 2) (f/d)^2 / sigma^2 and the
  // worst direction has sigma = d sigma / f; resolution is f/d.
  Scene scene;
  Rig rig;
  const double d = 2.0, sigma = 0.5;
  rig.cameras.push_back(MakeCamera("x", Vec3(d, 0, 0), Vec3(0, 0, 0), 60));
  rig.cameras.push_back(MakeCamera("y", Vec3(0, d, 0), Vec3(0, 0, 0), 60));
  scene.rigs.push_back(rig);
  scene.study.pixel_sigma = sigma;
  scene.objects.push_back(
      testing::TestObject("far", MakeBox(Vec3(0.1, 0.1, 0.1)), Vec3(5, 5, 5), true));
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const PointValues v = PointEvaluator(scene, rig, *caster).Evaluate(Vec3::Zero());
  const double f = rig.cameras[0].model.intrinsics().fx;
  EXPECT_EQ(v.coverage, 2);
  EXPECT_TRUE(v.triangulable);
  EXPECT_NEAR(v.resolution, f / d, 1e-4 * f / d);  // stored as float
  EXPECT_NEAR(v.sigma_max_mm, 1e3 * d * sigma / f, 1e-9 * v.sigma_max_mm);
}

TEST(SurfacePly, HeaderAndRecordsReadBack) {
  const Scene scene = TestScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const std::vector<SurfaceSample> samples = SampleSurfaces(scene, 0.1, 1);
  const std::vector<PointValues> values =
      PointEvaluator(scene, scene.rigs[0], *caster).EvaluateSamples(samples);
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("surface_test_" + std::to_string(::getpid()) + ".ply"))
                               .string();
  WriteSurfacePly(path, samples, values, 4, {"units: metres", "two\nlines"});
  EXPECT_FALSE(std::filesystem::exists(TemporaryPath(path)));
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string file = ss.str();
  std::filesystem::remove(path);
  const std::size_t end = file.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = file.substr(0, end);
  const std::string start =
      "ply\nformat binary_little_endian 1.0\ncomment units: metres\n"
      "comment two lines\nelement vertex " +
      std::to_string(samples.size()) + "\n";
  EXPECT_EQ(header.rfind(start, 0), 0u) << header;
  for (const char* p :
       {"property float x\n", "property float nz\n", "property uchar red\n",
        "property float coverage\n", "property float resolution\n", "property float sigma_max\n",
        "property uchar triangulable\n", "property int object\n"})
    EXPECT_NE(header.find(p), std::string::npos) << p;
  const std::size_t record = 24 + 3 + 12 + 1 + 4;
  const char* data = file.data() + end + std::strlen("end_header\n");
  ASSERT_EQ(file.size() - (data - file.data()), record * samples.size());
  int seen = 0, tri = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const char* r = data + i * record;
    float f[6];
    std::memcpy(f, r, 24);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(f[k], static_cast<float>(samples[i].position[k]));
    for (int k = 0; k < 3; ++k) ASSERT_EQ(f[3 + k], static_cast<float>(samples[i].normal[k]));
    const unsigned char* rgb = reinterpret_cast<const unsigned char*>(r + 24);
    float cov, res, sig;
    std::memcpy(&cov, r + 27, 4);
    std::memcpy(&res, r + 31, 4);
    std::memcpy(&sig, r + 35, 4);
    const unsigned char flag = static_cast<unsigned char>(r[39]);
    std::int32_t object;
    std::memcpy(&object, r + 40, 4);
    ASSERT_EQ(cov, values[i].coverage);
    ASSERT_EQ(res, static_cast<float>(values[i].resolution));
    ASSERT_TRUE(std::isfinite(sig));
    ASSERT_EQ(flag, values[i].triangulable ? 1 : 0);
    ASSERT_EQ(sig, values[i].triangulable ? static_cast<float>(values[i].sigma_max_mm) : 0.0f);
    ASSERT_EQ(object, samples[i].object);
    if (values[i].coverage == 0) {
      ASSERT_EQ(rgb[0], 128);
      ASSERT_EQ(rgb[1], 128);
      ASSERT_EQ(rgb[2], 128);
    } else {
      const Rgb8 c = Viridis(values[i].coverage / 4.0);
      ASSERT_EQ(rgb[0], c.r);
      ASSERT_EQ(rgb[2], c.b);
      ++seen;
    }
    tri += flag;
  }
  EXPECT_GT(seen, 0);
  EXPECT_GT(tri, 0);
}

TEST(FieldSlice, PicksTheNearestPlaneAndMarksTheRegion) {
  const Scene scene = TestScene();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "resolution", "sigma_max"};
  const Fields fields = EvaluateFields(scene, scene.rigs[0], *caster, options);
  const FieldSlice s = SliceField(fields, "coverage", 2, 0.351);
  EXPECT_EQ(s.index, 7);  // centres at z = 0.025 + 0.05 k: 0.375 is the nearest
  EXPECT_NEAR(s.coordinate, 0.375, 1e-12);
  EXPECT_EQ(s.width, fields.lattice.dims.x());
  EXPECT_EQ(s.height, fields.lattice.dims.y());
  auto cov = fields.impl().coverage->getConstAccessor();
  int solid = 0;
  for (int row = 0; row < s.height; ++row)
    for (int col = 0; col < s.width; ++col) {
      const openvdb::Coord c(col, s.height - 1 - row, 7);
      const std::size_t o = std::size_t(row) * s.width + col;
      ASSERT_EQ(bool(s.inside[o]), cov.isValueOn(c));
      if (s.inside[o]) {
        ASSERT_EQ(s.values[o], cov.getValue(c));
      }
      solid += !s.inside[o];
    }
  EXPECT_GT(solid, 20);                                            // the ball's cross-section
  const FieldSlice y = SliceField(fields, "sigma_max", 1, 100.0);  // clamped to the last plane
  EXPECT_EQ(y.index, fields.lattice.dims.y() - 1);
  EXPECT_EQ(y.width, fields.lattice.dims.x());
  EXPECT_EQ(y.height, fields.lattice.dims.z());
  EXPECT_THROW(SliceField(fields, "cameras", 2, 0.0), std::invalid_argument);
  // Without clamping, a plane beyond the lattice has no value anywhere.
  const FieldSlice off = SliceField(fields, "sigma_max", 1, 100.0, false);
  EXPECT_EQ(off.index, -1);
  EXPECT_EQ(std::count(off.has_value.begin(), off.has_value.end(), 1), 0);
  EXPECT_TRUE(std::isnan(off.Sample(Vec3(0, 100.0, 0.3))));

  // Sample: every world point inside a voxel's cell reads that voxel; its range is min / max.
  const FieldSlice r = SliceField(fields, "resolution", 2, 0.351);
  auto res = fields.impl().Float("resolution")->getConstAccessor();
  const VoxelLattice& L = fields.lattice;
  double lo = 1e300, hi = -1e300;
  int valued = 0;
  for (int i = 0; i < L.dims.x(); ++i)
    for (int j = 0; j < L.dims.y(); ++j) {
      const Vec3 centre = L.Center(i, j, 7);
      for (const Vec3& d : {Vec3(0, 0, 0), Vec3(0.49, -0.49, 3), Vec3(-0.49, 0.49, -2)}) {
        const double v = r.Sample(centre + L.voxel_size * d);  // the z offset is projected away
        float expected = 0;
        if (res.probeValue(openvdb::Coord(i, j, 7), expected)) {
          ASSERT_EQ(v, expected) << i << " " << j;
        } else {
          ASSERT_TRUE(std::isnan(v)) << i << " " << j;
        }
      }
      float value = 0;
      if (res.probeValue(openvdb::Coord(i, j, 7), value)) {
        lo = std::min<double>(lo, value);
        hi = std::max<double>(hi, value);
        ++valued;
      }
    }
  ASSERT_GT(valued, 0);
  EXPECT_EQ(r.min, lo);
  EXPECT_EQ(r.max, hi);
  EXPECT_TRUE(std::isnan(r.Sample(L.Center(0, 0, 7) - Vec3(L.voxel_size, 0, 0))));  // outside
}

}  // namespace
}  // namespace pandora
