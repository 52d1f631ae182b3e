#include "app/session/session.h"

#include <algorithm>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/motion.h"
#include "analysis/scene/scene_text.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "app/session/camera_edits.h"
#include "app/session/ptz_edit.h"
#include "render/progressive.h"
#include "suggest/suggestion_file.h"

namespace pandora::session {

Session::Session(std::shared_ptr<const Study> study, SessionOptions options)
    : study_(std::move(study)),
      options_(std::move(options)),
      rig_(DisableCameras(study_->FindRig(options_.rig, options_.rig_option), options_.disable,
                          options_.disable_option)),
      saved_text_(study_->text()) {
  if (!options_.fields.solid_trees) options_.fields.solid_trees = &study_->solid_trees();
  evaluator_ = std::make_unique<FieldEvaluator>(study_->scene(), study_->caster(), options_.fields,
                                                options_.incremental);
}

Session::~Session() = default;

FieldUpdate Session::UpdateFields() {
  std::lock_guard<std::mutex> lock(fields_mutex_);
  evaluator_->SetCallbacks(options_.fields.progress, options_.fields.cancel);
  const std::int64_t version = rig_.version();
  const FieldUpdate u = evaluator_->Update(rig_.rig());
  if (!u.cancelled) fields_version_ = version;
  return u;
}

std::int64_t Session::UpdateFieldsInBackground() {
  // The job evaluates a copy: the owner may edit on while it runs.
  auto snapshot = std::make_shared<Rig>(rig_.rig());
  const std::int64_t version = rig_.version();
  return jobs_.Submit("fields", [this, snapshot, version](JobContext& job) {
    std::lock_guard<std::mutex> lock(fields_mutex_);
    if (job.cancelled()) return;
    evaluator_->SetCallbacks([&job](double f) { job.Progress(f); }, &job.cancel_flag());
    const FieldUpdate u = evaluator_->Update(*snapshot);
    evaluator_->SetCallbacks(nullptr, nullptr);
    if (!u.cancelled) fields_version_ = version;
  });
}

void Session::ReadFields(const std::function<void(const Fields&, std::int64_t)>& fn) const {
  std::lock_guard<std::mutex> lock(fields_mutex_);
  fn(evaluator_->fields(), fields_version_);
}

bool Session::TryReadFields(const std::function<void(const Fields&, std::int64_t)>& fn) const {
  std::unique_lock<std::mutex> lock(fields_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return false;
  fn(evaluator_->fields(), fields_version_);
  return true;
}

const RigidPartsRayCaster& Session::Parts() const {
  std::lock_guard<std::mutex> lock(parts_mutex_);
  if (!parts_) parts_ = MakeSceneParts(study_->scene());
  return *parts_;
}

std::optional<TimeSummary> Session::EvaluateOverTime(
    const Rig& rig, const std::atomic<bool>* cancel,
    const std::function<void(double)>& progress) const {
  const Scene& scene = study_->scene();
  if (!scene.Animated() && !scene.study.targets) return std::nullopt;
  const std::vector<TimeSample> samples = scene.TimeSamples();
  if (samples.empty()) return std::nullopt;
  FieldOptions options = OverTimeOptions(options_.fields);
  options.progress = progress;
  options.cancel = cancel;
  TimeFieldsResult r =
      EvaluateFieldsOverTime(scene, rig, Parts(), samples, options, scene.TimeMinCameras());
  if (cancel && cancel->load()) return std::nullopt;
  return std::move(r.summary);
}

std::int64_t Session::UpdateTimeInBackground() {
  const Scene& scene = study_->scene();
  if ((!scene.Animated() && !scene.study.targets) || scene.TimeSamples().empty()) return 0;
  auto snapshot = std::make_shared<Rig>(rig_.rig());
  const std::int64_t version = rig_.version();
  return jobs_.Submit("time", [this, snapshot, version](JobContext& job) {
    if (job.cancelled()) return;
    std::optional<TimeSummary> t =
        EvaluateOverTime(*snapshot, &job.cancel_flag(), [&job](double f) { job.Progress(f); });
    if (!t) return;  // a newer rig is on its way
    std::lock_guard<std::mutex> lock(time_mutex_);
    time_ = std::make_pair(std::move(*t), version);
  });
}

std::optional<std::pair<TimeSummary, std::int64_t>> Session::TimeNumbers() const {
  std::lock_guard<std::mutex> lock(time_mutex_);
  return time_;
}

Fields Session::TakeFields() {
  std::lock_guard<std::mutex> lock(fields_mutex_);
  fields_version_ = -1;
  return evaluator_->TakeFields();
}

Suggestion Session::Suggest(const std::vector<TargetPoint>& targets,
                            const SuggestOptions& options) const {
  return pandora::Suggest(study_->scene(), rig_.rig(), study_->caster(), targets, options);
}

Image Session::Render(const RenderView& view, const RenderOptions& options,
                      const PreparedOverlays* overlays, RenderStats* stats) const {
  return RenderWithStats(study_->prepared(), rig_.rig(), view, options, overlays, stats);
}

std::int64_t Session::RenderInBackground(
    const RenderView& view, const RenderOptions& options,
    std::shared_ptr<const PreparedOverlays> overlays,
    std::function<void(const Image&, int, std::int64_t)> on_pass) {
  return RenderInBackground(rig_.rig(), view, options, std::move(overlays), std::move(on_pass));
}

std::int64_t Session::RenderInBackground(
    Rig rig_to_render, const RenderView& view, const RenderOptions& options,
    std::shared_ptr<const PreparedOverlays> overlays,
    std::function<void(const Image&, int, std::int64_t)> on_pass) {
  auto rig = std::make_shared<Rig>(std::move(rig_to_render));
  const std::int64_t version = rig_.version();
  const Study* study = study_.get();
  return jobs_.Submit("render", [study, rig, version, view, options, overlays = std::move(overlays),
                                 on_pass = std::move(on_pass)](JobContext& job) {
    ProgressiveRender frame(study->prepared(), *rig, view, options, overlays.get());
    RenderControl control;
    control.cancel = &job.cancel_flag();
    control.progress = [&job](double f) { job.Progress(f); };
    while (!frame.done()) {
      if (!frame.RunPass(control)) return;  // a newer frame was asked for
      if (on_pass) on_pass(frame.image(), frame.passes_done() - 1, version);
    }
  });
}

std::int64_t Session::SuggestInBackground(std::vector<TargetPoint> targets, SuggestOptions options,
                                          std::shared_ptr<const void> keep) {
  auto rig = std::make_shared<Rig>(rig_.rig());
  auto data = std::make_shared<std::pair<std::vector<TargetPoint>, SuggestOptions>>(
      std::move(targets), std::move(options));
  {
    std::lock_guard<std::mutex> lock(suggestion_mutex_);
    suggestion_.reset();
  }
  const std::int64_t job =
      jobs_.Submit("suggest", [this, rig, data, keep = std::move(keep)](JobContext& context) {
        // Cancel stops the search itself (it returns its best so far, discarded here).
        SuggestOptions options = data->second;
        options.cancel = &context.cancel_flag();
        options.progress = [&context](double fraction) { context.Progress(fraction); };
        Suggestion s =
            pandora::Suggest(study_->scene(), *rig, study_->caster(), data->first, options);
        if (context.cancelled()) return;  // a newer suggestion was asked for
        std::lock_guard<std::mutex> lock(suggestion_mutex_);
        suggestion_ = std::move(s);
      });
  std::lock_guard<std::mutex> lock(suggestion_mutex_);
  suggestion_job_ = job;
  return job;
}

std::optional<Suggestion> Session::WaitSuggestion(JobStatus* status) {
  const JobStatus s = jobs_.Wait("suggest");
  if (status) *status = s;
  std::lock_guard<std::mutex> lock(suggestion_mutex_);
  if (s.state != JobState::kDone || s.id != suggestion_job_) return std::nullopt;
  return suggestion_;
}

void Session::ApplySuggestion(const Suggestion& suggestion) {
  std::vector<EditableRig::Pose> poses;
  for (const pandora::CameraChange& c : suggestion.cameras) {
    const int index = rig_.Find(c.id);
    if (index < 0 || rig_.rig().cameras[index].world_from_camera.matrix() != c.before.matrix())
      throw InputError(study_->scene().path, "",
                       "camera '" + c.id + "' is no longer where the suggestion started from",
                       "ask for a new suggestion on the rig as it is now");
    poses.push_back({c.id, c.after, c.focal_scale});
  }
  rig_.SetPoses(poses, "accept suggestion (" + std::to_string(poses.size()) + " cameras)",
                study_->scene().path);
}

std::string Session::CameraJsonPath(int index) const {
  const Scene& scene = study_->scene();
  std::size_t r = 0;
  while (r < scene.rigs.size() && scene.rigs[r].name != rig_.rig().name) ++r;
  return "$.rigs[" + std::to_string(r) + "].cameras[" + std::to_string(index) + "]";
}

void Session::SetPtzState(int index, const PtzState& state) {
  const Camera& before = rig_.rig().cameras.at(index);
  if (!before.ptz)
    throw InputError(study_->scene().path, CameraJsonPath(index),
                     "camera '" + before.id + "' has no pan-tilt-zoom head",
                     "pan, tilt and zoom apply to a camera with a \"ptz\" block (docs/ptz.md)");
  rig_.Apply({"pan/tilt/zoom " + before.id, {{index, before, WithPtzState(before, state)}}});
}

void Session::RecentrePtz(int index) {
  rig_.rig().cameras.at(index);  // std::out_of_range for a wrong index, as before
  rig_.Apply(
      MakeEdit(rig_.rig(), RecentreEdit{index, study_->scene().path, CameraJsonPath(index)}).edit);
}

SaveResult Session::Save(bool force, const std::vector<StationMove>& stations) {
  const Scene& scene = study_->scene();
  if (saved_text_.empty())
    throw InputError(scene.path, "", "this study was not loaded from a file", "nothing to save to");
  const Rig& now = rig_.rig();
  const Rig& before = rig_.saved();
  std::vector<PoseUpdate> poses;
  std::vector<PtzHeadUpdate> heads;
  std::vector<std::string> saved;  // camera ids written
  std::string unsupported;
  for (int c : rig_.Unsaved()) {
    const Camera& a = before.cameras[c];
    const Camera& b = now.cameras[c];
    const Intrinsics& p = a.model.intrinsics();
    const Intrinsics& q = b.model.intrinsics();
    // What ReplacePoses writes: the pose and the focal lengths.
    Camera other = a;
    other.world_from_camera = b.world_from_camera;
    Intrinsics k = p;
    k.fx = q.fx;
    k.fy = q.fy;
    other.model = CameraModel(k);
    if (!SameCameraGeometry(other, b) || a.name != b.name || a.color != b.color ||
        !a.ptz != !b.ptz) {
      unsupported += (unsupported.empty() ? "" : ", ") + b.id;
      continue;
    }
    saved.push_back(b.id);
    PoseUpdate u;
    u.id = b.id;
    if (b.ptz) {
      // The file pose of a PTZ camera is its home at the pivot (its text is kept while home stays);
      // the zoom and the ptz block are written by ReplacePtzHeads.
      heads.push_back({b.id, *a.ptz, *b.ptz, q});
      if (b.ptz->home.matrix() == a.ptz->home.matrix()) continue;
      u.pose = b.ptz->home;
    } else {
      u.pose = b.world_from_camera;
      if (p.fx != q.fx || p.fy != q.fy) u.focal_px = Vec2(q.fx, q.fy);
    }
    poses.push_back(std::move(u));
  }
  if (!unsupported.empty())
    throw InputError(scene.path, "",
                     "cameras " + unsupported +
                         " have changes other than pose and focal length, which "
                         "saving does not write yet",
                     "undo those changes or edit the scene file by hand");
  SaveResult result;
  result.scene_path = scene.path;
  if (saved.empty() && stations.empty()) return result;
  // The file must be the one the session knows, or the edits would overwrite someone's changes.
  const std::string on_disk = ReadInputFile(scene.path, InputLimits::kJsonBytes, "scene file");
  if (!force && on_disk != saved_text_)
    throw InputError(scene.path, "", "the scene file changed on disk since it was loaded",
                     "reload it, or save with force to overwrite (a backup is kept)");
  std::string text = ReplacePoses(on_disk, scene.path, now.name, poses, &result.notes);
  if (!heads.empty()) text = ReplacePtzHeads(text, scene.path, now.name, heads);
  if (!stations.empty()) text = ReplaceStations(text, scene.path, stations);
  result.backup_path = ReplaceSceneFileWithBackup(scene.path, on_disk, text);
  result.saved = saved;
  for (const StationMove& s : stations) result.saved_stations.push_back(s.name);
  saved_text_ = text;
  rig_.MarkSaved();
  return result;
}

void Session::MarkSaved(std::string text) {
  saved_text_ = std::move(text);
  rig_.MarkSaved();
}

}  // namespace pandora::session
