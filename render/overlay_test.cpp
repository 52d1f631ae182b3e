// Field overlays: slice colours against the grid values read directly through OpenVDB, isosurface
// vertices against the coverage change they must bracket, and ReadFieldsVdb's round trip.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "analysis/geometry/primitives.h"
#include "analysis/util/units.h"
#include "render/colormap.h"
#include "render/overlay_fields.h"
#include "render/render.h"
#include "tests/fixtures.h"
#include "volume/fields_vdb.h"
#include "volume/surface.h"
#include "volume/vdb_io.h"

namespace pandora {
namespace {

Camera DownCamera(const std::string& id, const Vec3& from, const Vec3& at, const Vec3& color) {
  Camera c = testing::TestCamera(id, from, at, 50, 64, 48, LensModel::kPinhole, Vec3(0, 1, 0));
  c.color = color;
  return c;
}

struct FieldScene {
  Scene scene;
  std::unique_ptr<RayCaster> caster;
  Fields fields;
};

FieldScene MakeSetup() {
  FieldScene s;
  s.scene.path = "overlay_test.json";
  SceneObject floor;
  floor.name = "floor";
  floor.mesh = MakePlane(Vec2(6, 6));
  s.scene.objects.push_back(floor);
  Rig rig;
  rig.name = "two";
  rig.cameras.push_back(DownCamera("a", Vec3(-0.4, 0, 2.5), Vec3(-0.2, 0, 0), Vec3(1, 0, 0)));
  rig.cameras.push_back(DownCamera("b", Vec3(0.4, 0, 2.5), Vec3(0.2, 0, 0), Vec3(0, 0, 1)));
  s.scene.rigs.push_back(rig);
  s.scene.study.region.kind = Region::Kind::kBox;
  s.scene.study.region.box.min = Vec3(-1.2, -0.8, 0.2);
  s.scene.study.region.box.max = Vec3(1.2, 0.8, 1.4);
  s.scene.study.voxel_size = 0.05;
  s.caster = MakeEmbreeRayCaster(s.scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage", "resolution"};
  s.fields = EvaluateFields(s.scene, rig, *s.caster, options);
  return s;
}

TEST(Overlay, SliceShowsTheVoxelValueWhereTheEyeRayCrossesThePlane) {
  FieldScene s = MakeSetup();
  const Rig& rig = s.scene.rigs[0];
  RenderView view;
  view.from = Vec3(0.3, -2.5, 3.0);
  view.at = Vec3(0, 0, 0.5);
  view.fov_deg = 60;
  view.width = 96;
  view.height = 64;
  RenderOptions options;
  options.surface = Surface::kBlack;
  options.background = Vec3::Zero();
  options.brightness = 1e-12;  // the floor's light vanishes next to the slice's colour
  options.overlays.cameras = false;
  options.overlays.slice_field = "coverage";
  options.overlays.slice_axis = 2;
  options.overlays.slice_position = 0.825;  // a voxel layer's centres (0.225 + 12 * 0.05)
  options.overlays.slice_min = 0;
  options.overlays.slice_max = 2;
  options.overlays.slice_opacity = 0.75;
  options.overlays.legend = false;
  options.overlays.key = false;
  const Image img = Render(s.scene, rig, *s.caster, view, options, &s.fields);
  const openvdb::Int32Grid& grid = *s.fields.impl().coverage;
  auto acc = grid.getConstAccessor();
  const Eigen::Isometry3d pose = *LookAt(view.from, view.at, view.up);
  const double f = 0.5 * view.width / std::tan(0.5 * view.fov_deg * kPi / 180.0);
  int checked = 0, per_value[3] = {0, 0, 0};
  for (int y = 0; y < view.height; ++y)
    for (int x = 0; x < view.width; ++x) {
      const Vec3 d = (pose.linear() * Vec3((x - 47.5) / f, (y - 31.5) / f, 1)).normalized();
      const double t = (0.825 - view.from.z()) / d.z();
      const Vec3 P = view.from + t * d;
      const openvdb::Vec3d ijk = grid.transform().worldToIndex(openvdb::Vec3d(P.x(), P.y(), P.z()));
      // Skip points within 1e-6 voxels of a cell border, where rounding may go either way.
      bool border = false;
      for (int k : {0, 1}) border |= std::abs(ijk[k] - std::floor(ijk[k]) - 0.5) < 1e-6;
      if (border) continue;
      const openvdb::Coord c(int(std::lround(ijk[0])), int(std::lround(ijk[1])),
                             int(std::lround(ijk[2])));
      int value = 0;
      const Vec3 rgb = img.Rgb(x, y);
      if (!acc.probeValue(c, value)) {
        EXPECT_LT(rgb.maxCoeff(), 1e-6) << x << "," << y;  // no slice outside the fields
        continue;
      }
      const Vec3 expected = 0.75 * ViridisLinear(value / 2.0);
      EXPECT_LT((rgb - expected).cwiseAbs().maxCoeff(), 1e-5)
          << x << "," << y << " value " << value;
      ++checked;
      ++per_value[std::min(value, 2)];
    }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(per_value[0], 50);
  EXPECT_GT(per_value[1], 50);
  EXPECT_GT(per_value[2], 50);
}

TEST(Overlay, IsosurfaceBracketsTheCoverageChange) {
  FieldScene s = MakeSetup();
  const TriangleMesh iso = ExtractIsosurface(s.fields, "coverage", 1.5);
  ASSERT_GT(iso.triangles.size(), 100u);
  const openvdb::Int32Grid& grid = *s.fields.impl().coverage;
  auto acc = grid.getConstAccessor();
  // Each vertex lies on a lattice edge (or inside a cell) whose corners straddle 1.5: within the
  // 2x2x2 voxel centres around it there is one with coverage >= 2 and one below (inactive: 0).
  int straddling = 0;
  for (const Vec3& v : iso.vertices) {
    const openvdb::Vec3d ijk = grid.transform().worldToIndex(openvdb::Vec3d(v.x(), v.y(), v.z()));
    const openvdb::Coord base(int(std::floor(ijk[0])), int(std::floor(ijk[1])),
                              int(std::floor(ijk[2])));
    bool high = false, low = false;
    for (int dz = 0; dz <= 1; ++dz)
      for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx) {
          int value = 0;
          acc.probeValue(base.offsetBy(dx, dy, dz), value);
          (value >= 2 ? high : low) = true;
        }
    straddling += high && low;
  }
  EXPECT_EQ(straddling, int(iso.vertices.size()));
  // Nothing above the camera plane or below the region.
  const Aabb b = iso.Bounds();
  EXPECT_GE(b.min.z(), 0.2 - 0.05 - 1e-9);
  EXPECT_LE(b.max.z(), 1.4 + 0.05 + 1e-9);
}

TEST(Overlay, FieldsVdbRoundTrip) {
  FieldScene s = MakeSetup();
  const std::string path = ::testing::TempDir() + "/overlay_fields.vdb";
  WriteFieldsVdb(s.fields, path, {{"tool", "test"}});
  const Fields back = ReadFieldsVdb(path);
  ASSERT_TRUE(back.impl().coverage);
  ASSERT_TRUE(back.impl().Float("resolution"));
  EXPECT_TRUE(back.impl().visible.empty());
  EXPECT_EQ(back.impl().coverage->activeVoxelCount(), s.fields.impl().coverage->activeVoxelCount());
  EXPECT_NEAR(back.lattice.voxel_size, 0.05, 1e-12);
  EXPECT_LT((back.lattice.origin - s.fields.lattice.origin).norm(), 1e-9);
  // Values agree voxel by voxel.
  auto a = s.fields.impl().Float("resolution")->getConstAccessor();
  for (auto it = back.impl().Float("resolution")->cbeginValueOn(); it; ++it)
    EXPECT_EQ(*it, a.getValue(it.getCoord()));
  // Slices of the original and the copy are identical.
  double plane1 = 0, plane2 = 0;
  const FieldSlice s1 = SampleSlice(s.fields, "resolution", 0, 0.1, &plane1);
  const FieldSlice s2 = SampleSlice(back, "resolution", 0, 0.1, &plane2);
  EXPECT_EQ(plane1, 0.1);
  EXPECT_EQ(plane2, 0.1);
  ASSERT_EQ(s1.values.size(), s2.values.size());
  EXPECT_EQ(s1.has_value, s2.has_value);
  EXPECT_EQ(s1.values, s2.values);
}

// The EXR layers of a trauma-room render, read back through OpenEXR, against the field maths at the
// surface points the pixels show (PointEvaluator: the visibility rules with the surface normal, the
// information matrix and eigenvalues exactly as EvaluateFields computes them). Each sampled pixel's
// centre ray is rebuilt from the view (renderer convention: pixel centres at integer coordinates,
// horizontal field of view across the full width) and checked against the EXR depth first.
TEST(Render, ExrLayersMatchTheFieldValuesAtSampledPixels) {
  const Scene scene = LoadScene("examples/trauma_room/scene.json");
  const Rig& rig = scene.FindRig("octagon");
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const RenderView view = ViewFromScene(scene.views.at("overview"), 160, 90);
  RenderOptions options;
  options.surface = Surface::kBlack;
  options.overlays.cameras = false;
  options.pixel_sigma = scene.study.pixel_sigma;
  const Image rendered = Render(scene, rig, *caster, view, options);
  const std::string path = ::testing::TempDir() + "/pandora_layers.exr";
  WriteExr(rendered, path, static_cast<int>(rig.cameras.size()));
  const Image image = ReadExr(path);
  std::remove(path.c_str());
  ASSERT_EQ(image.width, 160);
  ASSERT_EQ(image.height, 90);

  const PointEvaluator evaluator(scene, rig, *caster);
  const Mat3 R = LookAt(view.from, view.at, view.up)->linear();
  const double f = 0.5 * view.width / std::tan(0.5 * view.fov_deg * kPi / 180.0);
  const double cx = 0.5 * view.width - 0.5, cy = 0.5 * view.height - 0.5;
  int sampled = 0, agree = 0, triangulable = 0, seen = 0;
  for (int y = 1; y < image.height; y += 4)
    for (int x = 1; x < image.width; x += 4) {
      const std::size_t p = std::size_t(y) * image.width + x;
      if (!std::isfinite(image.depth[p])) continue;
      const Vec3 d =
          (R.col(2) + ((x - cx) / f) * R.col(0) + ((y - cy) / f) * R.col(1)).normalized();
      const auto hit = caster->Intersect(Ray{view.from, d, 0.0, 1e9});
      ASSERT_TRUE(hit.has_value()) << x << "," << y;
      // The EXR depth is float: the rebuilt ray must land on the same surface point.
      ASSERT_NEAR(hit->t, image.depth[p], 2e-6 * hit->t) << x << "," << y;
      const Vec3 X = view.from + hit->t * d;
      const Vec3 n = hit->normal.dot(d) > 0 ? Vec3(-hit->normal) : hit->normal;
      const PointValues v = evaluator.Evaluate(X, &n);
      ++sampled;
      std::uint64_t mask = 0;  // the rig has fewer than 64 cameras
      for (int c : v.cameras) mask |= std::uint64_t{1} << c;
      bool same = image.coverage[p] == v.coverage && image.cameras[p] == mask;
      if (v.coverage > 0)
        same = same && std::abs(image.resolution[p] - v.resolution) <= 5e-5 * v.resolution;
      if (v.triangulable)
        same = same && std::abs(image.sigma_max[p] - v.sigma_max_mm) <= 5e-5 * v.sigma_max_mm;
      else
        same = same && !std::isfinite(image.sigma_max[p]);
      agree += same;
      seen += v.coverage > 0;
      triangulable += v.triangulable;
    }
  // The renderer evaluates a tenth of the visibility epsilon (10 um here) off the surface: density
  // and sigma move by ~1e-5 relative (hence 5e-5), and a pixel on a shadow or frustum edge may
  // change its camera set (3 of 543 here).
  EXPECT_GE(sampled, 500);
  EXPECT_GE(seen, sampled / 4);
  EXPECT_GE(triangulable, sampled / 10);
  EXPECT_GE(agree, sampled - sampled / 100) << "sampled " << sampled;
}

}  // namespace
}  // namespace pandora
