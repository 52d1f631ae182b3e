#pragma once
/// \file model.h
/// What the viewer shows and edits, without GL: the session (study, rig being edited with undo,
/// fields kept up to date in the background, suggest), the selection, the main view, the display
/// settings, the pending suggestion, and the autosave. Every UI action, from the window or from a
/// script, is ViewerModel::Do(action): the GL front end draws the model and turns input into
/// actions; the unit tests run whole sessions through Do with the exact CPU renderer standing in
/// for the GPU (CpuFrontend).

#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/session/camera_edits.h"
#include "app/session/session.h"
#include "viewer/core/navigation.h"
#include "viewer/core/script.h"
#include "volume/rig_comparison.h"

namespace pandora::viewer {

class ViewerModel;

/// Shares of the voxels of a field evaluation's coverage histogram seen by at least k cameras:
/// entry k - 1 for k = 1, 2, ... (0 for an empty histogram).
/// The script action key of an option field (`{field}` in a library's error,
/// analysis/util/error.h): the viewer's one table, e.g. "max_rotate_deg" -> "max_rotate", "cameras"
/// -> "suggest"; else the field itself.
std::string ActionKey(const std::string& field);

std::vector<double> CoverageAtLeast(const std::vector<std::int64_t>& histogram);

/// What a front end does for the actions that need a window: screenshots, raw input, frames.
class Frontend {
 public:
  virtual ~Frontend() = default;
  /// Writes `path` (PNG): the main view, or camera `camera`'s own view when it is >= 0.
  virtual void Screenshot(const ViewerModel& model, const std::string& path, int camera) = 0;
  /// Mouse, key, scroll and frame actions (the GL front end feeds them to GLFW and Dear ImGui).
  virtual void Input(ViewerModel& model, const Action& action) {
    (void)model;
    (void)action;
  }
};

/// The exact CPU renderer as a front end: screenshots through Session::Render with the model's
/// view, settings and slice / isosurface over the current fields. Raw input is refused.
class CpuFrontend : public Frontend {
 public:
  void Screenshot(const ViewerModel& model, const std::string& path, int camera) override;
  void Input(ViewerModel& model, const Action& action) override;
};

struct ViewerOptions {
  std::string rig;  ///< Empty: the first.
  std::vector<std::string>
      disable;  ///< Camera ids disabled for the session (--disable; not saved).
  std::vector<std::string>
      fields;                 ///< Live fields; empty: coverage, cameras, resolution, sigma_max.
  std::string autosave_path;  ///< Empty: no autosave.
  int width = 1280, height = 720;  ///< The main view.
};

class ViewerModel {
 public:
  /// Throws InputError for an unknown rig or field.
  ViewerModel(std::shared_ptr<const session::Study> study, ViewerOptions options);
  ~ViewerModel();

  session::Session& session() { return *session_; }
  const session::Session& session() const { return *session_; }
  const Rig& rig() const { return session_->rig().rig(); }
  const Scene& scene() const { return session_->study().scene(); }

  /// Runs one action. Throws InputError naming the script's `where` for an action that cannot
  /// apply (an unknown camera id, accept without a suggestion, a field that is not live).
  void Do(const Action& action, Frontend* frontend);
  /// Runs every action of a script in order.
  void Run(const std::vector<Action>& script, Frontend* frontend);

  // What the front end draws.
  OrbitView view;
  int width = 1280, height = 720;
  RenderOptions display;       ///< Pattern, surface, brightness, grid, slice and isosurface.
  std::vector<int> selection;  ///< Rig indices.
  std::optional<Suggestion> suggestion;  ///< Suggested poses waiting for accept or reject (ghosts).
  /// What the suggestion asked for last is evaluated on, in words ("1500 points of the study
  /// region", "the study's targets at 6 time samples"), for the Suggest panel.
  std::string suggestion_targets;
  bool suggestion_over_time =
      false;           ///< It was asked for over time (the panel shows what was asked).
  std::string status;  ///< The last action's one-line message.
  /// The scene's viewing stations as placed in this session; Save writes the moved ones (eye and
  /// display centre) into the scene file with the cameras. Station moves are not undo steps.
  std::map<std::string, ViewingStation> stations;
  /// The stations as loaded or last saved.
  std::map<std::string, ViewingStation> saved_stations;
  std::int64_t stations_version = 0;  ///< Bumps when a station moves.
  /// The last "compare": the edited rig (its live fields, as they were) first, then the rig as last
  /// saved and / or other rigs of the scene (each evaluated once and kept while it stays the same).
  std::optional<RigComparison> comparison;
  std::int64_t comparison_rig_version = -1;  ///< The edited rig's version it was made for.

  /// PTZ traces of the main view (docs/ptz.md): "single", "path" (one light per second home ->
  /// current) or "all" (everything reachable within the budget; the exact CPU renderer's
  /// RenderOptions::ptz_all); the budget in seconds, NaN: each head's trace_s.
  std::string ptz_trace = "single";
  double ptz_trace_s = std::numeric_limits<double>::quiet_NaN();
  /// The rig the main view lights: the edited rig with the PTZ cameras' traces (PtzTracedRig);
  /// `all` (may be null) receives the "all" traces for RenderOptions::ptz_all.
  Rig TracedRig(std::vector<RenderOptions::PtzTrace>* all) const;

  /// The main view as a plan or elevation (docs/viewer.md, "Plans and elevations"): "" (none: the
  /// orbit view `view`), "plan", "north", "south", "east" or "west". The main view is then
  /// PlanView of the scene's content bounds, cut at PlanDefaultCut of the study region (as
  /// `pandora render --plan` / `--elevation SIDE`), moved by plan_offset (world metres, in the
  /// picture's plane) and magnified plan_zoom times.
  std::string plan;
  Vec3 plan_offset = Vec3::Zero();
  double plan_zoom = 1;
  /// Sets the plan or elevation `side` ("plan", "north", ...), framed afresh (no offset, zoom 1).
  /// Throws std::invalid_argument for an unknown side.
  void SetPlan(const std::string& side);
  /// Leaves the plan mode: the orbit view then looks the same way at the content's centre (from a
  /// framing distance, perspective again). Nothing when not in it.
  void LeavePlan();
  /// Navigation that knows the plan mode: orbit leaves it (a plan is not a 3D view); pan moves the
  /// drawing under the cursor and dolly magnifies it (x 1 / 0.85 a step), staying orthographic and
  /// cut. Outside the plan mode, OrbitView's Orbit, Pan and Dolly.
  void Orbit(double dx_px, double dy_px);
  void Pan(double dx_px, double dy_px);
  void Dolly(double steps);

  /// The main view as the renderer takes it.
  RenderView MainView() const;
  /// The state as JSON, for `pandora view --log`: rig version, undo label, selection, cameras'
  /// poses, fields (version, shares seen by at least 1, 2, ... cameras, sigma_max median), the
  /// pending suggestion.
  nlohmann::json StateJson() const;
  /// Called after each action that edited the rig (the GL front end re-uploads cameras).
  std::function<void()> on_edit;

 private:
  int CameraIndex(const std::string& id, const Action& action) const;
  std::vector<int> CameraIndices(const std::vector<std::string>& ids, const Action& action) const;
  void Edited();  // fields in the background, autosave, on_edit
  void Compare(const Action& action);
  // What the camera edits of one Do share.
  struct EditStep {
    std::string drag;        // the label of the drag the action may amend, empty: none
    std::string ptz_status;  // a PTZ camera's setting after a pose edit
  };
  void ApplyEdit(const Action& a, EditStep& step, const std::vector<int>& cams,
                 const std::string& label, const std::function<void(Camera&)>& change);
  // A typed session edit (app/session/camera_edits.h): its errors as the action's keys.
  template <class TypedEdit>
  void ApplyTyped(const Action& a, EditStep& step, const std::vector<int>& cams,
                  const TypedEdit& edit);
  void Commit(const Action& a, EditStep& step, const std::vector<int>& cams,
              session::CameraEditResult made);
  std::string EditLabel(const char* verb, const std::vector<int>& cams) const;
  // Do's actions, one per kind or group (model.cpp).
  void DoMove(const Action& a, EditStep& step);
  void DoRotate(const Action& a, EditStep& step);
  void DoAim(const Action& a, EditStep& step);
  void DoOrient(const Action& a, EditStep& step);
  void DoEnable(const Action& a, EditStep& step);
  void DoHfov(const Action& a, EditStep& step);
  void DoIntrinsics(const Action& a, EditStep& step);
  void DoRange(const Action& a, EditStep& step);
  void DoColor(const Action& a, EditStep& step);
  void DoSliceIso(const Action& a);
  void DoView(const Action& a);
  void DoLight(const Action& a);
  void DoWait(const Action& a);
  void DoSuggest(const Action& a);
  void DoAccept(const Action& a);
  void DoSave(const Action& a);
  void DoScreenshot(const Action& a, Frontend* frontend);
  void DoGamepad(const Action& a, EditStep& step);
  void DoStation(const Action& a);
  void DoPtz(const Action& a, EditStep& step);
  void DoRecentre(const Action& a, EditStep& step);
  void DoTrace(const Action& a);
  std::vector<std::string> LiveFields() const;
  // Summaries of rigs other than the edited one, evaluated once (Compare).
  struct CachedSummary {
    Rig rig;
    Summary summary;
  };
  std::vector<CachedSummary> compare_cache_;
  std::string drag_label_;  // the drag in progress (its steps amend one edit), empty: none
  ViewerOptions options_;
  std::unique_ptr<session::Session> session_;
};

}  // namespace pandora::viewer
