#include "app/report/time_section.h"

#include <gtest/gtest.h>

#include <string>

namespace pandora::report {
namespace {

Summary WithTime(double always, double mean, double target_ge3) {
  Summary s;
  TimeSummary t;
  t.min_cameras = 3;
  t.always = always;
  t.mean = mean;
  for (int i = 0; i < 2; ++i) {
    TimeSampleSummary row;
    row.label = i == 0 ? "pose 'x'" : "pose 'y'";
    row.ge_k = i == 0 ? mean + 0.01 : mean - 0.01;
    t.samples.push_back(row);
  }
  t.worst_sample = 1;
  s.time = t;
  SurfaceTargetResult r;
  r.name = "alice";
  r.share_ge = {0.95, 0.9, target_ge3};
  r.always = target_ge3 / 2;
  r.sample_share = {target_ge3 + 0.02, target_ge3 - 0.02};
  r.worst_sample = 1;
  s.targets.push_back(r);
  s.sample_labels = {"pose 'x'", "pose 'y'"};
  return s;
}

TEST(TimeSection, OneColumnPerRigTheBestInBoldAndEverySample) {
  const Summary a = WithTime(0.9, 0.95, 0.8), b = WithTime(0.99, 0.999, 0.7);
  const std::string html = TimeSectionHtml({&a, &b}, {"ring", "corners"});
  EXPECT_NE(html.find("<h2 id=\"time\">"), std::string::npos);
  EXPECT_NE(html.find("<th>ring</th><th>corners</th>"), std::string::npos);
  // Volume always: corners best; alice >= 3: ring best.
  EXPECT_NE(html.find("<td>90.0 %</td><td><b>99.0 %</b></td>"), std::string::npos) << html;
  EXPECT_NE(html.find("<td><b>80.0 %</b></td><td>70.0 %</td>"), std::string::npos) << html;
  // The worst sample with its label, and the per-sample table.
  EXPECT_NE(
      html.find("<th>pose 'y'</th><td>94.0 %</td><td>78.0 %</td><td>98.9 %</td><td>68.0 %</td>"),
      std::string::npos)
      << html;
  // Nothing to show: nothing written.
  const Summary plain;
  EXPECT_EQ(TimeSectionHtml({&plain}, {"r"}), "");
}

}  // namespace
}  // namespace pandora::report
