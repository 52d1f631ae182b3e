#pragma once
/// \file session.h
/// The session layer (docs/architecture.md): one open study, one rig being edited with undo, its
/// fields kept up to date incrementally, and background jobs. The `pandora` commands run through
/// it (synchronously) and the viewer will too (in the background, latest wins).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "app/session/editable_rig.h"
#include "app/session/jobs.h"
#include "app/session/study.h"
#include "render/render.h"
#include "suggest/suggest.h"
#include "suggest/suggestion_file.h"
#include "volume/fields.h"
#include "volume/time_fields.h"

namespace pandora::session {

struct SessionOptions {
  std::string rig;         ///< Rig to edit; empty: the first.
  std::string rig_option;  ///< The option that named it ("{rig}"), for errors.
  /// Camera ids disabled in the rig for this session (DisableCameras), not an edit: nothing of it
  /// is saved. `disable_option` names the option in errors.
  std::vector<std::string> disable;
  std::string disable_option = "{disable}";
  FieldOptions fields;  ///< The fields to keep (names, budget, messages).
  /// Keep the evaluator's per-pair state so that edits update incrementally (an interactive
  /// session); false for one evaluation (a command), which then needs no more memory than
  /// EvaluateFields.
  bool incremental = true;
};

struct SaveResult {
  std::string scene_path, backup_path;
  std::vector<std::string> saved;           ///< Camera ids written.
  std::vector<std::string> saved_stations;  ///< Viewing stations written.
  std::vector<std::string> notes;           ///< As `pandora accept`'s (an `up` that changed, ...).
};

class Session {
 public:
  /// Throws InputError for an unknown rig or field list.
  Session(std::shared_ptr<const Study> study, SessionOptions options);
  ~Session();

  const Study& study() const { return *study_; }
  EditableRig& rig() { return rig_; }
  const EditableRig& rig() const { return rig_; }
  Jobs& jobs() { return jobs_; }

  /// Brings the fields to the rig as it is now, on the calling thread (what a command does).
  FieldUpdate UpdateFields();
  /// The same as a background job of kind "fields" (latest wins: an edit while it runs cancels it
  /// and the newest rig is evaluated next). Returns the job id.
  std::int64_t UpdateFieldsInBackground();
  JobStatus WaitFields() { return jobs_.Wait("fields"); }

  /// Calls fn(fields, rig version they reflect) under the fields' lock (-1: none yet).
  void ReadFields(const std::function<void(const Fields&, std::int64_t)>& fn) const;
  /// The same without waiting: false (and `fn` not called) while an update holds the fields. What a
  /// window drawing every frame calls, so that a background update never stalls a frame.
  bool TryReadFields(const std::function<void(const Fields&, std::int64_t)>& fn) const;
  /// Moves the fields out (a command that writes them); the next update evaluates in full.
  Fields TakeFields();

  /// A study with time samples (moving objects, people): the fields at every sample combined, as
  /// `pandora analyze` reports them over time (EvaluateFieldsOverTime with OverTimeOptions of the
  /// session's fields), for the rig as it is now, as a background job of kind "time" (latest wins).
  /// The live fields are the static scene's, the volume without the people; these are the numbers
  /// with them. Returns the job id, or 0 (nothing submitted) for a study without time samples.
  std::int64_t UpdateTimeInBackground();
  /// The last summary over time and the rig version it reflects; nothing before the first.
  std::optional<std::pair<TimeSummary, std::int64_t>> TimeNumbers() const;
  /// The scene's moving parts (MakeSceneParts), built at the first call and kept: what every
  /// evaluation over time of this session shares (the background numbers, the viewer's Compare).
  const RigidPartsRayCaster& Parts() const;
  /// The same summary for any `rig`, on the calling thread, over the session's moving parts
  /// (Parts()); nothing for a study without time samples, or when `cancel` was set.
  std::optional<TimeSummary> EvaluateOverTime(
      const Rig& rig, const std::atomic<bool>* cancel = nullptr,
      const std::function<void(double)>& progress = {}) const;

  /// Runs Suggest on the rig as it is now, on the calling thread (what `pandora suggest` does).
  Suggestion Suggest(const std::vector<TargetPoint>& targets, const SuggestOptions& options) const;
  /// The same as a background job of kind "suggest" (latest wins: a
  /// suggestion asked for later replaces a waiting one; a running one finishes but its result is
  /// dropped). Returns the job id; WaitSuggestion() gives the result.
  /// `keep` (may be null) is held until the job ends: what `options.sample_casters` point into
  /// (app::SuggestProblem).
  std::int64_t SuggestInBackground(std::vector<TargetPoint> targets, SuggestOptions options,
                                   std::shared_ptr<const void> keep = nullptr);
  /// Waits for the suggest job; the suggestion of the newest job, or nothing when it failed (the
  /// status says why) or was replaced.
  std::optional<Suggestion> WaitSuggestion(JobStatus* status = nullptr);
  /// Applies a suggestion's poses and zooms to the rig in memory as one undo step (the person
  /// accepts; nothing is written until Save). Throws InputError when a selected camera is no longer
  /// where the suggestion started from (the rig was edited since).
  void ApplySuggestion(const Suggestion& suggestion);

  /// Renders the rig as it is now from `view` over the study's prepared scene, on the calling
  /// thread (what `pandora render` does). Throws as pandora::Render does.
  Image Render(const RenderView& view, const RenderOptions& options,
               const PreparedOverlays* overlays = nullptr, RenderStats* stats = nullptr) const;
  /// The same as a background job of kind "render", progressively (render/progressive.h): coarse
  /// first, then refined; `on_pass` is called on the worker after each completed pass with the
  /// image, the pass (ProgressiveRender::kPasses - 1 is the exact image) and the rig version it
  /// shows. Latest wins: a newer render cancels this one between tiles. `overlays` (may be null) is
  /// kept alive by the job. Returns the job id; jobs().Wait("render") waits for it.
  std::int64_t RenderInBackground(
      const RenderView& view, const RenderOptions& options,
      std::shared_ptr<const PreparedOverlays> overlays,
      std::function<void(const Image& image, int pass, std::int64_t rig_version)> on_pass);
  /// The same with another rig in place of the edited one (a PTZ trace of it: PtzTracedRig);
  /// `rig_version` is still the edited rig's.
  std::int64_t RenderInBackground(
      Rig rig, const RenderView& view, const RenderOptions& options,
      std::shared_ptr<const PreparedOverlays> overlays,
      std::function<void(const Image& image, int pass, std::int64_t rig_version)> on_pass);

  /// A PTZ camera's current pan, tilt and zoom (clamped to its ranges; docs/ptz.md, "In the
  /// viewer"), one undo step: the camera's pose and focal lengths become PtzHead::CameraAt of it.
  /// Throws InputError (the scene file, the camera's JSON path) for a fixed camera.
  void SetPtzState(int index, const PtzState& state);
  /// "Re-centre" a PTZ camera (RecentredPtz in app/session/ptz_edit.h): home becomes the current
  /// view, pan and tilt 0, presets and ranges shifted; the camera's pose is unchanged. One undo
  /// step. Throws InputError when the shifted tilt range would fail the scene reader's check.
  void RecentrePtz(int index);
  /// "$.rigs[r].cameras[c]": camera `index` of the edited rig in the scene file.
  std::string CameraJsonPath(int index) const;

  /// Writes the edited cameras' poses and focal lengths into the scene file, keeping a backup, as
  /// `pandora accept` does (each in its camera's own form). Refuses (InputError) when the file
  /// changed on disk since it was loaded or last saved (unless `force`), when the study has no file
  /// text, or when an edit is of a kind the scene file cannot take this way (enabled, lens model,
  /// principal point, range, pixel noise): those are listed. `stations` (viewing stations moved in
  /// the session, suggest/suggestion_file.h ReplaceStations) are written in the same file write.
  /// A PTZ camera is written as the file describes it: position = pivot, orientation = home, the
  /// lens = the current zoom, and its "ptz" block's pan_deg / tilt_deg (after a re-centre also the
  /// shifted ranges and presets) through ReplacePtzHeads; the rest of its block keeps its text.
  SaveResult Save(bool force = false, const std::vector<StationMove>& stations = {});
  /// The scene file now holds `text` and the edited rig as it is now is what it says (an accept
  /// written outside the session, e.g. by AcceptSuggestion after ApplySuggestion): the rig counts
  /// as saved and the next Save compares the file on disk with `text`.
  void MarkSaved(std::string text);

 private:
  std::shared_ptr<const Study> study_;
  SessionOptions options_;
  EditableRig rig_;
  std::string saved_text_;  // the scene file as loaded or last saved
  mutable std::mutex fields_mutex_;
  std::unique_ptr<FieldEvaluator> evaluator_;
  std::int64_t fields_version_ = -1;
  mutable std::mutex parts_mutex_;
  mutable std::unique_ptr<RigidPartsRayCaster> parts_;  // built at the first evaluation over time
  mutable std::mutex time_mutex_;
  std::optional<std::pair<TimeSummary, std::int64_t>> time_;
  std::mutex suggestion_mutex_;
  std::optional<Suggestion> suggestion_;
  std::int64_t suggestion_job_ = 0;
  Jobs jobs_;  // last: destroyed (workers joined) first
};

}  // namespace pandora::session
