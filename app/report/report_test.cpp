// The report's computation and page (app/report/report.h) on a synthetic scene: option checks
// that name the option, the numbers against closed forms and brute force (free voxels, histogram
// shares, scales, slices), and the page's image count.
#include "app/report/report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "analysis/geometry/primitives.h"
#include "analysis/rig/rig_formats.h"
#include "analysis/util/error.h"
#include "app/report/plot.h"
#include "app/report/report_images.h"
#include "tests/expect_input_error.h"
#include "tests/fixtures.h"

namespace pandora::report {
namespace {

// The box room (4 x 4 x 2.5 m) with a 0.35 m solid cube in a 1 m region at 0.1 m voxels; rig
// "ring4" (four cameras) and rig "ring6" (six, one of them disabled).
Scene TwoRigRoom() {
  Scene scene = testing::BoxRoom(Vec3(4, 4, 2.5), 0.1);
  scene.objects.push_back(
      testing::TestObject("cube", MakeBox(Vec3(0.35, 0.35, 0.35)), Vec3(0, 0, 0.5), true));
  scene.study.max_sigma_mm = 2.0;
  scene.rigs.push_back(testing::RingRig(4, 1.8, 1.2, Vec3(0, 0, 0.5), 70, 64, 48, "ring4"));
  scene.rigs.push_back(testing::RingRig(6, 1.6, 1.0, Vec3(0, 0, 0.5), 80, 64, 48, "ring6"));
  scene.rigs[1].cameras[5].enabled = false;
  return scene;
}

using testing::ErrorOf;

TEST(ReportOptions, ErrorsNameTheOptionNeverAFlag) {
  ReportOptions o;
  o.Check();  // the defaults are valid
  auto expect = [](const ReportOptions& bad, const std::string& field, const std::string& reason) {
    const InputError e = ErrorOf([&] { bad.Check(); });
    EXPECT_EQ(e.file(), field);
    EXPECT_EQ(e.json_path(), "");
    EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos) << e.what();
  };
  ReportOptions twice;
  twice.rigs = {"a", "b", "a"};
  expect(twice, "{rigs}", "rig 'a' listed twice");
  ReportOptions empty;
  empty.rigs = {""};
  expect(empty, "{rigs}", "empty rig name");
  ReportOptions voxel;
  voxel.voxel_size = 0;
  expect(voxel, "{voxel_size}", "must be a number of metres, greater than 0");
  voxel.voxel_size = std::numeric_limits<double>::infinity();
  expect(voxel, "{voxel_size}", "greater than 0");
  ReportOptions narrow;
  narrow.view_width = 15;
  expect(narrow, "{view_width}", "in [16, 8192], got 15");
  ReportOptions wide;
  wide.camera_width = 8193;
  expect(wide, "{camera_width}", "in [16, 8192]");
  ReportOptions dark;
  dark.brightness = -1;
  expect(dark, "{brightness}", "in (0, 1e+06]");

  const Scene scene = TwoRigRoom();
  ReportOptions unknown;
  unknown.rigs = {"ring4", "ring5"};
  const InputError e = ErrorOf([&] { unknown.Check(scene); });
  EXPECT_EQ(e.file(), "{rigs}");
  EXPECT_EQ(e.reason(), "no rig named 'ring5' in box_room.json");
  EXPECT_EQ(e.hint(), "rigs in this scene: 'ring4', 'ring6'");
}

class ReportOnRoom : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = new Scene(TwoRigRoom());
    caster_ = MakeEmbreeRayCaster(scene_->AllTriangles()).release();
    ReportOptions options;
    options.camera_width = 16;
    data_ = new ReportData(ComputeReport(*scene_, *caster_, options));
  }
  static void TearDownTestSuite() {
    delete data_;
    delete caster_;
    delete scene_;
  }
  static Scene* scene_;
  static RayCaster* caster_;
  static ReportData* data_;
};
Scene* ReportOnRoom::scene_ = nullptr;
RayCaster* ReportOnRoom::caster_ = nullptr;
ReportData* ReportOnRoom::data_ = nullptr;

TEST_F(ReportOnRoom, EveryRigIsEvaluatedAsAnalyzeWould) {
  const ReportData& d = *data_;
  ASSERT_EQ(d.rigs.size(), 2u);
  EXPECT_EQ(d.rigs[0].rig.name, "ring4");
  EXPECT_EQ(d.field_names,
            (std::vector<std::string>{"coverage", "cameras", "resolution", "sigma_max"}));
  for (const RigReport& r : d.rigs) {
    // 10^3 centres, 4^3 inside the cube (closed form).
    EXPECT_EQ(r.summary.region_voxels, 936);
    EXPECT_EQ(r.summary.solid_voxels, 64);
    // The same numbers as an evaluation of its own (what `pandora analyze` writes).
    FieldOptions options;
    options.fields = d.field_names;
    const Fields fields = EvaluateFields(*scene_, r.rig, *caster_, options);
    Summary alone =
        Summarize(*scene_, r.rig, fields, d.field_names, r.summary.timing.threads, r.warnings);
    alone.robustness =
        ComputeCriticality(*scene_, r.rig, fields, *caster_, scene_->TimeMinCameras());
    nlohmann::json a = alone, b = r.summary;
    a.erase("timing");
    b.erase("timing");
    ASSERT_TRUE(b.contains("robustness"));
    a["robustness"].erase("seconds");
    b["robustness"].erase("seconds");
    EXPECT_EQ(a, b) << r.rig.name;
  }
  EXPECT_EQ(d.comparison.rigs, (std::vector<std::string>{"ring4", "ring6"}));
  EXPECT_EQ(d.comparison.enabled_cameras, (std::vector<int>{4, 5}));
  EXPECT_EQ(d.comparison.Find("coverage_ge2")->values[1], d.rigs[1].summary.coverage.ge2);
  ASSERT_TRUE(d.comparison.Find("meets_max_sigma"));
}

TEST_F(ReportOnRoom, HistogramSharesAddUpAndMatchTheCounts) {
  const ReportData& d = *data_;
  const CoverageHistogram& c = d.coverage_histogram;
  // The histograms count 0 .. every camera of the rig (disabled ones too): ring6 has six.
  EXPECT_EQ(c.max_cameras, 6);
  double y_max = 0;
  for (std::size_t i = 0; i < d.rigs.size(); ++i) {
    ASSERT_EQ(c.shares[i].size(), 7u);
    double sum = 0;
    for (std::size_t k = 0; k < c.shares[i].size(); ++k) {
      const auto& h = d.rigs[i].fields.stats.coverage_histogram;
      const double expected = k < h.size() ? double(h[k]) / 936 : 0.0;
      EXPECT_DOUBLE_EQ(c.shares[i][k], expected);
      sum += c.shares[i][k];
      y_max = std::max(y_max, c.shares[i][k]);
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);  // every free voxel once
  }
  EXPECT_DOUBLE_EQ(c.y_max, y_max);

  // sigma_max: a 1-2-5 bin width, about 30 bins to the scale's top, an overflow bin; brute-force
  // counts of the triangulable voxels' values.
  const SigmaHistogram& s = d.sigma_histogram;
  const double top = d.slices[2].scale.max;
  EXPECT_EQ(s.bin_width, NiceStep(top / 30));
  EXPECT_GE(s.top + 1e-12, top);
  EXPECT_LE(s.bins, 30);
  EXPECT_DOUBLE_EQ(s.top, s.bins * s.bin_width);
  for (std::size_t i = 0; i < d.rigs.size(); ++i) {
    const std::vector<float>& values = d.rigs[i].fields.stats.sigma_max_mm;
    ASSERT_EQ(s.shares[i].size(), std::size_t(s.bins) + 1);
    double sum = 0;
    for (int b = 0; b <= s.bins; ++b) {
      int count = 0;
      for (float v : values)
        count += b < s.bins ? (v >= b * s.bin_width && v < (b + 1) * s.bin_width) : v >= s.top;
      EXPECT_NEAR(s.shares[i][b], count / 936.0, 1e-12) << "bin " << b;
      sum += s.shares[i][b];
    }
    EXPECT_NEAR(sum, double(values.size()) / 936, 1e-12);
    EXPECT_EQ(static_cast<std::int64_t>(values.size()),
              d.rigs[i].summary.uncertainty->triangulable_voxels);
  }
}

TEST_F(ReportOnRoom, SliceScalesAndPlanes) {
  const ReportData& d = *data_;
  ASSERT_EQ(d.slices.size(), 3u);
  const FieldSlices& coverage = d.slices[0];
  EXPECT_EQ(coverage.field, "coverage");
  EXPECT_TRUE(coverage.scale.discrete);
  EXPECT_EQ(coverage.scale.max, 5);  // most enabled cameras of a rig
  // resolution: a nice number at or above every value on the slices.
  const FieldSlices& resolution = d.slices[1];
  double top = 0;
  for (const auto& pair : resolution.rigs)
    for (const FieldSlice& s : pair)
      for (std::size_t k = 0; k < s.values.size(); ++k)
        if (s.has_value[k]) top = std::max(top, s.values[k]);
  EXPECT_GT(top, 0);
  EXPECT_GE(resolution.scale.max, top);
  EXPECT_EQ(resolution.scale.max, NiceTicks(top, 4).back());
  // sigma_max: from the largest p99, open at the top.
  const FieldSlices& sigma = d.slices[2];
  const double p99 = std::max(*d.rigs[0].summary.uncertainty->sigma_max_mm.p99,
                              *d.rigs[1].summary.uncertainty->sigma_max_mm.p99);
  EXPECT_EQ(sigma.scale.max, NiceTicks(p99, 4).back());
  EXPECT_TRUE(sigma.scale.open);
  // Planes through the region's centre (0, 0, 0.5): the nearest voxel layers, 10 x 10 voxels.
  for (const FieldSlices& fs : d.slices)
    for (const auto& pair : fs.rigs) {
      EXPECT_EQ(pair[0].axis, 2);
      EXPECT_EQ(pair[1].axis, 1);
      EXPECT_EQ(pair[0].width, 10);
      EXPECT_EQ(pair[0].height, 10);
      EXPECT_NEAR(std::fabs(pair[0].coordinate - 0.5), 0.05, 1e-9);
      EXPECT_NEAR(std::fabs(pair[1].coordinate), 0.05, 1e-9);
    }
}

TEST_F(ReportOnRoom, PageHasOneImagePerFigure) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("report_test_" + std::to_string(::getpid()));
  ReportFile file;
  {
    OutputTransaction output;
    const ReportTarget target = StageReport(output, dir.string(), "out");
    EXPECT_EQ(target.path, (dir / "report.html").string());
    ReportOptions options;
    options.camera_width = 16;
    file = WriteReport(*scene_, *caster_, *data_, options, target);
    output.Commit();
  }
  std::ifstream in(dir / "report.html");
  std::stringstream html;
  html << in.rdbuf();
  std::filesystem::remove_all(dir);
  const std::string page = html.str();
  EXPECT_EQ(file.bytes, page.size());
  // No named views: a plan per rig, 4 + 5 camera views, 3 legends, 3 fields x 2 planes x 2 rigs,
  // 2 histograms x 2.
  EXPECT_EQ(file.images, 2 + 9 + 3 + 12 + 4);
  EXPECT_NE(page.find("<h2 id=\"plan\">Plan</h2>"), std::string::npos);
  // The installation sheet: each rig's CSV link is export-rig's sheet, byte for byte.
  for (const Rig& rig : scene_->rigs) {
    const std::string uri = DataUri("text/csv", RigToSheetCsv(rig));
    EXPECT_NE(page.find("download=\"" + rig.name + "_sheet.csv\" href=\"" + uri + "\""),
              std::string::npos)
        << rig.name;
  }
  EXPECT_NE(page.find("<th>x_cm</th>"), std::string::npos);
  std::size_t imgs = 0;
  for (std::size_t p = page.find("<img "); p != std::string::npos; p = page.find("<img ", p + 1))
    ++imgs;
  EXPECT_EQ(imgs, std::size_t(file.images));
  EXPECT_NE(page.find("data-expected-images=\"" + std::to_string(file.images) + "\""),
            std::string::npos);
  EXPECT_NE(page.find("<th>ring4</th><th>ring6</th>"), std::string::npos);
  EXPECT_NE(page.find("Rigs compared"), std::string::npos);
  EXPECT_NE(page.find("class=\"summary\" data-rig=\"ring6\""), std::string::npos);
}

TEST(ReportCompute, VoxelSizeOptionAndRigOrder) {
  const Scene scene = TwoRigRoom();
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  ReportOptions options;
  options.rigs = {"ring6", "ring4"};
  options.voxel_size = 0.2;
  const ReportData d = ComputeReport(scene, *caster, options);
  ASSERT_EQ(d.rigs.size(), 2u);
  EXPECT_EQ(d.rigs[0].rig.name, "ring6");
  EXPECT_EQ(d.rigs[0].fields.lattice.voxel_size, 0.2);
  EXPECT_EQ(d.study.voxel_size, 0.2);
  EXPECT_EQ(scene.study.voxel_size, 0.1);  // the caller's scene is left alone
  // 5^3 centres at 0.2 m; the 0.35 m cube holds one of them, (0, 0, 0.5).
  EXPECT_EQ(d.rigs[0].summary.region_voxels, 124);
  EXPECT_EQ(d.rigs[0].summary.solid_voxels, 1);
  // The memory budget names the option when the option set the voxel size.
  Scene small = scene;
  small.study.memory_budget_bytes = 1024;
  const InputError e = ErrorOf([&] { ComputeReport(small, *caster, options); });
  EXPECT_EQ(e.file(), "{voxel_size}");
  EXPECT_NE(e.reason().find("over the budget"), std::string::npos);
}

}  // namespace
}  // namespace pandora::report
