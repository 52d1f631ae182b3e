// Editing a PTZ camera in a session (docs/ptz.md, "In the viewer"): the current setting clamped to
// the head's ranges and undoable; re-centre keeps every preset's pose and the camera's; a gizmo's
// pose made mechanical (pivot moves, pan and tilt follow); saving writes pivot, home, zoom and the
// ptz block with a backup, and the file read back has the session's head.
#include "app/session/ptz_edit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "app/session/autosave.h"
#include "app/session/session.h"

namespace pandora::session {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void Write(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// examples/ptz_home/scene.json in a fresh folder, optionally edited by one string replacement.
fs::path CopyPtzScene(const std::string& name, const std::string& from = "",
                      const std::string& to = "") {
  const fs::path dir = fs::path(::testing::TempDir()) / ("ptz_session_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::string text = Read("examples/ptz_home/scene.json");
  if (!from.empty()) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  Write(dir / "scene.json", text);
  return dir / "scene.json";
}

double Focal(const Camera& c, double hfov_deg) {
  return FocalFromHfov(hfov_deg * kRadPerDeg, c.model.width(), c.model.intrinsics().model);
}

double PoseDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

// The head read back from a saved file equals the session's (angles written to 12 digits).
void ExpectSameHead(const PtzHead& a, const PtzHead& b) {
  EXPECT_LT(PoseDistance(a.home, b.home), 1e-9);
  EXPECT_LT((a.pan_axis - b.pan_axis).norm(), 1e-12);
  EXPECT_NEAR(a.pan_min_deg, b.pan_min_deg, 1e-9);
  EXPECT_NEAR(a.pan_max_deg, b.pan_max_deg, 1e-9);
  EXPECT_NEAR(a.tilt_min_deg, b.tilt_min_deg, 1e-9);
  EXPECT_NEAR(a.tilt_max_deg, b.tilt_max_deg, 1e-9);
  EXPECT_NEAR(a.current.pan_deg, b.current.pan_deg, 1e-9);
  EXPECT_NEAR(a.current.tilt_deg, b.current.tilt_deg, 1e-9);
  EXPECT_NEAR(a.current.focal, b.current.focal, 1e-9 * b.current.focal);
  EXPECT_NEAR(a.home_focal, b.home_focal, 1e-9 * b.home_focal);
  ASSERT_EQ(a.presets.size(), b.presets.size());
  for (std::size_t i = 0; i < a.presets.size(); ++i) {
    EXPECT_EQ(a.presets[i].name, b.presets[i].name);
    EXPECT_NEAR(a.presets[i].state.pan_deg, b.presets[i].state.pan_deg, 1e-9);
    EXPECT_NEAR(a.presets[i].state.tilt_deg, b.presets[i].state.tilt_deg, 1e-9);
    EXPECT_NEAR(a.presets[i].state.focal, b.presets[i].state.focal,
                1e-9 * b.presets[i].state.focal);
  }
  ASSERT_EQ(a.tour.size(), b.tour.size());
}

TEST(PtzSession, SetStateIsClampedAndOneUndoStep) {
  const fs::path path = CopyPtzScene("set_state");
  Session session(Study::Load(path.string()), {});
  const Camera before = session.rig().rig().cameras[0];
  ASSERT_TRUE(before.ptz);
  const PtzHead& h0 = *before.ptz;
  // dome: pan [-180, 180] (continuous), tilt [-75, 10], zoom 60 .. 5 degrees.
  session.SetPtzState(0, {40, -20, Focal(before, 45)});
  const Camera& now = session.rig().rig().cameras[0];
  ASSERT_TRUE(now.ptz);
  EXPECT_NE(now.ptz.get(), before.ptz.get());  // a new head; the old one is the undo state's
  EXPECT_EQ(now.ptz->current.pan_deg, 40);
  EXPECT_EQ(now.ptz->current.tilt_deg, -20);
  const Camera expected = h0.CameraAt(before, {40, -20, Focal(before, 45)});
  EXPECT_EQ(now.world_from_camera.matrix(), expected.world_from_camera.matrix());
  EXPECT_EQ(now.model.intrinsics().fx, Focal(before, 45));
  // The pose closed form: pan 40 about +z, tilt -20 about the camera's x after it.
  const Mat3 R = Eigen::AngleAxisd(40 * kRadPerDeg, Vec3::UnitZ()) * h0.home.linear() *
                 Eigen::AngleAxisd(-20 * kRadPerDeg, Vec3::UnitX());
  EXPECT_LT((now.world_from_camera.linear() - R).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(session.rig().undo_label(), "pan/tilt/zoom dome");
  EXPECT_EQ(session.rig().Unsaved(), std::vector<int>{0});

  // Clamped: a continuous pan wraps (200 -> -160), tilt to [-75, 10], zoom to [60, 5] degrees.
  session.SetPtzState(0, {200, -80, Focal(before, 70)});
  const PtzHead& h = *session.rig().rig().cameras[0].ptz;
  EXPECT_DOUBLE_EQ(h.current.pan_deg, -160);
  EXPECT_EQ(h.current.tilt_deg, -75);
  EXPECT_DOUBLE_EQ(h.current.focal, Focal(before, 60));
  EXPECT_DOUBLE_EQ(HfovFromFocal(session.rig().rig().cameras[0].model.intrinsics().fx, 1280,
                                 LensModel::kPinhole) /
                       kRadPerDeg,
                   60);

  ASSERT_TRUE(session.rig().Undo());
  ASSERT_TRUE(session.rig().Undo());
  const Camera& back = session.rig().rig().cameras[0];
  EXPECT_EQ(back.ptz.get(), before.ptz.get());
  EXPECT_EQ(back.world_from_camera.matrix(), before.world_from_camera.matrix());
  EXPECT_TRUE(session.rig().Unsaved().empty());

  // A fixed camera has no head: one line naming the file and the camera.
  Session fixed(Study::Load("tests/data/minimal.json"), {});
  try {
    fixed.SetPtzState(0, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("$.rigs[0].cameras[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no pan-tilt-zoom head"), std::string::npos) << e.what();
  }
}

TEST(PtzSession, RecentreKeepsEveryPresetPoseAndShiftsTheRanges) {
  const fs::path path = CopyPtzScene("recentre");
  Session session(Study::Load(path.string()), {});
  const Camera start = session.rig().rig().cameras[0];
  session.SetPtzState(0, {63, -3, Focal(start, 40)});
  const Camera before = session.rig().rig().cameras[0];
  const PtzHead h0 = *before.ptz;
  session.RecentrePtz(0);
  const Camera& after = session.rig().rig().cameras[0];
  const PtzHead& h = *after.ptz;
  EXPECT_EQ(session.rig().undo_label(), "re-centre dome");
  EXPECT_EQ(h.current.pan_deg, 0);
  EXPECT_EQ(h.current.tilt_deg, 0);
  EXPECT_EQ(h.current.focal, h0.current.focal);
  EXPECT_EQ(h.home.translation(), h0.home.translation());  // the same pivot
  EXPECT_LT(PoseDistance(after.world_from_camera, before.world_from_camera), 1e-12);
  EXPECT_EQ(after.model.intrinsics().fx, before.model.intrinsics().fx);
  // New home: Rot(z, 63) home Rot(x, -3); it is the old pose at (63, -3).
  EXPECT_LT(PoseDistance(h.home, h0.Pose({63, -3, 0})), 1e-12);
  // Ranges shifted by (-63, +3).
  EXPECT_DOUBLE_EQ(h.pan_min_deg, -243);
  EXPECT_DOUBLE_EQ(h.pan_max_deg, 117);
  EXPECT_DOUBLE_EQ(h.tilt_min_deg, -72);
  EXPECT_DOUBLE_EQ(h.tilt_max_deg, 13);
  ASSERT_EQ(h.presets.size(), 3u);
  for (std::size_t i = 0; i < h.presets.size(); ++i) {
    EXPECT_EQ(h.presets[i].name, h0.presets[i].name);
    EXPECT_DOUBLE_EQ(h.presets[i].state.pan_deg, h0.presets[i].state.pan_deg - 63);
    EXPECT_DOUBLE_EQ(h.presets[i].state.tilt_deg, h0.presets[i].state.tilt_deg + 3);
    EXPECT_LT(PoseDistance(h.Pose(h.presets[i].state), h0.Pose(h0.presets[i].state)), 1e-12)
        << h.presets[i].name;
  }
  // The west door preset is now straight ahead.
  EXPECT_NEAR(h.presets[1].state.pan_deg, 0, 1e-12);
  EXPECT_NEAR(h.presets[1].state.tilt_deg, 0, 1e-12);
  // Home elevation moved by the tilt: -3 degrees more downward.
  EXPECT_NEAR(h.HomeElevationDeg(), h0.HomeElevationDeg() - 3, 1e-10);
  // The pose is unchanged, the head is not: an unsaved change (and undo restores the head).
  EXPECT_EQ(session.rig().Unsaved(), std::vector<int>{0});
  ASSERT_TRUE(session.rig().Undo());
  EXPECT_TRUE(SamePtzHead(session.rig().rig().cameras[0].ptz.get(), &h0));
}

TEST(PtzSession, RecentreRefusesAHomeStraightUpOrDown) {
  // No tilt range: the optical axis may tilt from straight down to straight up. Tilted straight up,
  // the new home would look along the pan axis, where the reader's elevation check is undefined.
  const fs::path path = CopyPtzScene("recentre_refused", "\"tilt_range_deg\": [-75, 10], ", "");
  Session session(Study::Load(path.string()), {});
  const PtzHead h0 = *session.rig().rig().cameras[0].ptz;
  const double el = h0.HomeElevationDeg();
  EXPECT_NEAR(h0.tilt_max_deg, 90 - el, 1e-12);
  session.SetPtzState(0, {20, h0.tilt_max_deg, h0.current.focal});
  try {
    session.RecentrePtz(0);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find("$.rigs[0].cameras[0].ptz.tilt_range_deg"), std::string::npos) << what;
    EXPECT_NE(what.find("would make its home look straight up, along the pan axis"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_EQ(session.rig().undo_label(), "pan/tilt/zoom dome");  // nothing applied
  // 40 degrees down is fine: the default range shifts with it.
  session.SetPtzState(0, {20, -40, h0.current.focal});
  session.RecentrePtz(0);
  const PtzHead& h = *session.rig().rig().cameras[0].ptz;
  EXPECT_NEAR(h.tilt_min_deg, -90 - h.HomeElevationDeg(), 1e-9);
  EXPECT_NEAR(h.tilt_max_deg, 90 - h.HomeElevationDeg(), 1e-9);
  // Saved, the shifted range sits exactly on the reader's limits and is read back.
  session.Save();
  const auto reloaded = Study::Load(path.string());
  const Camera& back = reloaded->FindRig("home").cameras[0];
  ASSERT_TRUE(back.ptz);
  ExpectSameHead(*back.ptz, h);
}

TEST(PtzSession, GizmoPosesBecomePivotMovesAndPanTilt) {
  const auto study = Study::Load(CopyPtzScene("follow").string());
  const Camera cam = study->FindRig("home").cameras[0];
  const PtzHead& h = *cam.ptz;
  // A move: the pivot moves, the setting stays exactly.
  Camera moved = cam;
  moved.world_from_camera.translation() += Vec3(0.5, -0.25, 0.1);
  const Camera m = PtzFollow(cam, moved);
  EXPECT_LT((m.ptz->home.translation() - (h.home.translation() + Vec3(0.5, -0.25, 0.1))).norm(),
            1e-15);
  EXPECT_EQ(m.ptz->current.pan_deg, h.current.pan_deg);
  EXPECT_EQ(m.ptz->current.tilt_deg, h.current.tilt_deg);
  EXPECT_EQ(m.ptz->home.linear(), h.home.linear());
  // A turn of 25 degrees about the pan axis and a roll: pan 25, tilt 0, the roll dropped.
  Camera turned = cam;
  turned.world_from_camera.linear() = Eigen::AngleAxisd(25 * kRadPerDeg, Vec3::UnitZ()) *
                                      cam.world_from_camera.linear() *
                                      Eigen::AngleAxisd(7 * kRadPerDeg, Vec3::UnitZ());
  bool clamped = true;
  const Camera t = PtzFollow(cam, turned, &clamped);
  EXPECT_FALSE(clamped);
  EXPECT_NEAR(t.ptz->current.pan_deg, 25, 1e-12);
  EXPECT_NEAR(t.ptz->current.tilt_deg, 0, 1e-12);
  EXPECT_LT(PoseDistance(t.world_from_camera, h.Pose({25, 0, h.current.focal})), 1e-12);
  // Aimed 50 degrees below home's axis: tilt -50; 20 above: clamped at the range's 10.
  Camera down = cam;
  down.world_from_camera.linear() =
      cam.world_from_camera.linear() * Eigen::AngleAxisd(-50 * kRadPerDeg, Vec3::UnitX());
  const Camera d = PtzFollow(cam, down, &clamped);
  EXPECT_FALSE(clamped);
  EXPECT_NEAR(d.ptz->current.tilt_deg, -50, 1e-12);
  EXPECT_NEAR(d.ptz->current.pan_deg, 0, 1e-12);
  Camera up = cam;
  up.world_from_camera.linear() =
      cam.world_from_camera.linear() * Eigen::AngleAxisd(20 * kRadPerDeg, Vec3::UnitX());
  const Camera u = PtzFollow(cam, up, &clamped);
  EXPECT_TRUE(clamped);
  EXPECT_EQ(u.ptz->current.tilt_deg, 10);
  EXPECT_NEAR(u.ptz->current.pan_deg, 0, 1e-12);
  // A zoom: the focal length clamped to the zoom range (60 .. 5 degrees).
  Camera wide = cam;
  Intrinsics k = wide.model.intrinsics();
  k.fx = k.fy = Focal(cam, 90);
  wide.model = CameraModel(k);
  const Camera w = PtzFollow(cam, wide);
  EXPECT_DOUBLE_EQ(w.ptz->current.focal, Focal(cam, 60));
  EXPECT_DOUBLE_EQ(w.model.intrinsics().fx, Focal(cam, 60));
}

TEST(PtzSession, SaveWritesPivotHomeZoomAndTheHeadWithABackup) {
  // The window preset without its own zoom: it means "the camera's zoom" (30), which must stay 30
  // when the camera zooms to 40.
  const fs::path path = CopyPtzScene(
      "save", "{\"name\": \"window\", \"pan_deg\": 0, \"tilt_deg\": 0, \"hfov_deg\": 30}",
      "{\"name\": \"window\"}");
  const std::string original = Read(path);
  Session session(Study::Load(path.string()), {});
  const Camera start = session.rig().rig().cameras[0];
  session.SetPtzState(0, {63, -3, Focal(start, 40)});
  session.RecentrePtz(0);
  session.SetPtzState(0, {-10, 5, Focal(start, 40)});
  const Camera edited = session.rig().rig().cameras[0];
  const SaveResult r = session.Save();
  EXPECT_EQ(r.saved, std::vector<std::string>{"dome"});
  EXPECT_EQ(Read(r.backup_path), original);
  EXPECT_TRUE(session.rig().Unsaved().empty());

  // Read back: the same head and camera.
  const auto reloaded = Study::Load(path.string());
  const Camera& back = reloaded->FindRig("home").cameras[0];
  ASSERT_TRUE(back.ptz);
  ExpectSameHead(*back.ptz, *edited.ptz);
  EXPECT_LT(PoseDistance(back.world_from_camera, edited.world_from_camera), 1e-9);
  EXPECT_NEAR(back.model.intrinsics().fx, edited.model.intrinsics().fx,
              1e-9 * edited.model.intrinsics().fx);
  EXPECT_NEAR(back.ptz->presets[0].state.focal, Focal(start, 30), 1e-9 * Focal(start, 30));
  // The file keeps its form: position + look_at (at the old distance along the new home axis),
  // hfov_deg for the zoom; everything but the dome of rig "home" is as it was.
  const nlohmann::json before = nlohmann::json::parse(original),
                       after = nlohmann::json::parse(Read(path));
  const nlohmann::json& dome = after["rigs"][0]["cameras"][0];
  EXPECT_TRUE(dome.contains("look_at"));
  EXPECT_FALSE(dome.contains("quaternion"));
  EXPECT_DOUBLE_EQ(dome["hfov_deg"].get<double>(), 40);
  EXPECT_EQ(dome["position"],
            before["rigs"][0]["cameras"][0]["position"]);  // the pivot did not move
  EXPECT_EQ(dome["ptz"]["pan_deg"], -10);
  EXPECT_EQ(dome["ptz"]["tilt_deg"], 5);
  EXPECT_EQ(dome["ptz"]["tilt_range_deg"], nlohmann::json::parse("[-72, 13]"));
  EXPECT_EQ(dome["ptz"]["pan_range_deg"], nlohmann::json::parse("[-243, 117]"));
  EXPECT_EQ(dome["ptz"]["presets"][0]["hfov_deg"], 30);
  EXPECT_EQ(dome["ptz"]["tour"], before["rigs"][0]["cameras"][0]["ptz"]["tour"]);
  EXPECT_FALSE(dome["ptz"].contains("pan_axis"));  // +z stays the reader's default
  nlohmann::json rest_before = before, rest_after = after;
  rest_before["rigs"][0]["cameras"].erase(0);
  rest_after["rigs"][0]["cameras"].erase(0);
  EXPECT_EQ(rest_before, rest_after);

  // Moving the pivot writes the position; the setting stays.
  Camera requested = session.rig().rig().cameras[0];
  requested.world_from_camera.translation() += Vec3(0.4, 0, 0);
  const Camera before_move = session.rig().rig().cameras[0];
  session.rig().Apply({"move dome", {{0, before_move, PtzFollow(before_move, requested)}}});
  const SaveResult r2 = session.Save();
  EXPECT_EQ(fs::path(r2.backup_path).filename(), "scene.json.bak.1");
  const auto moved_study = Study::Load(path.string());
  const Camera& moved = moved_study->FindRig("home").cameras[0];
  EXPECT_LT((moved.ptz->home.translation() - Vec3(0.4, -2.3, 2.45)).norm(), 1e-12);
  EXPECT_NEAR(moved.ptz->current.pan_deg, -10, 1e-12);
}

TEST(PtzSession, SavingASettingKeepsThePoseKeysText) {
  // Pan, tilt and zoom only: home did not move, so position and look_at keep their text.
  const fs::path path = CopyPtzScene("save_setting");
  Session session(Study::Load(path.string()), {});
  const Camera start = session.rig().rig().cameras[0];
  session.SetPtzState(0, {-30.5, 4.25, Focal(start, 12)});
  EXPECT_EQ(session.Save().saved, std::vector<std::string>{"dome"});
  const std::string text = Read(path);
  const nlohmann::json dome = nlohmann::json::parse(text)["rigs"][0]["cameras"][0];
  EXPECT_EQ(dome["look_at"], nlohmann::json::parse("[0, 2.5, 1.5]"));
  EXPECT_EQ(dome["position"], nlohmann::json::parse("[0, -2.3, 2.45]"));
  EXPECT_EQ(dome["hfov_deg"], 12);
  EXPECT_EQ(dome["ptz"]["pan_deg"], -30.5);
  EXPECT_EQ(dome["ptz"]["tilt_deg"], 4.25);
  EXPECT_EQ(dome["ptz"]["tilt_range_deg"], nlohmann::json::parse("[-75, 10]"));
  EXPECT_FALSE(dome["ptz"].contains("pan_range_deg"));
  const auto reloaded = Study::Load(path.string());
  const Camera& back = reloaded->FindRig("home").cameras[0];
  EXPECT_EQ(back.ptz->home.matrix(), start.ptz->home.matrix());
  EXPECT_LT(PoseDistance(back.world_from_camera, session.rig().rig().cameras[0].world_from_camera),
            1e-12);
}

TEST(PtzSession, SaveWritesThePanAxisWhenTheReadersDefaultWouldChange) {
  // A head mounted rolled (its home image x axis not horizontal): the pan axis defaults to home's
  // up. After a re-centre with a tilt, home's up is another direction, so the file must say it.
  const fs::path path = CopyPtzScene("pan_axis", "\"look_at\": [0, 2.5, 1.5], ",
                                     "\"look_at\": [0, 2.5, 1.5], \"up\": [0.5, 0, 1], ");
  Session session(Study::Load(path.string()), {});
  const Camera start = session.rig().rig().cameras[0];
  const Vec3 axis0 = start.ptz->pan_axis;
  EXPECT_GT(std::abs(start.ptz->home.linear()(2, 0)), 0.1);            // rolled
  EXPECT_LT((axis0 + start.ptz->home.linear().col(1)).norm(), 1e-12);  // the default: home's up
  session.SetPtzState(0, {10, -20, start.ptz->current.focal});
  session.RecentrePtz(0);
  const PtzHead h = *session.rig().rig().cameras[0].ptz;
  EXPECT_EQ(h.pan_axis, axis0);
  EXPECT_GT((h.pan_axis + h.home.linear().col(1)).norm(), 0.3);  // no longer home's up
  session.Save();
  const nlohmann::json dome = nlohmann::json::parse(Read(path))["rigs"][0]["cameras"][0];
  EXPECT_TRUE(dome["ptz"].contains("pan_axis"));
  const auto reloaded = Study::Load(path.string());
  const Camera& back = reloaded->FindRig("home").cameras[0];
  ExpectSameHead(*back.ptz, h);
  EXPECT_LT(PoseDistance(back.world_from_camera, session.rig().rig().cameras[0].world_from_camera),
            1e-9);
  for (std::size_t i = 0; i < h.presets.size(); ++i)
    EXPECT_LT(PoseDistance(back.ptz->Pose(back.ptz->presets[i].state),
                           start.ptz->Pose(start.ptz->presets[i].state)),
              1e-9);
}

TEST(PtzSession, AutosaveKeepsARecentredHead) {
  const fs::path path = CopyPtzScene("autosave");
  Session session(Study::Load(path.string()), {});
  const Camera start = session.rig().rig().cameras[0];
  session.SetPtzState(0, {63, -3, Focal(start, 40)});
  session.RecentrePtz(0);
  const std::string autosave = AutosavePath(path.string());
  WriteAutosave(session, autosave);
  Session fresh(Study::Load(path.string()), {});
  const std::optional<Autosave> a = ReadAutosave(autosave, fresh.study());
  ASSERT_TRUE(a);
  RecoverAutosave(fresh, *a, autosave);
  ExpectSameHead(*fresh.rig().rig().cameras[0].ptz, *session.rig().rig().cameras[0].ptz);
}

TEST(PtzSession, TracedRigsAsRenderHasThem) {
  const auto study = Study::Load("examples/ptz_home/scene.json");
  const Rig& rig = study->FindRig("home_path");
  std::vector<RenderOptions::PtzTrace> all;
  bool any = false;
  // pan 63 at 45 deg/s decides: 1.4 s, lights at 0, 1 and the end.
  const Rig path = PtzTracedRig(rig, "path", NAN, &all, &any);
  EXPECT_TRUE(any);
  ASSERT_EQ(path.cameras.size(), 3u);
  EXPECT_EQ(path.cameras[2].id, "dome@2-end");
  EXPECT_LT(PoseDistance(path.cameras[2].world_from_camera, rig.cameras[0].world_from_camera),
            1e-15);
  EXPECT_TRUE(all.empty());
  const Rig traced = PtzTracedRig(rig, "all", 1.5, &all);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].camera, 0);
  EXPECT_EQ(all[0].budget_s, 1.5);
  EXPECT_LT(PoseDistance(traced.cameras[0].world_from_camera, rig.cameras[0].ptz->home), 1e-15);
  EXPECT_THROW(PtzTracedRig(rig, "sweep", NAN, &all), std::invalid_argument);
}

}  // namespace
}  // namespace pandora::session
