// The session layer: edits with undo and redo restore cameras exactly; jobs run latest-wins with
// cancellation and failures reported; a session's fields follow its edits (in the background too)
// and equal a full evaluation of the rig as edited; saving writes the poses with a backup and
// refuses what it cannot write or a file changed on disk.
#include "app/session/session.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "analysis/util/error.h"
#include "app/session/autosave.h"
#include "volume/fields.h"

namespace pandora::session {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A copy of tests/data/minimal.json in a fresh folder (sessions save into it).
fs::path CopyScene(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("session_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file("tests/data/minimal.json", dir / "scene.json");
  return dir / "scene.json";
}

Eigen::Isometry3d Moved(const Camera& cam, const Vec3& by) {
  Eigen::Isometry3d p = cam.world_from_camera;
  p.translation() += by;
  return p;
}

bool SameRig(const Rig& a, const Rig& b) {
  if (a.cameras.size() != b.cameras.size()) return false;
  for (std::size_t c = 0; c < a.cameras.size(); ++c)
    if (!SameCameraGeometry(a.cameras[c], b.cameras[c])) return false;
  return true;
}

TEST(EditableRig, UndoAndRedoRestoreEveryCameraExactly) {
  const auto study = Study::Load("tests/data/minimal.json");
  EditableRig rig(study->FindRig(""));
  const Rig original = rig.rig();
  ASSERT_GE(original.cameras.size(), 2u);
  rig.SetPose(0, Moved(original.cameras[0], Vec3(0.1, 0, 0)));
  const Rig after_move = rig.rig();
  rig.SetEnabled(1, false);
  Intrinsics k = rig.rig().cameras[1].model.intrinsics();
  k.fx *= 1.5;
  k.fy *= 1.5;
  rig.SetIntrinsics(1, k);
  EXPECT_EQ(rig.version(), 3);
  EXPECT_EQ(rig.camera_version(0), 1);
  EXPECT_EQ(rig.camera_version(1), 2);
  EXPECT_EQ(rig.undo_label(), "lens of " + original.cameras[1].id);
  EXPECT_EQ(rig.Unsaved(), (std::vector<int>{0, 1}));
  ASSERT_TRUE(rig.Undo());
  ASSERT_TRUE(rig.Undo());
  EXPECT_TRUE(SameRig(rig.rig(), after_move));
  ASSERT_TRUE(rig.Undo());
  EXPECT_TRUE(SameRig(rig.rig(), original));
  EXPECT_FALSE(rig.Undo());
  EXPECT_TRUE(rig.Unsaved().empty());
  ASSERT_TRUE(rig.Redo());
  EXPECT_TRUE(SameRig(rig.rig(), after_move));
  // A new edit drops the redo stack.
  rig.SetEnabled(0, false);
  EXPECT_FALSE(rig.can_redo());
  EXPECT_FALSE(rig.Redo());
  // An edit made against an older state is refused.
  CameraEdit stale{0, original.cameras[0], original.cameras[0]};
  EXPECT_THROW(rig.Apply({"stale", {stale}}), std::logic_error);
  // Several cameras at once are one undo step.
  rig.SetPoses({{original.cameras[0].id, original.cameras[0].world_from_camera, 1.0},
                {original.cameras[1].id, Moved(original.cameras[1], Vec3(0, 0.2, 0)), 1.25}},
               "accept suggestion", "s.json");
  EXPECT_DOUBLE_EQ(rig.rig().cameras[1].model.intrinsics().fx,
                   after_move.cameras[1].model.intrinsics().fx * 1.25);
  ASSERT_TRUE(rig.Undo());
  EXPECT_FALSE(rig.rig().cameras[0].enabled);  // back to before the suggestion, not further
  EXPECT_THROW(rig.SetPoses({{"nope", Eigen::Isometry3d::Identity(), 1.0}}, "x", "s.json"),
               InputError);
}

TEST(EditableRig, AmendKeepsADragOneUndoStep) {
  const auto study = Study::Load("tests/data/minimal.json");
  EditableRig rig(study->FindRig(""));
  const Rig original = rig.rig();
  // A drag in three steps: the first applies, the others amend it.
  for (int step = 1; step <= 3; ++step) {
    const Camera now = rig.rig().cameras[0];
    Camera after = now;
    after.world_from_camera = Moved(original.cameras[0], Vec3(0.01 * step, 0, 0));
    Edit e{"move a", {{0, now, after}}};
    if (step == 1)
      rig.Apply(e);
    else
      rig.Amend(e);
  }
  EXPECT_EQ(rig.version(), 3);
  EXPECT_EQ(rig.camera_version(0), 3);
  EXPECT_LT(
      (rig.rig().cameras[0].center() - (original.cameras[0].center() + Vec3(0.03, 0, 0))).norm(),
      1e-12);
  ASSERT_TRUE(rig.Undo());
  EXPECT_TRUE(SameRig(rig.rig(), original));  // one step back to the start of the drag
  EXPECT_FALSE(rig.Undo());
  // Amending another camera than the last edit's, or with nothing to amend, is refused.
  EXPECT_FALSE(rig.CanAmend({1}));
  ASSERT_TRUE(rig.Redo());
  EXPECT_FALSE(rig.CanAmend({1}));
  EXPECT_TRUE(rig.CanAmend({0}));
  Edit other{"move b", {{1, rig.rig().cameras[1], rig.rig().cameras[1]}}};
  EXPECT_THROW(rig.Amend(other), std::logic_error);
}

TEST(Jobs, LatestWinsAndFailuresAreReported) {
  Jobs jobs;
  std::atomic<int> started{0}, finished{0};
  std::atomic<bool> first_saw_cancel{false};
  // The first job runs until it is cancelled.
  jobs.Submit("fields", [&](JobContext& job) {
    ++started;
    while (!job.cancelled()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    first_saw_cancel = true;
  });
  while (started == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  // Two more while it runs: the second is replaced by the third before it starts.
  jobs.Submit("fields", [&](JobContext&) {
    ++started;
    ++finished;
  });
  const std::int64_t last = jobs.Submit("fields", [&](JobContext& job) {
    job.Progress(0.5);
    ++started;
    ++finished;
  });
  const JobStatus s = jobs.Wait("fields");
  EXPECT_TRUE(first_saw_cancel);
  EXPECT_EQ(started, 2);  // the first and the last
  EXPECT_EQ(finished, 1);
  EXPECT_EQ(s.state, JobState::kDone);
  EXPECT_EQ(s.id, last);
  // A failure ends the job with its message; the worker lives on.
  jobs.Submit("render", [](JobContext&) { throw InputError("x.json", "$.a", "broken"); });
  const JobStatus f = jobs.Wait("render");
  EXPECT_EQ(f.state, JobState::kFailed);
  EXPECT_NE(f.error.find("broken"), std::string::npos);
  // The exception itself comes back, so a command can rethrow it as its one-line error.
  ASSERT_TRUE(f.exception);
  try {
    std::rethrow_exception(f.exception);
  } catch (const InputError& e) {
    EXPECT_EQ(e.json_path(), "$.a");
  }
  jobs.Submit("render", [](JobContext&) {});
  EXPECT_EQ(jobs.Wait("render").state, JobState::kDone);
  EXPECT_EQ(jobs.Status("suggest").state, JobState::kIdle);
}

void ExpectFieldsOf(const Session& session, const Rig& rig, const FieldOptions& options) {
  const Fields full =
      EvaluateFields(session.study().scene(), rig, session.study().caster(), options);
  session.ReadFields([&](const Fields& f, std::int64_t) {
    EXPECT_EQ(f.stats.coverage_histogram, full.stats.coverage_histogram);
    EXPECT_EQ(f.stats.per_camera_seen, full.stats.per_camera_seen);
    EXPECT_EQ(f.stats.sigma_max_mm, full.stats.sigma_max_mm);
  });
}

TEST(Session, FieldsFollowEditsUndoAndBackgroundUpdates) {
  const auto study = Study::Load("tests/data/minimal.json");
  SessionOptions options;
  options.fields.fields = {"coverage", "cameras", "resolution", "sigma_max"};
  Session session(study, options);
  const Rig original = session.rig().rig();
  EXPECT_TRUE(session.UpdateFields().full);
  ExpectFieldsOf(session, original, options.fields);

  session.rig().SetPose(0, Moved(original.cameras[0], Vec3(0.05, 0.02, 0)));
  const FieldUpdate u = session.UpdateFields();
  EXPECT_FALSE(u.full);
  EXPECT_EQ(u.changed_cameras, 1);
  ExpectFieldsOf(session, session.rig().rig(), options.fields);

  // In the background, several edits in a row: the fields end at the last state.
  for (int i = 0; i < 5; ++i) {
    session.rig().SetPose(0, Moved(session.rig().rig().cameras[0], Vec3(0.01, 0, 0)));
    session.UpdateFieldsInBackground();
  }
  EXPECT_EQ(session.WaitFields().state, JobState::kDone);
  std::int64_t version = -2;
  session.ReadFields([&](const Fields&, std::int64_t v) { version = v; });
  EXPECT_EQ(version, session.rig().version());
  ExpectFieldsOf(session, session.rig().rig(), options.fields);

  while (session.rig().Undo()) {
  }
  session.UpdateFields();
  ExpectFieldsOf(session, original, options.fields);
}

// --disable: the session's rig has the named cameras disabled (not as an edit: nothing to undo or
// save), its fields are those of that rig, and an unknown id is an InputError naming the option.
TEST(Session, DisabledCamerasAreOffForTheSessionOnly) {
  const auto study = Study::Load("tests/data/minimal.json");
  SessionOptions options;
  options.fields.fields = {"coverage", "cameras"};
  const Rig file_rig = study->FindRig("");
  ASSERT_GE(file_rig.cameras.size(), 2u);
  options.disable = {file_rig.cameras[1].id};
  Session session(study, options);
  EXPECT_TRUE(session.rig().rig().cameras[0].enabled);
  EXPECT_FALSE(session.rig().rig().cameras[1].enabled);
  EXPECT_FALSE(session.rig().can_undo());
  session.UpdateFields();
  Rig expected = file_rig;
  expected.cameras[1].enabled = false;
  ExpectFieldsOf(session, expected, options.fields);
  session.ReadFields(
      [&](const Fields& f, std::int64_t) { EXPECT_EQ(f.stats.per_camera_seen[1], 0); });

  options.disable = {file_rig.cameras[0].id, "no-such-camera"};
  try {
    Session bad(study, options);
    ADD_FAILURE() << "no error for an unknown id";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("{disable}"), std::string::npos) << message;
    EXPECT_NE(message.find("no camera 'no-such-camera' in rig '" + file_rig.name + "'"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find(file_rig.CameraIds()), std::string::npos) << message;
  }
}

// The interactive suggest-and-accept loop in memory: a suggestion runs in the background on the rig
// as it is, is applied as one undo step, undone, and refused once the rig has moved on.
TEST(Session, SuggestInTheBackgroundThenApplyAndUndo) {
  const auto study = Study::Load("tests/data/suggest_ring.json");
  SessionOptions options;
  options.fields.fields = {"coverage"};
  Session session(study, options);
  const Rig original = session.rig().rig();
  SuggestOptions so;
  so.cameras = {0};
  so.limits.resize(1);
  so.limits[0].max_move = 0.3;
  so.limits[0].max_rotate_deg = 10;
  so.screening_candidates = 20;
  so.outer_iterations = 2;
  so.scene_path = study->scene().path;
  const auto targets = SampleTargets(study->scene(), 200, {}, false, 1);
  session.SuggestInBackground(targets, so);
  JobStatus status;
  const std::optional<Suggestion> s = session.WaitSuggestion(&status);
  ASSERT_TRUE(s) << JobStateName(status.state) << " " << status.error;
  ASSERT_EQ(s->cameras.size(), 1u);
  session.ApplySuggestion(*s);
  EXPECT_EQ(session.rig().rig().cameras[0].world_from_camera.matrix(),
            s->cameras[0].after.matrix());
  EXPECT_EQ(session.rig().undo_label(), "accept suggestion (1 cameras)");
  // The fields follow the accepted poses.
  session.UpdateFields();
  ExpectFieldsOf(session, session.rig().rig(), options.fields);
  ASSERT_TRUE(session.rig().Undo());
  EXPECT_TRUE(SameRig(session.rig().rig(), original));
  // Camera 0 moves by hand: the suggestion no longer applies.
  session.rig().SetPose(0, Moved(original.cameras[0], Vec3(0.01, 0, 0)));
  if (!s->cameras[0].after.isApprox(original.cameras[0].world_from_camera)) {
    EXPECT_THROW(session.ApplySuggestion(*s), InputError);
  }
}

TEST(Session, SuggestOnTheCallingThreadEqualsTheBackgroundJob) {
  const auto study = Study::Load("tests/data/suggest_ring.json");
  Session session(study, SessionOptions());
  SuggestOptions so;
  so.cameras = {1};
  so.limits.resize(1);
  so.limits[0].max_move = 0.2;
  so.limits[0].max_rotate_deg = 5;
  so.screening_candidates = 10;
  so.outer_iterations = 1;
  const auto targets = SampleTargets(study->scene(), 150, {}, false, 2);
  const Suggestion now = session.Suggest(targets, so);
  session.SuggestInBackground(targets, so);
  const std::optional<Suggestion> later = session.WaitSuggestion();
  ASSERT_TRUE(later);
  ASSERT_EQ(now.cameras.size(), later->cameras.size());
  EXPECT_EQ(now.cameras[0].after.matrix(), later->cameras[0].after.matrix());  // deterministic
  EXPECT_EQ(now.after.objective, later->after.objective);
}

TEST(Session, RenderInTheBackgroundRefinesToTheExactFrameOfTheNewestRig) {
  const auto study = Study::Load("tests/data/minimal.json");
  Session session(study, SessionOptions());
  RenderView view;
  view.from = Vec3(3, -3, 2.5);
  view.at = Vec3(0, 0, 0.5);
  view.width = 96;
  view.height = 64;
  RenderOptions options;
  options.layers = true;
  const Rig original = session.rig().rig();
  // A frame of the original rig is asked for, then one with camera 0 off: the newest wins.
  std::mutex mutex;
  std::vector<std::pair<int, std::int64_t>> passes;  // (pass, rig version)
  Image last;
  auto on_pass = [&](const Image& image, int pass, std::int64_t version) {
    std::lock_guard<std::mutex> lock(mutex);
    passes.emplace_back(pass, version);
    last = image;
  };
  session.RenderInBackground(view, options, nullptr, on_pass);
  session.rig().SetEnabled(0, false);
  const std::int64_t moved_version = session.rig().version();
  session.RenderInBackground(view, options, nullptr, on_pass);
  EXPECT_EQ(session.jobs().Wait("render").state, JobState::kDone);
  ASSERT_FALSE(passes.empty());
  // The newest frame ran every pass in order, and its last pass is the exact frame, bit for bit.
  std::vector<int> newest;
  for (const auto& [pass, version] : passes)
    if (version == moved_version) newest.push_back(pass);
  EXPECT_EQ(newest, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(passes.back(), std::make_pair(3, moved_version));
  RenderStats stats;
  const Image exact = session.Render(view, options, nullptr, &stats);
  EXPECT_EQ(last.rgb, exact.rgb);
  EXPECT_EQ(last.cameras, exact.cameras);
  EXPECT_EQ(last.sigma_max, exact.sigma_max);
  // The session's frame is the one-shot renderer's for the edited rig.
  const Image one_shot =
      pandora::Render(study->scene(), session.rig().rig(), study->caster(), view, options);
  EXPECT_EQ(one_shot.rgb, exact.rgb);
  // ...and differs from the original rig's (camera 0 lit part of the block).
  const Image before = pandora::Render(study->scene(), original, study->caster(), view, options);
  EXPECT_NE(before.cameras, exact.cameras);
}

TEST(Autosave, WritesOnlyEditedCamerasAndRecoversThemAsOneUndoStep) {
  const fs::path scene = CopyScene("autosave");
  const std::string path = AutosavePath(scene.string());
  Rig edited;
  {
    Session session(Study::Load(scene.string()), SessionOptions());
    WriteAutosave(session, path);
    EXPECT_FALSE(fs::exists(path));  // nothing edited: no file
    const Rig& rig = session.rig().rig();
    session.rig().SetPose(1, Moved(rig.cameras[1], Vec3(0.05, -0.02, 0.1)));
    Intrinsics k = session.rig().rig().cameras[1].model.intrinsics();
    k.fx *= 1.25;
    k.fy *= 1.25;
    session.rig().SetIntrinsics(1, k);
    session.rig().SetEnabled(0, false);
    WriteAutosave(session, path);
    edited = session.rig().rig();
    // The session "crashes" here: the scene file was never written.
  }
  ASSERT_TRUE(fs::exists(path));
  const std::string scene_text = Read(scene);
  Session again(Study::Load(scene.string()), SessionOptions());
  const Rig original = again.rig().rig();
  const std::optional<Autosave> a = ReadAutosave(path, again.study());
  ASSERT_TRUE(a);
  EXPECT_FALSE(a->stale);
  ASSERT_EQ(a->cameras.size(), 2u);  // only the two edited cameras
  const std::vector<std::string> ids = RecoverAutosave(again, *a, path);
  EXPECT_EQ(ids, (std::vector<std::string>{original.cameras[0].id, original.cameras[1].id}));
  EXPECT_EQ(again.rig().undo_label(), "recover autosave (2 cameras)");
  for (int c : {0, 1}) {
    const Camera& x = again.rig().rig().cameras[c];
    const Camera& y = edited.cameras[c];
    EXPECT_EQ(x.enabled, y.enabled);
    EXPECT_LT((x.world_from_camera.matrix() - y.world_from_camera.matrix()).norm(), 1e-12);
    EXPECT_EQ(x.model.intrinsics().fx, y.model.intrinsics().fx);
  }
  EXPECT_EQ(Read(scene), scene_text);  // recovery writes nothing into the scene
  ASSERT_TRUE(again.rig().Undo());
  EXPECT_TRUE(SameRig(again.rig().rig(), original));

  // Damaged autosaves name the file and the JSON path; a changed scene makes it stale.
  auto expect_error = [&](const std::string& text, const std::string& json_path) {
    std::ofstream(path, std::ios::binary) << text;
    try {
      ReadAutosave(path, again.study());
      ADD_FAILURE() << "expected InputError for " << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.json_path(), json_path) << e.what();
    }
  };
  expect_error("{not json", "$");
  expect_error("[]", "$");
  expect_error(R"({"pandora_autosave": 2})", "$.pandora_autosave");
  expect_error(R"({"pandora_autosave": 1, "scene_sha256": "x", "rig": "nope", "cameras": []})",
               "$.rig");
  expect_error(R"({"pandora_autosave": 1, "scene_sha256": "x", "rig": ")" + original.name +
                   R"(", "cameras": [{"id": "zz", "position": [0, 0, 1], "look_at": [1, 0, 1],
                   "resolution": [64, 48], "hfov_deg": 60}]})",
               "$.cameras[0].id");
  expect_error(
      R"({"pandora_autosave": 1, "scene_sha256": "x", "rig": ")" + original.name +
          R"(", "cameras": [{"id": ")" + original.cameras[0].id +
          R"(", "position": [0, 0, "one"], "look_at": [1, 0, 1], "resolution": [64, 48], "hfov_deg": 60}]})",
      "$.cameras[0].position[2]");
  std::ofstream(path, std::ios::binary)
      << R"({"pandora_autosave": 1, "scene_sha256": "0000", "rig": ")" + original.name +
             R"(", "cameras": [{"id": ")" + original.cameras[0].id +
             R"(", "position": [0, 0, 1], "look_at": [1, 0, 1], "resolution": [64, 48], "hfov_deg": 60}]})";
  const std::optional<Autosave> stale = ReadAutosave(path, again.study());
  ASSERT_TRUE(stale);
  EXPECT_TRUE(stale->stale);
  EXPECT_THROW(RecoverAutosave(again, *stale, path), InputError);
}

TEST(Session, TryReadFieldsReadsWhenNoUpdateHoldsThem) {
  Session session(Study::Load("tests/data/minimal.json"), SessionOptions());
  session.UpdateFields();
  std::int64_t tried = -5, read = -6;
  EXPECT_TRUE(session.TryReadFields([&](const Fields&, std::int64_t v) { tried = v; }));
  session.ReadFields([&](const Fields&, std::int64_t v) { read = v; });
  EXPECT_EQ(tried, read);
  EXPECT_EQ(tried, session.rig().version());
}

TEST(Session, UnknownRigNamesTheOption) {
  const auto study = Study::Load("tests/data/minimal.json");
  SessionOptions options;
  options.rig = "nope";
  options.rig_option = "--rig";
  try {
    Session session(study, options);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "--rig");
  }
}

TEST(Session, SaveWritesPosesWithABackupAndRefusesWhatItCannotWrite) {
  const fs::path path = CopyScene("save");
  const std::string original_text = Read(path);
  const auto study = Study::Load(path.string());
  SessionOptions options;
  Session session(study, options);
  const Rig original = session.rig().rig();
  EXPECT_TRUE(session.Save().saved.empty());  // nothing edited: nothing written
  EXPECT_FALSE(fs::exists(path.string() + ".bak"));

  const Eigen::Isometry3d pose = Moved(original.cameras[0], Vec3(0.25, -0.5, 0.125));
  session.rig().SetPose(0, pose);
  const SaveResult r = session.Save();
  EXPECT_EQ(r.saved, std::vector<std::string>{original.cameras[0].id});
  EXPECT_EQ(Read(r.backup_path), original_text);
  const Scene saved = LoadScene(path.string());
  EXPECT_LT((saved.rigs[0].cameras[0].center() - pose.translation()).norm(), 1e-9);
  EXPECT_TRUE(session.rig().Unsaved().empty());

  // A change saving cannot write is refused, the file untouched.
  session.rig().SetEnabled(1, false);
  const std::string text = Read(path);
  EXPECT_THROW(session.Save(), InputError);
  EXPECT_EQ(Read(path), text);
  session.rig().Undo();

  // Someone else changed the file: refused unless forced.
  Eigen::Isometry3d higher = pose;
  higher.translation() += Vec3(0, 0, 0.1);
  session.rig().SetPose(0, higher);
  { std::ofstream(path, std::ios::app) << "\n"; }
  EXPECT_THROW(session.Save(), InputError);
  const SaveResult forced = session.Save(true);
  EXPECT_EQ(forced.saved.size(), 1u);
  EXPECT_EQ(fs::path(forced.backup_path).filename(), "scene.json.bak.1");
}

}  // namespace
}  // namespace pandora::session
