// The camera panel: the selected camera's pose, zoom, lens, range, colour and PTZ head
// (ViewerApp::Impl).
#include "viewer/window/viewer_app_impl.h"

namespace pandora::viewer {

void ViewerApp::Impl::CameraPanel() {
  const int c = Primary();
  ImGui::SetNextWindowPos(ImVec2(8, 316), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(250, 250), ImGuiCond_FirstUseEver);
  ImGui::Begin("Camera");
  if (c < 0) {
    ImGui::TextDisabled("click a camera to select it");
    ImGui::End();
    return;
  }
  const Camera& cam = model.rig().cameras[c];
  ImGui::Text("%s (%s), %dx%d %s", cam.id.c_str(), cam.name.c_str(), cam.model.width(),
              cam.model.height(), LensModelName(cam.model.intrinsics().model));
  float p[3] = {float(cam.center().x()), float(cam.center().y()), float(cam.center().z())};
  if (ImGui::DragFloat3("position m", p, 0.005f, -1e4f, 1e4f, "%.3f")) {
    Action a = Make(Action::Kind::kMove, {cam.id});
    a.flag = true;
    a.a = Vec3(p[0], p[1], p[2]);
    a.drag = true;
    Do(a);
  }
  const Vec3 ypr = YawPitchRollDeg(cam.world_from_camera.linear());
  float e[3] = {float(ypr.x()), float(ypr.y()), float(ypr.z())};
  if (ImGui::DragFloat3("yaw pitch roll", e, 0.2f, -180.0f, 180.0f, "%.1f")) {
    Action a = Make(Action::Kind::kOrient, {cam.id});
    a.a = Vec3(e[0], std::clamp(e[1], -90.0f, 90.0f), e[2]);
    a.drag = true;
    Do(a);
  }
  const Intrinsics& k = cam.model.intrinsics();
  float hfov = float(HfovFromFocal(k.fx, k.width, k.model) / kRadPerDeg);
  if (ImGui::DragFloat("hfov deg", &hfov, 0.1f, 1.0f,
                       k.model == LensModel::kFisheye ? 359.0f : 179.0f, "%.1f")) {
    Action a = Make(Action::Kind::kHfov, {cam.id});
    a.number = hfov;
    Do(a);
  }
  if (cam.ptz) PtzControls(cam);
  LensControls(cam);
  ImGui::DragFloat("snap move m", &move_step, 0.005f, 0.0f, 1.0f, "%.3f");
  ImGui::DragFloat("snap turn deg", &rotate_step, 0.5f, 0.0f, 45.0f, "%.1f");
  ImGui::TextDisabled("%zu selected: drag the gizmo (axes move, rings turn)",
                      model.selection.size());
  ImGui::End();
}

void ViewerApp::Impl::PtzControls(const Camera& cam) {
  const PtzHead& h = *cam.ptz;
  if (!ImGui::CollapsingHeader("Pan / tilt / zoom", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const Intrinsics& k = cam.model.intrinsics();
  auto hfov = [&](double f) { return float(HfovFromFocal(f, k.width, k.model) / kRadPerDeg); };
  const Vec3 pivot = h.home.translation();
  ImGui::TextDisabled("pivot %.3f %.3f %.3f, home elevation %.1f deg", pivot.x(), pivot.y(),
                      pivot.z(), h.HomeElevationDeg());
  float pan = float(h.current.pan_deg), tilt = float(h.current.tilt_deg),
        zoom = hfov(h.current.focal);
  Action a = Make(Action::Kind::kPtz, {cam.id});
  a.drag = true;
  if (ImGui::SliderFloat("pan deg", &pan, float(h.pan_min_deg), float(h.pan_max_deg), "%.1f")) {
    a.pan_deg = pan;
    Do(a);
  }
  if (ImGui::SliderFloat("tilt deg", &tilt, float(h.tilt_min_deg), float(h.tilt_max_deg), "%.1f")) {
    a.tilt_deg = tilt;
    Do(a);
  }
  if (h.focal_max > h.focal_min) {
    if (ImGui::SliderFloat("zoom hfov deg", &zoom, hfov(h.focal_min), hfov(h.focal_max), "%.1f")) {
      a.hfov_deg = zoom;
      Do(a);
    }
  } else {
    ImGui::TextDisabled("fixed focal length (no zoom_hfov_deg)");
  }
  if (!h.presets.empty()) {
    ImGui::TextUnformatted("presets:");
    for (const PtzPreset& p : h.presets) {
      ImGui::SameLine();
      if (ImGui::SmallButton(p.name.c_str())) {
        Action go = Make(Action::Kind::kPtz, {cam.id});
        go.preset = p.name;
        Do(go);
      }
    }
  }
  if (ImGui::Button("Re-centre")) Do(Make(Action::Kind::kRecentre, {cam.id}));
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "home := the current view; presets and ranges shift so that every preset stays where it "
        "is");
  ImGui::TextUnformatted("trace:");
  for (const char* mode : {"single", "path", "all"}) {
    ImGui::SameLine();
    if (ImGui::RadioButton(mode, model.ptz_trace == mode)) {
      Action t = Make(Action::Kind::kTrace, {});
      t.text = mode;
      t.number = std::isnan(trace_seconds) ? NAN : double(trace_seconds);
      Do(t);
    }
  }
  float budget = std::isnan(model.ptz_trace_s) ? float(h.trace_s) : float(model.ptz_trace_s);
  if (ImGui::DragFloat("budget s", &budget, 0.05f, 0.0f, 60.0f, "%.2f",
                       ImGuiSliderFlags_AlwaysClamp)) {
    trace_seconds = budget;
    Action t = Make(Action::Kind::kTrace, {});
    t.text = model.ptz_trace;
    t.number = budget;
    Do(t);
  }
  ImGui::TextDisabled(model.ptz_trace == "all" ? "all: exact CPU picture (slow while moving)"
                                               : "path: one light per second home -> current");
}

void ViewerApp::Impl::LensControls(const Camera& cam) {
  const Intrinsics& k = cam.model.intrinsics();
  bool on = cam.enabled;
  if (ImGui::Checkbox("on", &on))
    Do(Make(on ? Action::Kind::kEnable : Action::Kind::kDisable, {cam.id}));
  ImGui::SameLine();
  float rgb[3] = {float(cam.color.x()), float(cam.color.y()), float(cam.color.z())};
  if (ImGui::ColorEdit3("colour", rgb, ImGuiColorEditFlags_NoInputs | ImGuiColorEditFlags_Float)) {
    Action a = Make(Action::Kind::kColor, {cam.id});
    a.a = Vec3(std::clamp(rgb[0], 0.0f, 1.0f), std::clamp(rgb[1], 0.0f, 1.0f),
               std::clamp(rgb[2], 0.0f, 1.0f));
    a.drag = true;
    Do(a);
  }
  // The working range: near, and far unless unlimited.
  bool limited = std::isfinite(cam.far);
  ImGui::SameLine();
  if (ImGui::Checkbox("far limit", &limited)) {
    Action a = Make(Action::Kind::kRange, {cam.id});
    a.far = limited ? std::max(cam.near + 1.0, 5.0) : INFINITY;
    Do(a);
  }
  if (limited) {
    float n = float(cam.near), f = float(cam.far);
    if (ImGui::DragFloatRange2("range m", &n, &f, 0.01f, 0.0f, 1e4f, "%.2f", "%.2f",
                               ImGuiSliderFlags_AlwaysClamp)) {
      Action a = Make(Action::Kind::kRange, {cam.id});
      a.near = n;
      a.far = std::max(f, n + 1e-3f);
      a.drag = true;
      Do(a);
    }
  } else {
    float n = float(cam.near);
    if (ImGui::DragFloat("near m", &n, 0.01f, 0.0f, 1e4f, "%.2f", ImGuiSliderFlags_AlwaysClamp)) {
      Action a = Make(Action::Kind::kRange, {cam.id});
      a.near = n;
      a.drag = true;
      Do(a);
    }
  }
  if (!ImGui::CollapsingHeader("Lens and resolution")) return;
  // Resolution: typed, applied on Enter (the field of view kept: fx, fy, cx, cy scaled); what is
  // typed shows the camera's again once the field is left without Enter.
  if (!resolution_active || resolution_camera != cam.id) {
    resolution[0] = k.width;
    resolution[1] = k.height;
    resolution_camera = cam.id;
  }
  const bool entered =
      ImGui::InputInt2("resolution", resolution, ImGuiInputTextFlags_EnterReturnsTrue);
  resolution_active = ImGui::IsItemActive();
  if (entered && (resolution[0] != k.width || resolution[1] != k.height)) {
    Action a = Make(Action::Kind::kIntrinsics, {cam.id});
    a.width = std::clamp(resolution[0], 1, 65536);
    a.height = std::clamp(resolution[1], 1, 65536);
    Do(a);
    resolution_active = false;
  }
  int lens = int(k.model);
  if (ImGui::Combo("lens", &lens, "pinhole\0brown_conrady\0fisheye\0")) {
    Action a = Make(Action::Kind::kIntrinsics, {cam.id});
    a.lens = LensModelName(LensModel(lens));
    Do(a);
  }
  const double values[6] = {k.k1, k.k2, k.p1, k.p2, k.k3, k.k4};
  for (int i = 0; i < 6; ++i) {
    if (!LensHasCoefficient(k.model, i)) continue;
    float v = float(values[i]);
    if (ImGui::DragFloat(kLensCoefficientNames[i], &v, i == 2 || i == 3 ? 0.0001f : 0.001f, -10.0f,
                         10.0f, "%.4f")) {
      Action a = Make(Action::Kind::kIntrinsics, {cam.id});
      a.coefficients[i] = v;
      a.drag = true;
      Do(a);
    }
  }
  if (k.model == LensModel::kPinhole) ImGui::TextDisabled("no distortion");
}

}  // namespace pandora::viewer
