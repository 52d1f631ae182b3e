// PTZ suggestions (issue 13): the suggested preset sees at least as many target points as the best
// setting of a brute-force pan x tilt x zoom lattice around the target; the suggested tour order is
// the best of every order judged by the reference path (WatchTour over the reordered legs); accept
// writes exactly the preset or the tour into the scene file, with a backup, and refuses a file that
// changed.
#include "suggest/ptz_suggest.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "suggest/suggestion_file.h"

namespace pandora {
namespace {

// A 10 x 8 m room with a pillar and a cabinet; a ceiling dome "d" at (0, 0, 2.8) looking along +y.
std::string SceneText(const std::string& ptz) {
  return R"({"pandora": 1,
  "objects": [
    {"name": "pillar", "box": {"size": [0.4, 0.4, 3]}, "position": [1.2, 1.7, 1.5]},
    {"name": "cabinet", "box": {"size": [0.5, 2, 1.8]}, "position": [-2.75, 0, 0.9]}
  ],
  "rigs": [{"name": "r", "cameras": [
    {"id": "d", "position": [0, 0, 2.8], "look_at": [0, 5, 2.8], "resolution": [320, 240], "hfov_deg": 50,
     "ptz": {)" +
         ptz + R"(}}]}],
  "study": {"region": {"box": {"min": [-5, -4, 0], "max": [5, 4, 2.5]}}, "voxel_size": 0.5}
}
)";
}

const char* kHead =
    R"("pan_speed_deg_s": 60, "tilt_speed_deg_s": 30, "zoom_hfov_deg": [60, 6], "zoom_speed_pct_s": 40,
    "tilt_range_deg": [-85, 10],
    "presets": [{"name": "door", "pan_deg": 0, "tilt_deg": -10, "hfov_deg": 50},
                {"name": "east", "pan_deg": -90, "tilt_deg": -30, "hfov_deg": 30},
                {"name": "west", "pan_deg": 90, "tilt_deg": -30, "hfov_deg": 30},
                {"name": "south", "pan_deg": 180, "tilt_deg": -40, "hfov_deg": 40},
                {"name": "floor", "pan_deg": 45, "tilt_deg": -70, "hfov_deg": 60}],
    "tour": [{"preset": "door", "dwell_s": 3}, {"preset": "south", "dwell_s": 2}, {"preset": "east", "dwell_s": 2},
             {"preset": "floor", "dwell_s": 1}, {"preset": "west", "dwell_s": 2}])";

std::vector<Vec3> BoxPoints(const Vec3& lo, const Vec3& hi, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i)
    p.emplace_back(lo.x() + u(rng) * (hi.x() - lo.x()), lo.y() + u(rng) * (hi.y() - lo.y()),
                   lo.z() + u(rng) * (hi.z() - lo.z()));
  return p;
}

TEST(PtzSuggest, PresetSeesAtLeastTheBestOfABruteForceLattice) {
  const Scene scene = ParseScene(SceneText(kHead), "room.json");
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeBruteForceRayCaster(scene.AllTriangles());
  const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
  const PtzHead& h = *rig.cameras[0].ptz;
  // A target behind and beside the pillar, seen well only from some settings, at 120 px/m.
  const std::vector<Vec3> points = BoxPoints(Vec3(1.0, 2.2, 0.2), Vec3(3.0, 3.6, 1.8), 150, 3);
  const double px = 120;
  const PtzPresetSuggestion s = SuggestPtzPreset(tester, 0, 1, points, px);
  EXPECT_EQ(s.preset, "east");
  EXPECT_GT(s.seen_after, s.seen_before);
  // The lattice: 1 deg steps in pan and tilt within 50 deg of the target's centre direction, 10
  // zooms.
  const PtzPointJudge judge(tester, 0, points, px);
  const Vec3 centre(2.0, 2.9, 1.0);
  const Vec3 e = centre - Vec3(0, 0, 2.8);
  const double az = std::atan2(-e.x(), e.y()) * 180 / kPi,
               el = std::atan2(e.z(), std::hypot(e.x(), e.y())) * 180 / kPi;
  int best = 0;
  for (int z = 0; z < 10; ++z) {
    const double f = h.focal_min * std::pow(h.focal_max / h.focal_min, z / 9.0);
    for (double p = az - 50; p <= az + 50; p += 1)
      for (double t = std::max(h.tilt_min_deg, el - 50); t <= std::min(h.tilt_max_deg, el + 50);
           t += 1)
        best = std::max(best, judge.Count({p, t, f}));
  }
  std::printf("preset east: %d -> %d of %zu points (lattice best %d), %d settings judged, %.3f s\n",
              s.seen_before, s.seen_after, points.size(), best, s.evaluations, s.seconds);
  EXPECT_GT(best, 20);  // the target can be seen
  EXPECT_GE(s.seen_after, best);
  // The suggestion's own count is the exact one.
  EXPECT_EQ(judge.Count(s.after), s.seen_after);
  EXPECT_GE(s.after.tilt_deg, h.tilt_min_deg);
  EXPECT_LE(s.after.focal, h.focal_max * (1 + 1e-12));
}

TEST(PtzSuggest, TourOrderIsTheBestOfEveryOrderByTheReferencePath) {
  const Scene scene = ParseScene(SceneText(kHead), "room.json");
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeBruteForceRayCaster(scene.AllTriangles());
  const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
  const std::vector<Vec3> points = BoxPoints(Vec3(-4.5, -3.5, 0.2), Vec3(4.5, 3.5, 2.0), 80, 5);
  const double px = 40;
  // The reference: every order through TourLegs + WatchTour, over the points some stop watches.
  const PtzPointJudge judge(tester, 0, points, px);
  const PtzHead& h = *rig.cameras[0].ptz;
  std::vector<int> order{0, 1, 2, 3, 4};
  std::vector<std::vector<double>> gaps;
  std::vector<std::vector<int>> orders;
  do {
    gaps.push_back(PtzTourGaps(judge, order));
    orders.push_back(order);
  } while (std::next_permutation(order.begin() + 1, order.end()));
  std::vector<char> watchable(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i)
    for (const PtzTourStop& stop : h.tour)
      watchable[i] |= judge.Sees(i, h.presets[stop.preset].state);
  const int count = static_cast<int>(std::count(watchable.begin(), watchable.end(), 1));
  std::vector<double> max_gap, mean_gap;
  for (std::size_t o = 0; o < orders.size(); ++o) {
    double m = 0, sum = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (watchable[i]) {
        m = std::max(m, gaps[o][i]);
        sum += gaps[o][i];
      }
    max_gap.push_back(m);
    mean_gap.push_back(sum / count);
  }
  for (TourObjective objective : {TourObjective::kMean, TourObjective::kMax}) {
    const PtzTourSuggestion s = SuggestPtzTour(tester, 0, points, px, objective);
    EXPECT_TRUE(s.exhaustive);
    EXPECT_EQ(s.orders, 24);  // 4! orders with the first stop first
    EXPECT_EQ(s.watchable, count);
    EXPECT_GT(s.watchable, 20);
    // The best order by the reference, with the same tie rule.
    std::size_t best = 0;
    for (std::size_t o = 1; o < orders.size(); ++o)
      if (s.Better(max_gap[o], mean_gap[o], max_gap[best], mean_gap[best])) best = o;
    std::printf(
        "tour (%s): longest gap %.3f -> %.3f s, mean %.3f -> %.3f s (worst orders %.3f, %.3f s), "
        "%d of %zu "
        "points watchable, %.3f s\n",
        objective == TourObjective::kMax ? "max" : "mean", s.gap_max_before, s.gap_max_after,
        s.gap_mean_before, s.gap_mean_after, *std::max_element(max_gap.begin(), max_gap.end()),
        *std::max_element(mean_gap.begin(), mean_gap.end()), s.watchable, points.size(), s.seconds);
    EXPECT_NEAR(s.gap_max_before, max_gap[0], 1e-9);
    EXPECT_NEAR(s.gap_mean_before, mean_gap[0], 1e-9);
    EXPECT_NEAR(s.gap_max_after, max_gap[best], 1e-9);
    EXPECT_NEAR(s.gap_mean_after, mean_gap[best], 1e-9);
    EXPECT_EQ(s.after, orders[best]);
    EXPECT_TRUE(s.improved());
  }
  // The orders differ, or the test proves nothing.
  EXPECT_GT(*std::max_element(max_gap.begin(), max_gap.end()),
            *std::min_element(max_gap.begin(), max_gap.end()) + 0.5);
  EXPECT_GT(*std::max_element(mean_gap.begin(), mean_gap.end()),
            *std::min_element(mean_gap.begin(), mean_gap.end()) + 0.5);
}

std::string ReadText(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(PtzSuggest, AcceptWritesThePresetOrTheTourWithABackup) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("pandora_ptz_accept_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "room.json").string();
  std::ofstream(path) << SceneText(kHead);
  const Scene scene = LoadScene(path);
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeBruteForceRayCaster(scene.AllTriangles());
  const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
  const PtzPresetSuggestion s = SuggestPtzPreset(
      tester, 0, 1, BoxPoints(Vec3(1.0, 2.2, 0.2), Vec3(3.0, 3.6, 1.8), 150, 3), 120);
  ASSERT_TRUE(s.improved());
  const std::string sug = (dir / "preset.json").string();
  std::ofstream(sug) << PtzPresetSuggestionToJson(s, scene, rig);
  const AcceptResult r = AcceptSuggestion(sug, {});
  EXPECT_TRUE(std::filesystem::exists(r.backup_path));
  EXPECT_EQ(ReadText(r.backup_path), SceneText(kHead));
  const Scene after = LoadScene(path);
  const PtzHead& h = *after.rigs[0].cameras[0].ptz;
  EXPECT_NEAR(h.presets[1].state.pan_deg, s.after.pan_deg, 1e-9);
  EXPECT_NEAR(h.presets[1].state.tilt_deg, s.after.tilt_deg, 1e-9);
  EXPECT_NEAR(h.presets[1].state.focal, s.after.focal, 1e-9 * s.after.focal);
  for (int k : {0, 2, 3, 4})
    EXPECT_EQ(h.presets[k].state.pan_deg, rig.cameras[0].ptz->presets[k].state.pan_deg);
  // The same file again: it changed since, refused (one line, nothing written).
  EXPECT_THROW(AcceptSuggestion(sug, {}), InputError);
  // The tour, from the file as it is now.
  const auto caster2 = MakeBruteForceRayCaster(after.AllTriangles());
  const VisibilityTester tester2(after.rigs[0].cameras, *caster2, after.ContentBounds().diagonal());
  const PtzTourSuggestion t =
      SuggestPtzTour(tester2, 0, BoxPoints(Vec3(-4.5, -3.5, 0.2), Vec3(4.5, 3.5, 2.0), 80, 5), 40);
  ASSERT_TRUE(t.improved());
  const std::string tour = (dir / "tour.json").string();
  std::ofstream(tour) << PtzTourSuggestionToJson(t, after, after.rigs[0]);
  AcceptSuggestion(tour, {});
  const Scene reordered = LoadScene(path);
  const PtzHead& g = *reordered.rigs[0].cameras[0].ptz;
  for (std::size_t k = 0; k < t.after.size(); ++k) {
    EXPECT_EQ(g.tour[k].preset, h.tour[t.after[k]].preset);
    EXPECT_EQ(g.tour[k].dwell_s, h.tour[t.after[k]].dwell_s);
  }
  EXPECT_NEAR(g.presets[1].state.pan_deg, s.after.pan_deg, 1e-9);  // the accepted preset stays
  std::filesystem::remove_all(dir);
}

// A damaged PTZ suggestion file (random bytes changed or cut, every value replaced by a value of
// another type) is accepted only when it still says something valid, else refused with an
// InputError; never another exception, and a refused one leaves the scene file as it was.
TEST(PtzSuggest, DamagedSuggestionFilesAreRefusedCleanly) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("pandora_ptz_damage_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "room.json").string();
  const std::string original = SceneText(kHead);
  std::ofstream(path) << original;
  const Scene scene = LoadScene(path);
  const Rig& rig = scene.rigs[0];
  const auto caster = MakeBruteForceRayCaster(scene.AllTriangles());
  const VisibilityTester tester(rig.cameras, *caster, scene.ContentBounds().diagonal());
  const std::vector<Vec3> points = BoxPoints(Vec3(1.0, 2.2, 0.2), Vec3(3.0, 3.6, 1.8), 60, 3);
  const std::vector<std::string> valid{
      PtzPresetSuggestionToJson(SuggestPtzPreset(tester, 0, 1, points, 120), scene, rig),
      PtzTourSuggestionToJson(
          SuggestPtzTour(tester, 0, BoxPoints(Vec3(-4.5, -3.5, 0.2), Vec3(4.5, 3.5, 2.0), 80, 5),
                         40),
          scene, rig)};
  const std::string sug = (dir / "s.json").string();
  std::mt19937_64 rng(21);
  int accepted = 0, refused = 0;
  auto attempt = [&](const std::string& text) {
    std::ofstream(sug, std::ios::trunc) << text;
    try {
      const AcceptResult r = AcceptSuggestion(sug, {});
      ++accepted;
      std::filesystem::remove(r.backup_path);
      std::ofstream(path, std::ios::trunc)
          << original;  // back to the file the suggestion was made for
    } catch (const InputError&) {
      ++refused;
      EXPECT_EQ(ReadText(path), original) << text;
    }
  };
  for (const std::string& text : valid) {
    for (int i = 0; i < 150; ++i) {
      std::string t = text;
      const int kind = static_cast<int>(rng() % 3);
      const std::size_t at = rng() % t.size();
      if (kind == 0) t[at] = static_cast<char>(rng() % 256);
      if (kind == 1) t.resize(at);
      if (kind == 2) t.insert(at, 1, "{}[],:\"0-e"[rng() % 11]);
      attempt(t);
    }
    // Every value (depth first) replaced by values of other types.
    const nlohmann::json j = nlohmann::json::parse(text);
    const nlohmann::json flat = j.flatten();
    for (const auto& item : flat.items())
      for (const nlohmann::json& v :
           {nlohmann::json(), nlohmann::json("x"), nlohmann::json(-1), nlohmann::json(1e308),
            nlohmann::json::array(), nlohmann::json(true)}) {
        nlohmann::json f = j;
        f[nlohmann::json::json_pointer(item.key())] = v;
        attempt(f.dump());
      }
  }
  std::printf("damaged suggestion files: %d refused, %d accepted\n", refused, accepted);
  EXPECT_GT(refused, 300);
  EXPECT_GT(accepted, 0);  // harmless damage (a changed digit in a statistic) still accepts
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pandora
