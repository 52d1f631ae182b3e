#include "viewer/core/model.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/geometry/pose.h"
#include "analysis/rig/rig_check.h"
#include "analysis/util/error.h"
#include "analysis/util/output_transaction.h"
#include "analysis/util/units.h"
#include "app/session/analyze.h"
#include "app/session/autosave.h"
#include "app/session/camera_edits.h"
#include "app/session/ptz_edit.h"
#include "app/suggest_options.h"
#include "render/prepared_scene.h"
#include "viewer/core/manipulate.h"
#include "volume/fields.h"
#include "volume/summary.h"

namespace pandora::viewer {
namespace {

std::vector<std::string> DefaultFields() {
  return {"coverage", "cameras", "resolution", "sigma_max"};
}

Vec3 UpFor(const Vec3& from, const Vec3& at) {
  return std::abs((at - from).normalized().z()) > 0.99 ? Vec3(0, 1, 0) : Vec3(0, 0, 1);
}

LensModel LensFromName(const std::string& name) {
  return LensModelFromName(name).value_or(LensModel::kPinhole);
}

// What differs between a camera as saved and as edited that Session::Save cannot write (it writes
// poses and focal lengths): "resolution, range", empty when nothing.
std::string UnsavableChanges(const Camera& saved, const Camera& now) {
  const Intrinsics& p = saved.model.intrinsics();
  const Intrinsics& q = now.model.intrinsics();
  std::vector<std::string> what;
  if (p.width != q.width || p.height != q.height) what.push_back("resolution");
  if (p.cx != q.cx || p.cy != q.cy) {
    if (p.width == q.width && p.height == q.height) what.push_back("principal point");
  }
  if (p.model != q.model)
    what.push_back("lens model");
  else if (p.k1 != q.k1 || p.k2 != q.k2 || p.p1 != q.p1 || p.p2 != q.p2 || p.k3 != q.k3 ||
           p.k4 != q.k4)
    what.push_back("distortion");
  if (saved.near != now.near || saved.far != now.far) what.push_back("range");
  if (saved.color != now.color) what.push_back("colour");
  if (saved.enabled != now.enabled) what.push_back(now.enabled ? "switched on" : "switched off");
  if (saved.name != now.name) what.push_back("name");
  if (saved.pixel_sigma != now.pixel_sigma) what.push_back("pixel noise");
  std::string out;
  for (const std::string& w : what) out += (out.empty() ? "" : ", ") + w;
  return out;
}

std::string PtzStatus(const Camera& cam, bool clamped) {
  const PtzState& s = cam.ptz->current;
  char line[200];
  std::snprintf(
      line, sizeof line, "%s (PTZ): pan %.1f, tilt %.1f, hfov %.1f deg%s", cam.id.c_str(),
      s.pan_deg, s.tilt_deg,
      HfovFromFocal(s.focal, cam.model.width(), cam.model.intrinsics().model) / kRadPerDeg,
      clamped ? " (limited by its ranges)" : "");
  return line;
}

// A suggest action as the request every front end makes (app::PrepareSuggest): the viewer's
// Suggest panel and scripts optimise the same objective over the same points as the command.
app::SuggestRequest SuggestRequestOf(const Action& a) {
  app::SuggestRequest s;
  s.cameras = a.cameras;
  s.objective = a.text;
  s.max_move = {a.number};
  s.max_rotate_deg = {a.number2};
  s.points = int(a.number3);
  s.seed = a.seed;
  if (a.mount == "rail") s.rail.push_back({"", a.a});
  if (a.mount == "plane") s.plane.push_back({"", a.a});
  if (a.mount == "box") s.mount_box.push_back({"", a.mount_box});
  if (a.max_hfov > 0) s.hfov_range.push_back({"", {a.min_hfov, a.max_hfov}});
  s.keep_out = a.keep_out;
  if (!std::isnan(a.clearance)) s.clearance = a.clearance;
  if (!std::isnan(a.weights.x())) s.weights = a.weights;
  s.snap_move = a.snap_move;
  s.snap_rotate_deg = a.snap_rotate;
  s.outer_iterations = a.outer_iterations;
  s.target_surfaces = a.target_surfaces;
  s.with_region = a.with_region;
  s.over_time = a.over_time;
  return s;
}

// An error of `pandora suggest`'s options, renamed to the action's keys ("{max_move}" ->
// "$[8].max_move", and 'max_move' in the reason and hint).
[[noreturn]] void RethrowAsAction(const InputError& e, const std::string& where) {
  const std::string& f = e.file();
  if (f.size() < 3 || f.front() != '{' || f.back() != '}')
    throw e;  // the scene's own (a surface name, its targets)
  const InputError named =
      RenameOptions(e, [](const std::string& field) { return "'" + ActionKey(field) + "'"; });
  throw InputError(where + "." + ActionKey(f.substr(1, f.size() - 2)), named.json_path(),
                   named.reason(), named.hint());
}

// A typed camera edit's error (app/session/camera_edits.h) as the action's: a value's field as the
// action's key ("{hfov_deg}" -> "$[3].deg"), a camera's problem at the action ("$[3]").
[[noreturn]] void RethrowEditError(const InputError& e, const Action& a) {
  const std::string& f = e.file();
  const bool field = f.size() >= 3 && f.front() == '{' && f.back() == '}';
  if (!f.empty() && !field) throw e;  // a file's own (a PTZ head's ranges name the scene)
  const auto key = [&a](const std::string& name) {
    return a.kind == Action::Kind::kHfov && name == "hfov_deg" ? std::string("deg")
                                                               : ActionKey(name);
  };
  const InputError named =
      RenameOptions(e, [&key](const std::string& name) { return "'" + key(name) + "'"; });
  throw InputError(field ? a.where + "." + key(f.substr(1, f.size() - 2)) : a.where,
                   named.json_path(), named.reason(), named.hint());
}

}  // namespace

std::string ActionKey(const std::string& field) {
  // Only where the key differs from the field.
  static const std::pair<const char*, const char*> kKeys[] = {{"cameras", "suggest"},
                                                              {"mount_box", "box"},
                                                              {"max_rotate_deg", "max_rotate"},
                                                              {"snap_rotate_deg", "snap_rotate"},
                                                              {"target_surfaces", "target_surface"},
                                                              {"color", "rgb"}};
  for (const auto& [name, key] : kKeys)
    if (field == name) return key;
  return field;
}

std::vector<double> CoverageAtLeast(const std::vector<std::int64_t>& histogram) {
  std::int64_t total = 0;
  for (std::int64_t n : histogram) total += n;
  std::vector<double> shares;
  std::int64_t at_least = total;
  for (std::size_t k = 1; k < histogram.size(); ++k) {
    at_least -= histogram[k - 1];
    shares.push_back(total > 0 ? double(at_least) / total : 0.0);
  }
  return shares;
}

Rig ViewerModel::TracedRig(std::vector<RenderOptions::PtzTrace>* all) const {
  return session::PtzTracedRig(rig(), ptz_trace, ptz_trace_s, all);
}

void CpuFrontend::Screenshot(const ViewerModel& model, const std::string& path, int camera) {
  RenderOptions options = model.display;
  options.layers = false;
  options.pixel_sigma = model.scene().study.pixel_sigma;
  RenderView view = model.MainView();
  if (camera < 0 && !model.plan.empty())
    options.overlays.labels = true;  // camera ids, as render --plan
  if (camera >= 0) {
    // The camera's own image, scaled to fit the main view's size.
    const CameraModel& m = model.rig().cameras[camera].model;
    const double scale =
        std::min({1.0, double(model.width) / m.width(), double(model.height) / m.height()});
    view = RenderView();
    view.camera = camera;
    view.width = std::max(16, int(std::lround(m.width() * scale)));
    view.height = std::max(16, int(std::lround(m.height() * scale)));
  }
  std::unique_ptr<PreparedOverlays> overlays;
  if (!options.overlays.slice_field.empty() || !options.overlays.iso_field.empty())
    model.session().ReadFields([&](const Fields& fields, std::int64_t) {
      overlays = std::make_unique<PreparedOverlays>(fields, options.overlays);
    });
  if (camera < 0 && model.ptz_trace != "single") {
    // The traces light the main view, at the rig's brightness (as `pandora render --ptz`).
    if (std::isnan(options.brightness))
      options.brightness = DefaultBrightness(model.rig().enabled_count());
    const Rig traced = model.TracedRig(&options.ptz_all);
    WritePng(RenderWithStats(model.session().study().prepared(), traced, view, options,
                             overlays.get(), nullptr),
             path);
    return;
  }
  WritePng(model.session().Render(view, options, overlays.get()), path);
}

void CpuFrontend::Input(ViewerModel&, const Action& action) {
  if (action.kind == Action::Kind::kFrames) return;  // nothing to draw
  throw InputError(action.where, "", "raw input (mouse, key, scroll) needs the window",
                   "run the script in `pandora view`, not headless");
}

ViewerModel::ViewerModel(std::shared_ptr<const session::Study> study, ViewerOptions options)
    : options_(std::move(options)) {
  session::SessionOptions so;
  so.rig = options_.rig;
  so.rig_option = "--rig";
  so.disable = options_.disable;
  so.fields.fields = options_.fields.empty() ? DefaultFields() : options_.fields;
  so.fields.scene_path = study->scene().path;
  so.incremental = true;
  session_ = std::make_unique<session::Session>(study, so);
  width = options_.width;
  height = options_.height;
  const Scene& s = scene();
  if (!s.views.empty()) {
    // The scene's "overview" when it has one, else its first view (by name).
    const auto named = s.views.find("overview");
    const RenderView v = ViewFromScene((named != s.views.end() ? named : s.views.begin())->second,
                                       width, height, 50.0);
    view = OrbitView::FromLookAt(v.from, v.at, v.fov_deg);
  } else {
    view = OrbitView::Framing(s.Bounds());
  }
  display.pixel_sigma = s.study.pixel_sigma;
  display.layers = false;
  stations = s.stations;
  saved_stations = s.stations;
  session_->UpdateFieldsInBackground();
  session_->UpdateTimeInBackground();  // with people: the numbers over time too
}

ViewerModel::~ViewerModel() = default;

RenderView ViewerModel::MainView() const {
  if (plan.empty()) return view.ToRenderView(width, height);
  RenderView v = *PlanView(scene().ContentBounds(), plan, width, height,
                           PlanDefaultCut(scene().study.region.box, plan));
  // Panning moves eye and target in the picture's plane: the distance to the cut stays.
  v.from += plan_offset;
  v.at += plan_offset;
  v.fov_deg = 2.0 * std::atan(std::tan(0.5 * v.fov_deg * kPi / 180.0) / plan_zoom) * 180.0 / kPi;
  return v;
}

void ViewerModel::SetPlan(const std::string& side) {
  if (std::isnan(PlanDefaultCut(scene().study.region.box, side)))
    throw std::invalid_argument("SetPlan: unknown side '" + side + "'");
  plan = side;
  plan_offset = Vec3::Zero();
  plan_zoom = 1;
}

void ViewerModel::LeavePlan() {
  if (plan.empty()) return;
  const Aabb bounds = scene().ContentBounds();
  OrbitView o = OrbitView::Framing(bounds, view.fov_deg);
  o.target = bounds.center() + plan_offset;
  // The eye on the plan's side: yaw from +x towards +y of the eye's direction from the target.
  o.pitch_deg = plan == "plan" ? 89.0 : 0.0;
  o.yaw_deg = plan == "north" ? 90.0 : plan == "east" ? 0.0 : plan == "west" ? 180.0 : -90.0;
  view = o;
  plan.clear();
}

void ViewerModel::Orbit(double dx_px, double dy_px) {
  LeavePlan();
  view.Orbit(dx_px, dy_px);
}

void ViewerModel::Pan(double dx_px, double dy_px) {
  if (plan.empty()) return view.Pan(dx_px, dy_px, width);
  const RenderView v = MainView();
  const Vec3 forward = (v.at - v.from).normalized();
  const Vec3 right = forward.cross(v.up).normalized();
  const Vec3 up = right.cross(forward);
  // The scale at the framed centre: the picture is orthographic to 1 / kPlanDistance.
  const double metres_per_px =
      2.0 * (v.at - v.from).norm() * std::tan(0.5 * v.fov_deg * kPi / 180.0) / std::max(width, 1);
  plan_offset += metres_per_px * (-dx_px * right + dy_px * up);
}

void ViewerModel::Dolly(double steps) {
  if (plan.empty()) return view.Dolly(steps);
  plan_zoom = std::clamp(plan_zoom / std::pow(0.85, steps), 1e-2, 1e4);
}

int ViewerModel::CameraIndex(const std::string& id, const Action& action) const {
  const int c = rig().FindCamera(id);
  if (c < 0)
    throw InputError(action.where, "", "no camera '" + id + "' in rig '" + rig().name + "'",
                     "cameras: " + rig().CameraIds());
  return c;
}

std::vector<int> ViewerModel::CameraIndices(const std::vector<std::string>& ids,
                                            const Action& action) const {
  std::vector<int> out;
  for (const std::string& id : ids) out.push_back(CameraIndex(id, action));
  return out;
}

void ViewerModel::Edited() {
  session_->UpdateFieldsInBackground();
  session_->UpdateTimeInBackground();  // with people: the numbers over time too
  if (!options_.autosave_path.empty()) session::WriteAutosave(*session_, options_.autosave_path);
  if (on_edit) on_edit();
}

std::vector<std::string> ViewerModel::LiveFields() const {
  return options_.fields.empty() ? DefaultFields() : options_.fields;
}

void ViewerModel::Compare(const Action& a) {
  const std::vector<std::string> names = LiveFields();
  // Every rig asked for exists before anything is evaluated.
  std::vector<const Rig*> others;
  for (const std::string& name : a.cameras) {
    if (name == "saved") {
      others.push_back(&session_->rig().saved());
      continue;
    }
    const Rig* found = nullptr;
    std::string list;
    for (const Rig& r : scene().rigs) {
      if (r.name == name) found = &r;
      list += (list.empty() ? "" : ", ") + r.name;
    }
    if (!found)
      throw InputError(a.where, "", "no rig '" + name + "' in " + scene().path,
                       "compare with saved or " + list);
    others.push_back(found);
  }
  // The edited rig: its live fields once they have caught up.
  const session::JobStatus s = session_->WaitFields();
  if (s.state == session::JobState::kFailed && s.exception) std::rethrow_exception(s.exception);
  // Each rig's numbers as `pandora analyze` gives them, through the same conductor
  // (app/session/analyze.h): the warnings and, with moving objects, the numbers over the time
  // samples (the live fields are the static scene's: the volume without the people). The headline
  // rows only: no calibration, N-1, pixel targets, DORI or PTZ.
  session::AnalyzeOptions analysis;
  analysis.fields.fields = names;
  analysis.fields.scene_path = scene().path;
  analysis.threads = 1;
  analysis.pixel_targets = analysis.dori = analysis.ptz = false;
  analysis.calibration = analysis.robustness = false;
  // The moving parts once per session, not once per rig compared.
  if (scene().Animated() || scene().study.targets) analysis.parts = &session_->Parts();
  auto summarize = [&](const Rig& r, const Fields& f) {
    return session::CompleteAnalysis(scene(), session_->study().caster(), r, f, nullptr, analysis)
        .summary;
  };
  std::vector<Summary> summaries;
  // The fields have caught up (WaitFields): no update waits on this read meanwhile.
  session_->ReadFields(
      [&](const Fields& f, std::int64_t) { summaries.push_back(summarize(rig(), f)); });
  summaries.back().rig = rig().name + " (edited)";
  for (std::size_t i = 0; i < others.size(); ++i) {
    const Rig& other = *others[i];
    auto same = [&](const Rig& x) {
      if (x.name != other.name || x.cameras.size() != other.cameras.size()) return false;
      for (std::size_t c = 0; c < x.cameras.size(); ++c)
        if (!SameCameraGeometry(x.cameras[c], other.cameras[c])) return false;
      return true;
    };
    Summary summary;
    if (same(rig())) {
      summary = summaries.front();  // nothing edited: the live fields are this rig's
    } else {
      const auto hit = std::find_if(compare_cache_.begin(), compare_cache_.end(),
                                    [&](const CachedSummary& c) { return same(c.rig); });
      if (hit != compare_cache_.end()) {
        summary = hit->summary;
      } else {
        const Fields f =
            EvaluateFields(scene(), other, session_->study().caster(), analysis.fields);
        summary = summarize(other, f);
        compare_cache_.push_back({other, summary});
        if (compare_cache_.size() > 8) compare_cache_.erase(compare_cache_.begin());
      }
    }
    summary.rig = a.cameras[i] == "saved" ? other.name + " (saved)" : other.name;
    summaries.push_back(std::move(summary));
  }
  comparison = CompareRigs(summaries, scene().study);
  comparison_rig_version = session_->rig().version();
  status = "compared " + std::to_string(summaries.size()) + " rigs";
}

void ViewerModel::Run(const std::vector<Action>& script, Frontend* frontend) {
  for (const Action& a : script) Do(a, frontend);
}

// Applies camera changes as one undo step (a drag's later steps amend its first).
void ViewerModel::ApplyEdit(const Action& a, EditStep& step, const std::vector<int>& cams,
                            const std::string& label, const std::function<void(Camera&)>& change) {
  // The session's rule: a PTZ camera's base stays level and its head turns, so a pose or zoom
  // asked of it moves the pivot and becomes pan, tilt and zoom within its ranges (docs/ptz.md).
  Commit(a, step, cams, session::MakeCameraEdit(rig(), cams, label, change));
}

template <class TypedEdit>
void ViewerModel::ApplyTyped(const Action& a, EditStep& step, const std::vector<int>& cams,
                             const TypedEdit& edit) {
  session::CameraEditResult made;
  try {
    made = session::MakeEdit(rig(), edit);
  } catch (const InputError& e) {
    RethrowEditError(e, a);
  }
  Commit(a, step, cams, std::move(made));
}

void ViewerModel::Commit(const Action& a, EditStep& step, const std::vector<int>& cams,
                         session::CameraEditResult made) {
  session::EditableRig& edit = session_->rig();
  session::Edit& e = made.edit;
  const std::string label = e.label;
  for (const session::CameraEdit& ce : e.changes)
    if (ce.index == made.ptz_camera) step.ptz_status = PtzStatus(ce.after, made.clamped);
  if (a.drag && step.drag == label && edit.CanAmend(cams))
    edit.Amend(e);
  else
    edit.Apply(std::move(e));
  if (a.drag) drag_label_ = label;
  Edited();
}

// An edit's undo label: the verb and the camera's id, or the number of cameras.
std::string ViewerModel::EditLabel(const char* verb, const std::vector<int>& cams) const {
  return session::EditLabel(rig(), verb, cams);
}

// "move": the cameras by an offset, or one camera to a position.
void ViewerModel::DoMove(const Action& a, EditStep& step) {
  const std::vector<int> cams = CameraIndices(a.cameras, a);
  for (int c : cams) {
    const Vec3 target = a.flag ? a.a : rig().cameras[c].center() + a.a;
    scene().CheckReach(target, a.where, "the camera position");
  }
  ApplyEdit(a, step, cams, EditLabel("move", cams), [&](Camera& cam) {
    cam.world_from_camera.translation() =
        a.flag ? a.a : Vec3(cam.world_from_camera.translation() + a.a);
  });
}

// "rotate": the cameras rigidly about their mean centre.
void ViewerModel::DoRotate(const Action& a, EditStep& step) {
  const std::vector<int> cams = CameraIndices(a.cameras, a);
  Vec3 pivot = Vec3::Zero();
  std::vector<Eigen::Isometry3d> poses;
  for (int c : cams) {
    pivot += rig().cameras[c].center() / double(cams.size());
    poses.push_back(rig().cameras[c].world_from_camera);
  }
  const Mat3 R = Eigen::AngleAxisd(a.number * kRadPerDeg, a.a.normalized()).toRotationMatrix();
  const std::vector<Eigen::Isometry3d> moved = MoveRigidly(poses, pivot, Vec3::Zero(), R);
  std::size_t i = 0;
  ApplyEdit(a, step, cams, EditLabel("rotate", cams),
            [&](Camera& cam) { cam.world_from_camera = moved[i++]; });
}

// "aim": a camera turned to look at a point.
void ViewerModel::DoAim(const Action& a, EditStep& step) {
  const int c = CameraIndex(a.cameras[0], a);
  const Vec3 from = rig().cameras[c].center();
  const auto pose = LookAt(from, a.a, UpFor(from, a.a));
  if (!pose) throw InputError(a.where, "", "the camera cannot aim at its own position");
  ApplyEdit(a, step, {c}, EditLabel("aim", {c}),
            [&](Camera& cam) { cam.world_from_camera = *pose; });
}

// "orient": a camera turned to a yaw, pitch and roll.
void ViewerModel::DoOrient(const Action& a, EditStep& step) {
  const int c = CameraIndex(a.cameras[0], a);
  ApplyTyped(a, step, {c}, session::OrientEdit{c, a.a});
}

// "enable" and "disable": the cameras switched on or off.
void ViewerModel::DoEnable(const Action& a, EditStep& step) {
  const std::vector<int> cams = CameraIndices(a.cameras, a);
  ApplyTyped(a, step, cams, session::EnableEdit{cams, a.kind == Action::Kind::kEnable});
}

// "hfov": the cameras zoomed to a horizontal field of view.
void ViewerModel::DoHfov(const Action& a, EditStep& step) {
  const std::vector<int> cams = CameraIndices(a.cameras, a);
  ApplyTyped(a, step, cams, session::ZoomEdit{cams, a.number});
}

// "intrinsics": the cameras' resolution, lens model and distortion coefficients.
void ViewerModel::DoIntrinsics(const Action& a, EditStep& step) {
  session::LensEdit edit;
  edit.cameras = CameraIndices(a.cameras, a);
  edit.width = a.width;
  edit.height = a.height;
  if (!a.lens.empty()) edit.model = LensFromName(a.lens);
  std::copy(std::begin(a.coefficients), std::end(a.coefficients), edit.coefficients.begin());
  ApplyTyped(a, step, edit.cameras, edit);
}

// "range": the cameras' working range (near and / or far).
void ViewerModel::DoRange(const Action& a, EditStep& step) {
  const std::vector<int> cams = CameraIndices(a.cameras, a);
  ApplyTyped(a, step, cams, session::RangeEdit{cams, a.near, a.far});
}

// "color": the cameras' colour.
void ViewerModel::DoColor(const Action& a, EditStep& step) {
  const std::vector<int> cams = CameraIndices(a.cameras, a);
  ApplyTyped(a, step, cams, session::ColorEdit{cams, a.a});
}

// "slice" and "iso": the slice plane or the isosurface of a live field (or none).
void ViewerModel::DoSliceIso(const Action& a) {
  const bool slice = a.kind == Action::Kind::kSlice;
  if (!a.flag) {
    const std::vector<std::string> live =
        options_.fields.empty() ? DefaultFields() : options_.fields;
    if (std::find(live.begin(), live.end(), a.text) == live.end()) {
      std::string list;
      for (const std::string& f : live) list += (list.empty() ? "" : ", ") + f;
      throw InputError(a.where, "", "'" + a.text + "' is not a live field of this session",
                       "live: " + list);
    }
  }
  if (slice) {
    display.overlays.slice_field = a.text;
    display.overlays.slice_axis = a.text2 == "x" ? 0 : a.text2 == "y" ? 1 : 2;
    display.overlays.slice_position = a.number;
  } else {
    display.overlays.iso_field = a.text;
    if (!a.flag) display.overlays.iso_value = a.number;
  }
}

// "view": a plan, an elevation or one of the scene's views.
void ViewerModel::DoView(const Action& a) {
  const std::string& file = scene().path;
  if (a.text == "plan" || a.text == "elevation") {
    SetPlan(a.text == "plan" ? "plan" : a.text2);
    return;
  }
  const auto it = scene().views.find(a.text);
  if (it == scene().views.end()) {
    std::string names;
    for (const auto& [name, v] : scene().views) names += (names.empty() ? "" : ", ") + name;
    throw InputError(a.where, "", "no view '" + a.text + "' in " + file,
                     names.empty() ? "the scene defines no views" : "views: " + names);
  }
  const RenderView v = ViewFromScene(it->second, width, height, 50.0);
  plan.clear();
  view = OrbitView::FromLookAt(v.from, v.at, v.fov_deg);
}

// "light": the pattern, grid size, brightness and surface of the display.
void ViewerModel::DoLight(const Action& a) {
  display.pattern = PatternFromName(a.text).value_or(Pattern::kUniform);
  display.grid_pixels = int(a.number);
  display.brightness = a.number2;
  display.surface = SurfaceFromName(a.text2).value_or(Surface::kMaterial);
}

// "wait": for the fields, the suggestion or the render job.
void ViewerModel::DoWait(const Action& a) {
  if (a.text == "fields") {
    for (const char* kind : {"fields", "time"}) {
      const session::JobStatus s = session_->jobs().Wait(kind);
      if (s.state == session::JobState::kFailed && s.exception) std::rethrow_exception(s.exception);
    }
  } else if (a.text == "suggest") {
    session::JobStatus s;
    suggestion = session_->WaitSuggestion(&s);
    if (s.state == session::JobState::kFailed && s.exception) std::rethrow_exception(s.exception);
    if (suggestion) status = suggestion->message;
  } else {
    session_->jobs().Wait("render");
  }
}

// "suggest": starts a suggestion in the background.
void ViewerModel::DoSuggest(const Action& a) {
  std::shared_ptr<app::SuggestProblem> problem;
  try {
    problem = app::PrepareSuggest(SuggestRequestOf(a), scene(), rig());
  } catch (const InputError& e) {
    RethrowAsAction(e, a.where);
  }
  problem->options.scene_path = a.where;  // the library's checks name the action
  suggestion.reset();
  suggestion_over_time = a.over_time;
  suggestion_targets =
      std::to_string(problem->targets.size()) + " points " +
      (a.over_time ? "on the study's targets at " + std::to_string(problem->sample_casters.size()) +
                         " time samples"
       : a.target_surfaces.empty()
           ? std::string("of the study region")
           : std::string("on the target surfaces") + (a.with_region ? " and in the region" : ""));
  session_->SuggestInBackground(problem->targets, problem->options, problem);
  status = "suggesting";
}

// "accept": the suggestion's poses of all or the named cameras; the rest stays suggested.
void ViewerModel::DoAccept(const Action& a) {
  if (!suggestion)
    throw InputError(a.where, "", "there is no suggestion to accept",
                     "suggest first, then wait for it");
  // As `pandora accept`: a suggestion that does not improve its objective is not offered.
  if (!suggestion->improved)
    throw InputError(a.where, "", "the suggestion offers no improvement; nothing to accept",
                     "suggest again with other limits or cameras, or reject it");
  Suggestion take = *suggestion, keep = *suggestion;
  take.cameras.clear();
  keep.cameras.clear();
  for (const CameraChange& c : suggestion->cameras)
    (a.cameras.empty() || std::count(a.cameras.begin(), a.cameras.end(), c.id) ? take : keep)
        .cameras.push_back(c);
  for (const std::string& id : a.cameras)
    if (std::none_of(take.cameras.begin(), take.cameras.end(),
                     [&](const CameraChange& c) { return c.id == id; }))
      throw InputError(a.where, "", "camera '" + id + "' is not in the suggestion");
  session_->ApplySuggestion(take);
  Edited();
  if (keep.cameras.empty())
    suggestion.reset();
  else
    suggestion = keep;
  status = "accepted " + std::to_string(take.cameras.size()) + " cameras (not saved yet)";
}

// "save": the edited poses, focal lengths and moved viewing stations into the scene file.
void ViewerModel::DoSave(const Action& a) {
  session::EditableRig& edit = session_->rig();
  const std::string& file = scene().path;
  // Saving writes poses and focal lengths only: name what else changed, camera by camera.
  std::string unsavable;
  for (int c : edit.Unsaved()) {
    const std::string what = UnsavableChanges(edit.saved().cameras[c], rig().cameras[c]);
    if (!what.empty())
      unsavable += (unsavable.empty() ? "" : "; ") + rig().cameras[c].id + "'s " + what;
  }
  if (!unsavable.empty())
    throw InputError(file, "",
                     "not saved: saving writes poses and focal lengths only, not " + unsavable,
                     "undo them, or copy them into the scene file by hand");
  std::vector<StationMove> moved;
  for (const auto& [name, st] : stations) {
    const ViewingStation& before = saved_stations.at(name);
    if (st.eye != before.eye || st.display_center != before.display_center)
      moved.push_back({name, st.eye, st.display_center});
  }
  const session::SaveResult r = session_->Save(a.flag, moved);
  saved_stations = stations;
  if (!options_.autosave_path.empty()) session::WriteAutosave(*session_, options_.autosave_path);
  std::string what;
  auto count = [](std::size_t n, const std::string& what) {
    return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
  };
  if (!r.saved.empty()) what = count(r.saved.size(), "camera");
  if (!r.saved_stations.empty())
    what += (what.empty() ? "" : " and ") + count(r.saved_stations.size(), "viewing station");
  status = what.empty() ? "nothing to save"
                        : "saved " + what + " into " + r.scene_path + " (previous file kept as " +
                              r.backup_path + ")";
}

// "screenshot": the main view or a camera's view through the front end.
void ViewerModel::DoScreenshot(const Action& a, Frontend* frontend) {
  if (!frontend) throw InputError(a.where, "", "screenshots need a front end");
  const int camera = a.text2.empty() ? -1 : CameraIndex(a.text2, a);
  // As every command's outputs: never onto an input, written whole or not at all.
  OutputTransaction output;
  for (const auto& [path, what] : scene().InputFiles()) output.AddInput(path, what);
  frontend->Screenshot(*this, output.Stage(a.text, a.where), camera);
  output.Commit();
}

// "gamepad": a camera flown by stick positions held for some seconds.
void ViewerModel::DoGamepad(const Action& a, EditStep& step) {
  const int c = CameraIndex(a.cameras[0], a);
  GamepadAxes axes;
  axes.left_x = a.a.x();
  axes.left_y = a.a.y();
  axes.right_x = a.b.x();
  axes.right_y = a.b.y();
  Eigen::Isometry3d pose = rig().cameras[c].world_from_camera;
  const int steps = int(std::lround(a.number * 60.0));  // 60 Hz, as the window polls
  for (int i = 0; i < steps; ++i) pose = GamepadMove(pose, axes, 1.0 / 60.0, 0.5, 45.0);
  ApplyEdit(a, step, {c}, EditLabel("gamepad", {c}),
            [&](Camera& cam) { cam.world_from_camera = pose; });
}

// "station": a viewing station's eye or display centre moved.
void ViewerModel::DoStation(const Action& a) {
  const std::string& file = scene().path;
  auto it = stations.find(a.text);
  if (it == stations.end()) {
    std::string names;
    for (const auto& [name, st] : stations) names += (names.empty() ? "" : ", ") + name;
    throw InputError(a.where, "", "no viewing station '" + a.text + "' in " + file,
                     names.empty() ? "the scene defines no stations" : "stations: " + names);
  }
  ViewingStation moved = it->second;
  scene().CheckReach(a.a, a.where, a.flag ? "the display" : "the eye");
  if (a.flag)
    moved.display_center = a.a;
  else
    moved.eye = a.a;
  if (!((moved.eye - moved.display_center).dot(moved.display_normal) > 0))
    throw InputError(a.where, "", "the eye would be behind the display or in its plane");
  it->second = moved;
  ++stations_version;
}

// "ptz": a PTZ camera's pan, tilt and zoom, or one of its presets.
void ViewerModel::DoPtz(const Action& a, EditStep& step) {
  const int c = CameraIndex(a.cameras[0], a);
  ApplyTyped(a, step, {c}, session::PtzEdit{c, a.preset, a.pan_deg, a.tilt_deg, a.hfov_deg});
  status = step.ptz_status + (a.preset.empty() ? "" : ", preset " + a.preset);
}

// "recentre": a PTZ camera's home made its current view.
void ViewerModel::DoRecentre(const Action& a, EditStep& step) {
  const int c = CameraIndex(a.cameras[0], a);
  ApplyTyped(a, step, {c}, session::RecentreEdit{c, scene().path, session_->CameraJsonPath(c)});
  const PtzHead& h = *rig().cameras[c].ptz;
  char line[200];
  std::snprintf(line, sizeof line,
                "%s: home is now the current view (pan [%.1f, %.1f], tilt [%.1f, %.1f] deg)",
                rig().cameras[c].id.c_str(), h.pan_min_deg, h.pan_max_deg, h.tilt_min_deg,
                h.tilt_max_deg);
  status = line;
}

// "trace": the PTZ traces the main view shows.
void ViewerModel::DoTrace(const Action& a) {
  bool any = false;
  session::PtzTracedRig(rig(), a.text, a.number, nullptr, &any);
  if (!any && a.text != "single")
    throw InputError(a.where, "", "rig '" + rig().name + "' has no enabled PTZ camera",
                     "add a \"ptz\" block to a camera (docs/ptz.md)");
  ptz_trace = a.text;
  ptz_trace_s = a.number;
  status = "PTZ trace: " + a.text;
}

void ViewerModel::Do(const Action& a, Frontend* frontend) {
  using Kind = Action::Kind;
  session::EditableRig& edit = session_->rig();
  // The drag this action may continue: its camera edit then amends the drag's first (ApplyEdit).
  EditStep step;
  step.drag = a.drag ? drag_label_ : std::string();
  drag_label_.clear();
  status.clear();
  switch (a.kind) {
    case Kind::kSelect:
      selection = CameraIndices(a.cameras, a);
      break;
    case Kind::kMove:
      DoMove(a, step);
      break;
    case Kind::kRotate:
      DoRotate(a, step);
      break;
    case Kind::kAim:
      DoAim(a, step);
      break;
    case Kind::kOrient:
      DoOrient(a, step);
      break;
    case Kind::kEnable:
    case Kind::kDisable:
      DoEnable(a, step);
      break;
    case Kind::kHfov:
      DoHfov(a, step);
      break;
    case Kind::kIntrinsics:
      DoIntrinsics(a, step);
      break;
    case Kind::kRange:
      DoRange(a, step);
      break;
    case Kind::kColor:
      DoColor(a, step);
      break;
    case Kind::kCompare:
      Compare(a);
      break;
    case Kind::kUndo:
      status = edit.can_undo() ? "undo " + edit.undo_label() : "nothing to undo";
      if (edit.Undo()) Edited();
      break;
    case Kind::kRedo:
      status = edit.can_redo() ? "redo " + edit.redo_label() : "nothing to redo";
      if (edit.Redo()) Edited();
      break;
    case Kind::kSlice:
    case Kind::kIso:
      DoSliceIso(a);
      break;
    case Kind::kView:
      DoView(a);
      break;
    case Kind::kOrbit:
      Orbit(a.a.x(), a.a.y());
      break;
    case Kind::kPan:
      Pan(a.a.x(), a.a.y());
      break;
    case Kind::kDolly:
      Dolly(a.number);
      break;
    case Kind::kEye:
      plan.clear();
      view = OrbitView::FromLookAt(a.a, a.b, a.number);
      break;
    case Kind::kLight:
      DoLight(a);
      break;
    case Kind::kWait:
      DoWait(a);
      break;
    case Kind::kSuggest:
      DoSuggest(a);
      break;
    case Kind::kAccept:
      DoAccept(a);
      break;
    case Kind::kReject:
      suggestion.reset();
      break;
    case Kind::kSave:
      DoSave(a);
      break;
    case Kind::kScreenshot:
      DoScreenshot(a, frontend);
      break;
    case Kind::kSize:
      width = int(a.a.x());
      height = int(a.a.y());
      break;
    case Kind::kGamepad:
      DoGamepad(a, step);
      break;
    case Kind::kStation:
      DoStation(a);
      break;
    case Kind::kPtz:
      DoPtz(a, step);
      break;
    case Kind::kRecentre:
      DoRecentre(a, step);
      break;
    case Kind::kTrace:
      DoTrace(a);
      break;
    case Kind::kMouse:
    case Kind::kKey:
    case Kind::kScroll:
    case Kind::kFrames:
      if (frontend) frontend->Input(*this, a);
      break;
  }
  if (status.empty() && !step.ptz_status.empty()) status = step.ptz_status;
}

nlohmann::json ViewerModel::StateJson() const {
  using nlohmann::json;
  const session::EditableRig& edit = session_->rig();
  json cameras = json::array();
  for (const Camera& c : rig().cameras) {
    const Vec3 p = c.center();
    const Intrinsics& k = c.model.intrinsics();
    json lens = {{"model", LensModelName(k.model)}};
    const double* coefficients[6] = {&k.k1, &k.k2, &k.p1, &k.p2, &k.k3, &k.k4};
    for (int i = 0; i < 6; ++i)
      if (LensHasCoefficient(k.model, i)) lens[kLensCoefficientNames[i]] = *coefficients[i];
    cameras.push_back({{"id", c.id},
                       {"enabled", c.enabled},
                       {"position", {p.x(), p.y(), p.z()}},
                       {"hfov_deg", HfovFromFocal(k.fx, c.model.width(), k.model) / kRadPerDeg},
                       {"resolution", {k.width, k.height}},
                       {"lens", lens},
                       {"range", {c.near, std::isfinite(c.far) ? json(c.far) : json()}},
                       {"color", {c.color.x(), c.color.y(), c.color.z()}}});
    if (c.ptz) {
      const PtzHead& h = *c.ptz;
      const Vec3 pivot = h.home.translation();
      const Eigen::Quaterniond q(h.home.rotation());
      json presets = json::array();
      for (const PtzPreset& p : h.presets)
        presets.push_back(
            {{"name", p.name}, {"pan_deg", p.state.pan_deg}, {"tilt_deg", p.state.tilt_deg}});
      cameras.back()["ptz"] = {{"pan_deg", h.current.pan_deg},
                               {"tilt_deg", h.current.tilt_deg},
                               {"pivot", {pivot.x(), pivot.y(), pivot.z()}},
                               {"home_quaternion", {q.w(), q.x(), q.y(), q.z()}},
                               {"pan_range_deg", {h.pan_min_deg, h.pan_max_deg}},
                               {"tilt_range_deg", {h.tilt_min_deg, h.tilt_max_deg}},
                               {"presets", presets}};
    }
  }
  json selected = json::array();
  for (int c : selection) selected.push_back(rig().cameras[c].id);
  json fields = json::object();
  session_->ReadFields([&](const Fields& f, std::int64_t version) {
    fields["rig_version"] = version;
    // coverage_ge[k - 1]: share of the free region voxels seen by at least k cameras.
    fields["coverage_ge"] = CoverageAtLeast(f.stats.coverage_histogram);
    const std::optional<double> p50 = NearestRankPercentile(f.stats.sigma_max_mm, 50);
    fields["sigma_max_p50_mm"] = p50 ? json(*p50) : json();
  });
  // With people: the numbers over the time samples (the live fields are the empty volume's).
  if (const auto time = session_->TimeNumbers()) {
    const TimeSummary& t = time->first;
    fields["time"] = {
        {"rig_version", time->second},
        {"min_cameras", t.min_cameras},
        {"samples", t.samples.size()},
        {"always", t.always},
        {"mean", t.mean},
        {"worst_sample", t.samples.empty() ? json() : json(t.samples[t.worst_sample].ge_k)},
        {"sigma_max_p90_mm", t.sigma_max_p90 ? json(*t.sigma_max_p90) : json()}};
  }
  json j = {{"rig", rig().name},
            {"ptz_trace", ptz_trace},
            {"plan", plan},  // "": the orbit view; else the plan or elevation side
            {"rig_version", edit.version()},
            {"undo", edit.undo_label()},
            {"redo", edit.redo_label()},
            {"unsaved", edit.Unsaved().size()},
            {"selection", selected},
            {"cameras", cameras},
            {"fields", fields},
            {"status", status}};
  if (!stations.empty()) {
    json st = json::object();
    for (const auto& [name, s] : stations)
      st[name] = {
          {"eye", {s.eye.x(), s.eye.y(), s.eye.z()}},
          {"display_center", {s.display_center.x(), s.display_center.y(), s.display_center.z()}}};
    j["stations"] = st;
  }
  if (comparison) j["comparison"] = *comparison;
  if (suggestion) {
    json ids = json::array(), positions = json::object();
    for (const CameraChange& c : suggestion->cameras) {
      ids.push_back(c.id);
      const Vec3 p = c.after.translation();
      positions[c.id] = {p.x(), p.y(), p.z()};
    }
    j["suggestion"] = {
        {"cameras", ids},
        {"objective", ObjectiveName(suggestion->objective)},
        {"before", suggestion->before.objective},
        {"after", suggestion->after.objective},
        {"improved", suggestion->improved},
        {"positions", positions},  // the suggested centres, to compare with `pandora suggest`'s
        {"targets", suggestion_targets}};
  }
  return j;
}

}  // namespace pandora::viewer
