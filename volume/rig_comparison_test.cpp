// The rig comparison (app/report/rig_comparison.h) on hand-made summaries: the best rig of each
// row, decided on the values as shown, and the JSON form.
#include "volume/rig_comparison.h"

#include <gtest/gtest.h>

namespace pandora {
namespace {

Summary FakeSummary(const std::string& rig, double ge2, double p50_mm, int cameras = 4) {
  Summary s;
  s.rig = rig;
  s.cameras = cameras;
  s.coverage.ge1 = 0.9;
  s.coverage.ge2 = ge2;
  s.coverage.ge3 = 0.25;
  s.resolution_px_per_m = ResolutionPercentiles{800, 1200, 1500};
  UncertaintySummary u;
  u.triangulable = ge2;
  u.sigma_max_mm = {p50_mm, 2 * p50_mm, 3 * p50_mm};
  s.uncertainty = u;
  s.region_voxels = 1000;
  s.timing.seconds = 0.5;
  return s;
}

TEST(RigComparison, BestIsDecidedOnTheShownValues) {
  Study study;
  const RigComparison c =
      CompareRigs({FakeSummary("a", 0.5, 1.0), FakeSummary("b", 0.6, 1.2, 6)}, study);
  ASSERT_EQ(c.rigs, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(c.enabled_cameras, (std::vector<int>{4, 6}));
  ASSERT_EQ(c.rows.size(), 10u);  // no target, no motion
  const ComparisonRow* ge2 = c.Find("coverage_ge2");
  ASSERT_TRUE(ge2);
  EXPECT_EQ(ge2->best, (std::vector<bool>{false, true}));  // higher coverage is better
  EXPECT_EQ(ge2->Text(0), "50.0%");
  const ComparisonRow* p50 = c.Find("sigma_max_p50_mm");
  EXPECT_EQ(p50->best, (std::vector<bool>{true, false}));  // lower sigma is better
  EXPECT_EQ(p50->Text(1), "1.200");
  // Equal values: nobody is best.
  EXPECT_EQ(c.Find("coverage_ge1")->best, (std::vector<bool>{false, false}));
  EXPECT_EQ(c.Find("resolution_p50_px_per_m")->Text(0), "1200");
  EXPECT_FALSE(c.Find("meets_max_sigma"));
}

TEST(RigComparison, ValuesThatPrintAlikeAreEqual) {
  // 12.34% and 12.26% both show as 12.3%; 1.0004 and 0.9996 mm both as 1.000.
  const RigComparison c =
      CompareRigs({FakeSummary("a", 0.1234, 1.0004), FakeSummary("b", 0.1226, 0.9996)}, Study());
  EXPECT_EQ(c.Find("coverage_ge2")->best, (std::vector<bool>{false, false}));
  EXPECT_EQ(c.Find("sigma_max_p50_mm")->best, (std::vector<bool>{false, false}));
  EXPECT_DOUBLE_EQ(c.Find("coverage_ge2")->Shown(0), 12.3);
}

TEST(RigComparison, OneRigAndMissingValues) {
  Summary none = FakeSummary("solo", 0.0, 1.0);
  none.uncertainty->sigma_max_mm = {};  // nothing triangulable
  const RigComparison one = CompareRigs({none}, Study());
  for (const ComparisonRow& row : one.rows) EXPECT_FALSE(row.best[0]) << row.key;
  EXPECT_EQ(one.Find("sigma_max_p90_mm")->Text(0), "-");
  EXPECT_TRUE(std::isnan(one.Find("sigma_max_p90_mm")->Shown(0)));
  // A rig without a value is never best; the other one is when it beats a shown value.
  const RigComparison two =
      CompareRigs({none, FakeSummary("b", 0.5, 2.0), FakeSummary("c", 0.5, 3.0)}, Study());
  EXPECT_EQ(two.Find("sigma_max_p50_mm")->best, (std::vector<bool>{false, true, false}));
}

TEST(RigComparison, TargetAndMotionRowsAndJson) {
  Study study;
  study.max_sigma_mm = 2.0;
  study.motion = MotionModel{1.0, 60.0};
  Summary a = FakeSummary("a", 0.5, 1.0), b = FakeSummary("b", 0.5, 1.0);
  a.uncertainty->meets_max_sigma = 0.4;
  b.uncertainty->meets_max_sigma = 0.45;
  a.uncertainty->sigma_max_steady_mm = {0.9, 1.8, 2.7};
  b.uncertainty->sigma_max_steady_mm = {0.8, 1.8, 2.7};
  const RigComparison c = CompareRigs({a, b}, study);
  EXPECT_EQ(c.rows.size(), 15u);
  EXPECT_EQ(c.Find("meets_max_sigma")->label, "Meets sigma_max <= 2 mm");
  EXPECT_EQ(c.Find("meets_max_sigma")->best, (std::vector<bool>{false, true}));
  EXPECT_EQ(c.Find("sigma_max_steady_p50_mm")->best, (std::vector<bool>{false, true}));
  EXPECT_EQ(c.Find("sigma_max_steady_p90_mm")->best, (std::vector<bool>{false, false}));
  EXPECT_EQ(c.Find("meets_max_sigma_steady")->Text(0), "-");  // not in the summaries

  const nlohmann::json j = c;
  EXPECT_EQ(j["rigs"], nlohmann::json({"a", "b"}));
  EXPECT_EQ(j["region_voxels"], nlohmann::json({1000, 1000}));
  ASSERT_EQ(j["rows"].size(), 15u);
  EXPECT_EQ(j["rows"][1]["key"], "coverage_ge2");
  EXPECT_EQ(j["rows"][1]["values"], nlohmann::json({0.5, 0.5}));
  EXPECT_EQ(j["rows"][7]["key"], "sigma_max_p50_mm");
  EXPECT_EQ(j["rows"][7]["higher_better"], false);
  EXPECT_TRUE(j["rows"][14]["values"][0].is_null());
  EXPECT_EQ(j["rows"][10]["best"], nlohmann::json({false, true}));
}

}  // namespace
}  // namespace pandora
