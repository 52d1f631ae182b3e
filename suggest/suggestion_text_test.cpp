// The suggestion table's text (suggest/suggestion_text.h): values, rows and notes.
#include "suggest/suggestion_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace pandora {
namespace {

const double kInf = std::numeric_limits<double>::infinity();

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

Suggestion TwoCameras() {
  Suggestion s;
  s.objective = *ParseObjective("sigma-p90");
  s.target_points = 123;
  CameraChange a;
  a.id = "left";
  a.before.translation() = Vec3(1, 2, 3);
  a.after.translation() = Vec3(1.25, 2, 3);
  a.move_m = 0.25;
  a.rotate_deg = 4.5;
  a.surface_distance_before = a.surface_distance_after = kInf;
  CameraChange b = a;
  b.id = "right";
  b.focal_scale = 1.2;
  b.hfov_before_deg = 60;
  b.hfov_after_deg = 51.5;
  b.surface_distance_before = 0.30;
  b.surface_distance_after = 0.25;
  b.note = "sees none of the target";
  s.cameras = {a, b};
  s.before.objective = s.before.sigma_p90 = 3.5;
  s.after.objective = s.after.sigma_p90 = 2.25;
  s.before.sigma_p95 = kInf;  // the 95th percentile falls on an untriangulable point
  s.after.sigma_p95 = 4;
  s.before.untriangulable = 0.06;
  s.after.untriangulable = 0.01;
  s.iterations = 17;
  s.outer_iterations = 2;
  s.evaluations = 999;
  s.seconds = 0.5;
  s.message = "improved";
  return s;
}

TEST(SuggestionText, TableValue) {
  EXPECT_EQ(TableValue(kInf), "inf");
  EXPECT_EQ(TableValue(-kInf), "-inf");
  EXPECT_EQ(TableValue(std::nan("")), "n/a");
  EXPECT_EQ(TableValue(0.123456), "0.1235");
  EXPECT_EQ(TableValue(2.0, "%.2f"), "2.00");
}

TEST(SuggestionText, TableRowsAndNotes) {
  const Suggestion s = TwoCameras();
  const std::string t = FormatSuggestion(s, {"pandora suggest", "scene.json", "ring"});
  EXPECT_EQ(
      t.rfind("pandora suggest: scene scene.json, rig ring, objective sigma-p90 (lower is better), "
              "123 target points\n",
              0),
      0u)
      << t;
  EXPECT_NE(
      t.find(
          "left           0.250         4.50  (1.000, 2.000, 3.000)        (1.250, 2.000, 3.000)"),
      std::string::npos)
      << t;
  // Only the zoomed camera has a zoom line; only the one near a surface a surface line.
  EXPECT_EQ(Count(t, "zoom: horizontal field of view 60.00 -> 51.50 deg"), 1) << t;
  EXPECT_EQ(Count(t, "nearest surface: 0.300 m -> 0.250 m"), 1) << t;
  EXPECT_EQ(Count(t, "note: sees none of the target"), 1) << t;
  EXPECT_NE(t.find("sigma_max p95 (mm)                    inf              4"), std::string::npos)
      << t;
  EXPECT_NE(t.find("17 iterations (2 outer), 999 evaluations, 0.500 s\nimproved\n"),
            std::string::npos)
      << t;
  EXPECT_EQ(Count(t, "(inf: the percentile falls on a point that is not triangulable)"), 1);
  // coverage >= k appears only when k differs from 2; no screening line without screening.
  EXPECT_EQ(Count(t, "coverage >= "), 1);
  EXPECT_EQ(Count(t, "screening:"), 0);

  Suggestion finite = s;
  finite.before.sigma_p95 = 5;
  finite.objective = *ParseObjective("coverage3");
  finite.screened = 40;
  finite.screened_objective = 0.75;
  const std::string f = FormatSuggestion(finite, {});
  EXPECT_EQ(Count(f, "(inf:"), 0) << f;
  EXPECT_EQ(Count(f, "coverage >= 3 (share)"), 1) << f;
  EXPECT_EQ(Count(f, "screening: 40 exact evaluations, best 0.75; then 17 iterations"), 1) << f;
}

TEST(SuggestionText, Recovery) {
  Suggestion s;
  s.before.objective = 0.6;  // perturbed
  s.after.objective = 0.75;
  EXPECT_EQ(FormatRecovery(s, 0.8, "0.2,5"),
            "perturbed by 0.2,5: objective at the original poses 0.8; recovered 0.15 of the lost "
            "0.2 (75%)\n");
  s.before.objective = 0.8;  // nothing lost
  s.after.objective = 0.8;
  EXPECT_NE(FormatRecovery(s, 0.8, "0,0").find("recovered 0 of the lost 0 (0%)"),
            std::string::npos);
}

}  // namespace
}  // namespace pandora
