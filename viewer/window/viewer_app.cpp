// The window of `pandora view` (viewer/window/viewer_app.h). Input from GLFW and from scripts lands
// in one InputState; each frame feeds it to Dear ImGui (no platform backend: the state is ours, so
// a script drives the panels exactly as a mouse does), then to the 3D handlers (orbit, pan, dolly,
// pick, gizmo), which turn it into the model's actions.
#include "viewer/window/viewer_app_impl.h"

namespace pandora::viewer {
namespace {

std::string g_glfw_error;
void OnGlfwError(int code, const char* text) {
  g_glfw_error = std::string(text) + " (" + std::to_string(code) + ")";
}

}  // namespace

void ViewerApp::Impl::Do(const Action& a) {
  if (a.kind == Action::Kind::kSelect && !a.cameras.empty())
    station.clear();  // the gizmo goes to the cameras
  try {
    error.clear();
    model.Do(a, nullptr);
  } catch (const InputError& original) {
    const InputError e = RenameOptions(original, ActionKey);  // options as the scripts' keys
    error = e.what();
    error_line = e.reason() + (e.hint().empty() ? "" : " (" + e.hint() + ")");
  }
}

Action ViewerApp::Impl::Make(Action::Kind kind, std::vector<std::string> cameras) const {
  Action a;
  a.kind = kind;
  a.where = "the window";
  a.cameras = std::move(cameras);
  return a;
}

std::vector<std::string> ViewerApp::Impl::SelectedIds() const {
  std::vector<std::string> ids;
  for (int c : model.selection) ids.push_back(model.rig().cameras[c].id);
  return ids;
}

std::vector<std::string> ViewerApp::Impl::ToggledSelection(const std::string& id) const {
  std::vector<std::string> ids = input.ctrl ? SelectedIds() : std::vector<std::string>();
  const auto it = std::find(ids.begin(), ids.end(), id);
  if (it != ids.end())
    ids.erase(it);
  else
    ids.push_back(id);
  return ids;
}

std::optional<Ray> ViewerApp::Impl::MouseRay(double x, double y) const {
  return PixelRay(model.rig(), model.MainView(), x, y);
}

std::optional<Vec3> ViewerApp::Impl::StationPoint() const {
  const auto it = model.stations.find(station);
  if (station.empty() || it == model.stations.end()) return std::nullopt;
  return station_display ? it->second.display_center : it->second.eye;
}

std::optional<Vec3> ViewerApp::Impl::GizmoOrigin() const {
  if (const auto p = StationPoint()) return p;
  const int c = Primary();
  if (c < 0) return std::nullopt;
  return model.rig().cameras[c].center();
}

double ViewerApp::Impl::GizmoLength() const {
  const auto o = GizmoOrigin();
  if (!o) return 0.3;
  return 0.12 * (*o - model.view.Eye()).norm();
}

void ViewerApp::Impl::UploadAllTrace() {
  std::lock_guard<std::mutex> lock(all_trace->mutex);
  if (!all_trace->fresh) return;
  all_trace->fresh = false;
  if (model.ptz_trace != "all") return;  // a pass that finished after the mode changed
  Upload(&main_texture, all_trace->image.width, all_trace->image.height,
         ToRgba8(all_trace->image.rgb));
  shown_texture = main_texture;  // made by the first upload
}

void ViewerApp::Impl::RenderMain() {
  if (full_now && model.ptz_trace == "all" && !all_trace_key.empty()) {
    // A screenshot shows the exact picture: the background frame's last pass (or a new frame).
    const session::JobStatus st = model.session().jobs().Wait("render");
    if (st.state != session::JobState::kDone) all_trace_key.clear(), main_key.clear();
  }
  UploadAllTrace();
  RenderView view = model.MainView();
  char key[512];
  std::snprintf(key, sizeof key,
                "%lld %.17g %.17g %.17g %.17g %.17g %.17g %.17g %d %d %d %d %.17g %d %d %s %.17g "
                "%.17g %.17g %.17g %.17g",
                static_cast<long long>(model.session().rig().version()), view.from.x(),
                view.from.y(), view.from.z(), view.at.x(), view.at.y(), view.at.z(), view.fov_deg,
                view.width, view.height, int(model.display.pattern), model.display.grid_pixels,
                model.display.brightness, int(model.display.surface), shadow_map_size,
                model.ptz_trace.c_str(), model.ptz_trace_s, view.clip_near, view.up.x(),
                view.up.y(), view.up.z());
  const auto now = std::chrono::steady_clock::now();
  if (key != main_key) last_change = now;
  const std::int64_t rig_version = model.session().rig().version();
  if (rig_version != main_rig_version) last_rig_change = now;
  main_rig_version = rig_version;
  auto since = [&](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(now - t).count();
  };
  // Reduced while things move, full once idle.
  const bool moving =
      options.motion_scale < 1 && !full_now && (drag != Drag::kNone || since(last_change) < 0.3);
  if (key == main_key && shown_texture && (moving || main_full)) return;
  main_key = key;
  main_full = !moving;
  if (moving) {
    view.width = std::max(16, int(std::lround(view.width * motion_now)));
    view.height = std::max(16, int(std::lround(view.height * motion_now)));
  }
  // Maps: at most 1024 texels while the eye moves (drawn once, then reused), 256 while cameras
  // move (their maps are drawn every frame, for a picture of 0.2-0.5 of the window: on llvmpipe
  // eight 512 maps took 70-78 ms of a 163 ms frame, eight 256 maps keep it at 82 ms).
  gl_options.shadow_map_size =
      !moving ? shadow_map_size
              : std::min(shadow_map_size, since(last_rig_change) < 0.3 ? 256 : 1024);
  gl_options.pattern = model.display.pattern;
  gl_options.surface = model.display.surface;
  gl_options.brightness = model.display.brightness;
  gl_options.grid_pixels = model.display.grid_pixels;
  const auto t0 = std::chrono::steady_clock::now();
  if (model.ptz_trace == "all") {
    // Everything a PTZ head reaches within the budget: the exact CPU renderer's ptz_all (each
    // surface point against its own best reachable pose; no GPU version yet), at the rig's
    // brightness as `pandora render --ptz all`. A screenshot waits for the exact picture; the
    // window renders it progressively in the background (UploadAllTrace shows each pass).
    RenderOptions o = InsetOptions();
    if (std::isnan(o.brightness)) o.brightness = DefaultBrightness(model.rig().enabled_count());
    const Rig traced = model.TracedRig(&o.ptz_all);
    // A new frame: passes of the older ones are dropped.
    auto next_generation = [&] {
      std::lock_guard<std::mutex> lock(all_trace->mutex);
      all_trace->fresh = false;
      return ++all_trace->generation;
    };
    if (full_now) {
      next_generation();
      model.session().jobs().Cancel("render");
      const Image image =
          RenderWithStats(model.session().study().prepared(), traced, view, o, nullptr, nullptr);
      Upload(&main_texture, image.width, image.height, ToRgba8(image.rgb));
      shown_texture = main_texture;
      all_trace_key = key;
    } else if (key != all_trace_key) {
      // Coarse first (1/64 of the pixels), then refined; a newer frame cancels this one.
      all_trace_key = key;
      const std::int64_t generation = next_generation();
      auto slot = all_trace;
      model.session().RenderInBackground(traced, model.MainView(), o, nullptr,
                                         [slot, generation](const Image& image, int, std::int64_t) {
                                           std::lock_guard<std::mutex> lock(slot->mutex);
                                           if (slot->generation != generation) return;
                                           slot->image = image;
                                           slot->fresh = true;
                                         });
    }
    main_full = true;  // the background frame refines itself
  } else {
    // "path": the steps home -> current as extra lights, at the rig's own brightness.
    all_trace_key.clear();
    GlRenderOptions o = gl_options;
    if (model.ptz_trace != "single" && std::isnan(o.brightness))
      o.brightness = DefaultBrightness(model.rig().enabled_count());
    // Kept on the GPU: the renderer's own 8-bit sRGB texture is what the window shows.
    GlFrameStats counts;
    counts.per_part = false;  // no waits: only what costs nothing to count
    shown_texture = gl->DrawToTexture(
        model.ptz_trace == "single" ? model.rig() : model.TracedRig(nullptr), view, o, &counts);
    readback_bytes += counts.readback_bytes;
    map_cpu_seconds += counts.map_cpu_seconds;
  }
  gl_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  frame_gl_seconds = gl_seconds;
  // Adaptive resolution while moving: the next moving frame's scale aims at the target rate
  // from this frame's light and the rest of the frame (panels, overlays, swap: overhead_seconds),
  // the picture's cost taken as proportional to its pixels; at most 30 % per frame, within
  // [kMinMotionScale, 1]. It aims 15 % above the target: frames vary by about that much from one
  // to the next, and aimed at the target itself half of them missed it.
  if (moving && options.target_hz > 0) {
    const double total = gl_seconds + overhead_seconds;
    const double aim = 1.0 / (kTargetHeadroom * options.target_hz);
    const double factor = std::clamp(std::sqrt(aim / std::max(total, 1e-4)), 0.7, 1.3);
    motion_now = std::clamp(motion_now * factor, kMinMotionScale, 1.0);
  }
}

void ViewerApp::Impl::Upload(GLuint* texture, int w, int h,
                             const std::vector<unsigned char>& rgba) {
  upload_bytes += std::int64_t(rgba.size());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (!*texture) glGenTextures(1, texture);
  glBindTexture(GL_TEXTURE_2D, *texture);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
}

RenderOptions ViewerApp::Impl::InsetOptions() const {
  RenderOptions o = model.display;
  o.layers = false;
  o.overlays.slice_field.clear();
  o.overlays.iso_field.clear();
  o.overlays.key = false;
  return o;
}

void ViewerApp::Impl::RenderCameraView(int c) {
  CameraView& v = camera_views[c];
  const Camera& cam = model.rig().cameras[c];
  // On the GPU (live while cameras move: the maps are the main view's, kept), but for wide
  // fisheyes, which the exact CPU renderer draws.
  const bool gpu = GlDrawsCameraEye(cam);
  char key[256];
  std::snprintf(key, sizeof key, "%lld %lld %d %d %d %.17g %d %d",
                static_cast<long long>(model.session().rig().camera_version(c)),
                static_cast<long long>(model.session().rig().version()), int(model.display.pattern),
                model.display.grid_pixels, int(model.display.surface), model.display.brightness,
                gl_options.shadow_map_size, gpu ? 1 : 0);
  if (v.texture && v.key == key) return;
  const CameraModel& m = cam.model;
  const double scale = std::min(1.0, 256.0 / m.width());
  RenderView view;
  view.camera = c;
  view.width = std::max(16, int(std::lround(m.width() * scale)));
  view.height = std::max(16, int(std::lround(m.height() * scale)));
  if (gpu) {
    GlFrameStats counts;
    counts.per_part = false;
    const unsigned frame = gl->DrawToTexture(model.rig(), view, gl_options, &counts);
    readback_bytes += counts.readback_bytes;
    map_cpu_seconds += counts.map_cpu_seconds;
    if (!v.texture || v.width != view.width || v.height != view.height) {
      if (!v.texture) glGenTextures(1, &v.texture);
      glBindTexture(GL_TEXTURE_2D, v.texture);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, view.width, view.height, 0, GL_RGBA,
                   GL_UNSIGNED_BYTE, nullptr);
    }
    GlCopyTexture(frame, v.texture, view.width, view.height);
  } else {
    const Image image = model.session().Render(view, InsetOptions());
    Upload(&v.texture, image.width, image.height, ToRgba8(image.rgb));
  }
  v.key = key;
  v.width = view.width;
  v.height = view.height;
}

int ViewerApp::Impl::HandleAt(double x, double y) const {
  const auto origin = GizmoOrigin();
  if (!origin) return -1;
  const bool rings = !StationPoint();
  const Projector P(model.MainView());
  const Vec3 o = *origin;
  const double len = GizmoLength();
  const ImVec2 m{float(x), float(y)};
  int best = -1;
  double best_d = 7.0;
  for (int k = 0; k < 3; ++k) {
    ImVec2 a, b;
    if (P.Segment(o + 0.15 * len * Vec3::Unit(k), o + len * Vec3::Unit(k), &a, &b)) {
      const double d = SegmentDistance(m, a, b);
      if (d < best_d) best_d = d, best = k;
    }
    if (!rings) continue;
    const Vec3 u = Vec3::Unit((k + 1) % 3), v = Vec3::Unit((k + 2) % 3);
    for (int i = 0; i < 48; ++i) {
      const double t0 = 2 * kPi * i / 48, t1 = 2 * kPi * (i + 1) / 48;
      if (P.Segment(o + 0.8 * len * (std::cos(t0) * u + std::sin(t0) * v),
                    o + 0.8 * len * (std::cos(t1) * u + std::sin(t1) * v), &a, &b)) {
        const double d = SegmentDistance(m, a, b);
        if (d < best_d) best_d = d, best = k + 3;
      }
    }
  }
  return best;
}

void ViewerApp::Impl::Handle3d(bool mouse_free) {
  const ImGuiIO& io = ImGui::GetIO();
  const double x = input.x, y = input.y;
  if (drag == Drag::kNone) hover_handle = mouse_free ? HandleAt(x, y) : -1;
  if (mouse_free && io.MouseWheel != 0) model.Dolly(io.MouseWheel);  // magnifies a plan
  const bool left = input.down[0], right = input.down[1] || input.down[2];
  if (drag == Drag::kNone && mouse_free && (left || right)) {
    press_x = last_x = x;
    press_y = last_y = y;
    if (right) {
      drag = Drag::kPan;
    } else if (hover_handle >= 0) {
      drag = hover_handle < 3 ? Drag::kAxis : Drag::kRing;
      drag_handle = hover_handle % 3;
      applied = 0;
      if (const auto p = StationPoint()) station_start = *p;
      if (const auto r = MouseRay(x, y)) drag_ray = *r;
    } else {
      drag = Drag::kClick;  // becomes an orbit once the mouse moves
    }
    return;
  }
  if (drag == Drag::kNone) return;
  const double dx = x - last_x, dy = y - last_y;
  last_x = x;
  last_y = y;
  if (drag == Drag::kClick && std::hypot(x - press_x, y - press_y) > 3) drag = Drag::kOrbit;
  if (drag == Drag::kOrbit) model.Orbit(dx, dy);  // leaves a plan or elevation
  if (drag == Drag::kPan) model.Pan(dx, dy);      // within a plan: the drawing follows the cursor
  if ((drag == Drag::kAxis || drag == Drag::kRing) && (dx != 0 || dy != 0)) DragGizmo(x, y);
  if (!left && !right) {  // released
    if (drag == Drag::kClick) Click(x, y);
    drag = Drag::kNone;
  }
}

void ViewerApp::Impl::DragGizmo(double x, double y) {
  const auto ray = MouseRay(x, y);
  if (!ray) return;
  if (StationPoint() && drag == Drag::kAxis) {
    // A station's eye or display: the `station` action with the absolute position.
    const Vec3 axis = Vec3::Unit(drag_handle);
    const auto t0 = AxisParameter(drag_ray, station_start, axis);
    const auto t1 = AxisParameter(*ray, station_start, axis);
    if (!t0 || !t1) return;
    const double total = Snap(*t1 - *t0, move_step);
    if (total == applied) return;
    Action a = Make(Action::Kind::kStation);
    a.text = station;
    a.flag = station_display;
    a.a = station_start + total * axis;
    Do(a);
    applied = total;
    return;
  }
  const int c = Primary();
  if (c < 0) return;
  const Vec3 o = model.rig().cameras[c].center();
  const Vec3 axis = Vec3::Unit(drag_handle);
  if (drag == Drag::kAxis) {
    // The start's parameter against the camera's start position: the handle follows the mouse.
    const Vec3 start_origin = o - applied * axis;
    const auto t0 = AxisParameter(drag_ray, start_origin, axis);
    const auto t1 = AxisParameter(*ray, start_origin, axis);
    if (!t0 || !t1) return;
    const double total = Snap(*t1 - *t0, move_step);
    if (total == applied) return;
    Action a = Make(Action::Kind::kMove, SelectedIds());
    a.a = (total - applied) * axis;
    a.drag = true;
    Do(a);
    applied = total;
  } else {
    const auto angle = SweptAngle(drag_ray, *ray, o, axis);
    if (!angle) return;
    const double total = Snap(*angle / kRadPerDeg, rotate_step);
    if (total == applied) return;
    Action a = Make(Action::Kind::kRotate, SelectedIds());
    a.a = axis;
    a.number = total - applied;
    a.drag = true;
    Do(a);
    applied = total;
  }
}

void ViewerApp::Impl::Click(double x, double y) {
  const auto ray = MouseRay(x, y);
  if (!ray) return;
  const double radius = 0.02 * (model.view.Eye() - model.view.target).norm() + 0.02;
  // A station's eye or display centre within 8 pixels: picked for the gizmo (the cameras
  // deselected); a click elsewhere drops it.
  {
    const Projector P(model.MainView());
    double best = 8.0;
    std::string picked;
    bool display = false;
    for (const auto& [name, st] : model.stations)
      for (int k = 0; k < 2; ++k)
        if (const auto q = P.Point(k ? st.display_center : st.eye)) {
          const double d = std::hypot(q->x - x, q->y - y);
          if (d < best) best = d, picked = name, display = k == 1;
        }
    station = picked;
    station_display = display;
    if (!picked.empty()) {
      Do(Make(Action::Kind::kSelect));
      model.status = "station '" + picked + "': " + (display ? "display" : "eye") +
                     " (drag the gizmo's axes; Save writes it into the scene file)";
      return;
    }
  }
  const int c = PickCamera(model.rig(), *ray, radius);
  std::vector<std::string> ids = input.ctrl ? SelectedIds() : std::vector<std::string>();
  if (c >= 0) {
    ids = ToggledSelection(model.rig().cameras[c].id);
  } else {
    PixelPicker picker(model.session().study().prepared(), model.rig(), model.MainView());
    const int px = std::clamp(int(std::lround(x)), 0, model.width - 1);
    const int py = std::clamp(int(std::lround(y)), 0, model.height - 1);
    if (const auto pick = picker.Pick(px, py)) {
      std::string seen;
      for (int k : pick->cameras) seen += (seen.empty() ? "" : ", ") + model.rig().cameras[k].id;
      model.status = "object '" + model.scene().objects[pick->object].name + "' at (" +
                     std::to_string(pick->point.x()).substr(0, 6) + ", " +
                     std::to_string(pick->point.y()).substr(0, 6) + ", " +
                     std::to_string(pick->point.z()).substr(0, 6) + "), seen by " +
                     (seen.empty() ? "no camera" : seen);
    }
  }
  Action a = Make(Action::Kind::kSelect, ids);
  Do(a);
}

void ViewerApp::Impl::Keys() {
  for (int key : input.pressed) {
    if (ImGui::GetIO().WantCaptureKeyboard) break;
    if (input.ctrl && key == GLFW_KEY_Z)
      Do(Make(input.shift ? Action::Kind::kRedo : Action::Kind::kUndo));
    else if (input.ctrl && key == GLFW_KEY_Y)
      Do(Make(Action::Kind::kRedo));
    else if (input.ctrl && key == GLFW_KEY_S)
      Do(Make(Action::Kind::kSave));
    else if (key == GLFW_KEY_ESCAPE)
      station.clear(), Do(Make(Action::Kind::kSelect));
    else if (key == GLFW_KEY_F)
      model.plan.clear(),
          model.view = OrbitView::Framing(model.scene().Bounds(), model.view.fov_deg);
  }
  input.pressed.clear();
  // Fly with W A S D Q E while the right button is held.
  if (input.down[1] && !ImGui::GetIO().WantCaptureKeyboard) {
    const Vec3 fly(input.keys[GLFW_KEY_D] - input.keys[GLFW_KEY_A],
                   input.keys[GLFW_KEY_E] - input.keys[GLFW_KEY_Q],
                   input.keys[GLFW_KEY_W] - input.keys[GLFW_KEY_S]);
    if (fly != Vec3::Zero()) model.LeavePlan();  // flying is 3D
    const double step = 0.02 * model.view.distance;
    model.view.Fly(step * fly.x(), step * fly.y(), step * fly.z());
  }
}

void ViewerApp::Impl::Gamepad() {
  GLFWgamepadstate s;
  if (!window) return;  // headless: no input devices
  if (!glfwJoystickIsGamepad(GLFW_JOYSTICK_1) || !glfwGetGamepadState(GLFW_JOYSTICK_1, &s)) return;
  GamepadAxes g;
  g.left_x = s.axes[GLFW_GAMEPAD_AXIS_LEFT_X];
  g.left_y = s.axes[GLFW_GAMEPAD_AXIS_LEFT_Y];
  g.right_x = s.axes[GLFW_GAMEPAD_AXIS_RIGHT_X];
  g.right_y = s.axes[GLFW_GAMEPAD_AXIS_RIGHT_Y];
  g.left_trigger = s.axes[GLFW_GAMEPAD_AXIS_LEFT_TRIGGER];
  g.right_trigger = s.axes[GLFW_GAMEPAD_AXIS_RIGHT_TRIGGER];
  const bool active = StickCurve(g.left_x) != 0 || StickCurve(g.left_y) != 0 ||
                      StickCurve(g.right_x) != 0 || StickCurve(g.right_y) != 0 ||
                      g.left_trigger > -0.9 || g.right_trigger > -0.9;
  if (!active) return;
  const double dt = std::clamp(frame_seconds, 1e-3, 0.1);
  if (Primary() < 0) {
    model.LeavePlan();
    model.view.Fly(dt * 1.5 * StickCurve(g.left_x), 0, -dt * 1.5 * StickCurve(g.left_y));
    model.view.Look(-dt * 60 * StickCurve(g.right_x), -dt * 60 * StickCurve(g.right_y));
    return;
  }
  Action a = Make(Action::Kind::kGamepad, {model.rig().cameras[Primary()].id});
  a.a = Vec3(g.left_x, g.left_y, 0);
  a.b = Vec3(g.right_x, g.right_y, 0);
  a.number = dt;
  a.drag = true;
  Do(a);
}

void ViewerApp::Impl::Panels() {
  const Rig& rig = model.rig();
  session::EditableRig& edit = model.session().rig();
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(250, 300), ImGuiCond_FirstUseEver);
  ImGui::Begin("Rig");
  ImGui::Text("%s: %d of %zu cameras on", rig.name.c_str(), rig.enabled_count(),
              rig.cameras.size());
  if (ImGui::Button("Undo")) Do(Make(Action::Kind::kUndo));
  ImGui::SameLine();
  if (ImGui::Button("Redo")) Do(Make(Action::Kind::kRedo));
  ImGui::SameLine();
  if (ImGui::Button("Save")) Do(Make(Action::Kind::kSave));
  ImGui::SameLine();
  ImGui::TextDisabled("%zu unsaved", edit.Unsaved().size());
  // The proposal views of `pandora render --plan` / `--elevation SIDE` (docs/viewer.md).
  auto plan_button = [&](const char* label, const char* view, const char* side) {
    const bool on = model.plan == (side[0] ? side : "plan");
    if (on) ImGui::PushStyleColor(ImGuiCol_Button, ImGui::GetStyleColorVec4(ImGuiCol_ButtonActive));
    if (ImGui::SmallButton(label)) {
      Action a = Make(Action::Kind::kView);
      a.text = view;
      a.text2 = side;
      Do(a);
    }
    if (on) ImGui::PopStyleColor();
  };
  plan_button("Plan", "plan", "");
  ImGui::SameLine();
  ImGui::TextUnformatted("Elevation");
  for (const char* side : {"north", "south", "east", "west"}) {
    ImGui::SameLine();
    const char label[2] = {char(side[0] - 'a' + 'A'), 0};
    ImGui::PushID(side);
    plan_button(label, "elevation", side);
    ImGui::PopID();
  }
  ImGui::Separator();
  for (int c = 0; c < int(rig.cameras.size()); ++c) {
    const Camera& cam = rig.cameras[c];
    ImGui::PushID(c);
    bool on = cam.enabled;
    if (ImGui::Checkbox("##on", &on))
      Do(Make(on ? Action::Kind::kEnable : Action::Kind::kDisable, {cam.id}));
    ImGui::SameLine();
    ImGui::ColorButton(
        "##col", ImVec4(float(cam.color.x()), float(cam.color.y()), float(cam.color.z()), 1.0f),
        ImGuiColorEditFlags_NoTooltip, ImVec2(14, 14));
    ImGui::SameLine();
    const bool selected = std::count(model.selection.begin(), model.selection.end(), c) > 0;
    if (ImGui::Selectable(cam.id.c_str(), selected)) {
      Do(Make(Action::Kind::kSelect, ToggledSelection(cam.id)));
    }
    ImGui::PopID();
  }
  ImGui::End();

  CameraPanel();
  FieldsPanel();
  ComparePanel();
  SuggestPanel();
  DisplayPanel();

  // Camera's-eye views of up to four selected cameras, distortion included: the GPU's (the exact
  // CPU renderer's for wide fisheyes), live while cameras move.
  for (std::size_t i = 0; i < model.selection.size() && i < 4; ++i) {
    const int c = model.selection[i];
    RenderCameraView(c);
    const CameraView& v = camera_views[c];
    ImGui::SetNextWindowPos(
        ImVec2(float(model.width - v.width - 24), float(8 + i * (v.height + 44))),
        ImGuiCond_FirstUseEver);
    ImGui::Begin(("View " + rig.cameras[c].id).c_str(), nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(v.texture)),
                 ImVec2(float(v.width), float(v.height)));
    ImGui::End();
  }

  // Status bar.
  ImGui::SetNextWindowPos(ImVec2(0, float(model.height - 28)));
  ImGui::SetNextWindowSize(ImVec2(float(model.width), 28));
  ImGui::Begin(
      "##status", nullptr,
      ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings);
  const session::JobStatus f = model.session().jobs().Status("fields");
  const std::string undo = edit.can_undo() ? "undo: " + edit.undo_label() : "nothing to undo";
  const std::string timing =
      options.show_timing ? " | GPU frame " + std::to_string(int(1000 * gl_seconds)) + " ms" : "";
  // The status bar stays on top of the panels (one may have been dragged over it).
  ImGui::BringWindowToDisplayFront(ImGui::GetCurrentWindow());
  if (!error.empty()) {
    // An error first, in red, without the file name the window already shows; all of it on hover.
    ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "%s", error_line.c_str());
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", error.c_str());
    ImGui::SameLine();
  }
  ImGui::Text("%s%s | fields %s%s%s%s%s", error.empty() ? "" : "| ", undo.c_str(),
              session::JobStateName(f.state),
              f.state == session::JobState::kRunning
                  ? (" " + std::to_string(int(100 * f.progress)) + "%").c_str()
                  : "",
              timing.c_str(), error.empty() && !model.status.empty() ? " | " : "",
              error.empty() ? model.status.c_str() : "");
  ImGui::End();
}

void ViewerApp::Impl::Draw() {
  glBindFramebuffer(GL_FRAMEBUFFER, FrameFramebuffer());
  int fw = 0, fh = 0;
  FramebufferSize(&fw, &fh);
  glViewport(0, 0, fw, fh);
  glClearColor(0.02f, 0.02f, 0.03f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void ViewerApp::Impl::FeedImGui() {
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(float(model.width), float(model.height));
  io.DeltaTime = float(std::clamp(frame_seconds, 1e-3, 0.25));
  io.MousePos = ImVec2(float(input.x), float(input.y));
  for (int b = 0; b < 3; ++b) io.MouseDown[b] = input.down[b];
  io.MouseWheel = float(input.wheel);
  input.wheel = 0;
  io.KeyCtrl = input.ctrl;
  io.KeyShift = input.shift;
  io.KeyAlt = input.alt;
  for (int k = 0; k <= GLFW_KEY_LAST && k < int(IM_ARRAYSIZE(io.KeysDown)); ++k)
    io.KeysDown[k] = input.keys[k];
  for (unsigned ch : input.chars) io.AddInputCharacter(ch);
  input.chars.clear();
}

bool ViewerApp::Impl::OneFrame() {
  const auto now = std::chrono::steady_clock::now();
  frame_seconds = std::chrono::duration<double>(now - last_frame).count();
  last_frame = now;
  // The last frame's time besides its picture, while frames follow each other (not after a wait
  // for input).
  if (frame_gl_seconds > 0 && frame_seconds < 1.0)
    overhead_seconds =
        0.7 * overhead_seconds + 0.3 * std::max(0.0, frame_seconds - frame_gl_seconds);
  frame_gl_seconds = 0;
  int w = 0, h = 0;
  if (window) glfwGetWindowSize(window, &w, &h);
  if (w > 0 && h > 0 && (w != model.width || h != model.height) && options.visible) {
    model.width = w;
    model.height = h;
  }
  FeedImGui();
  ImGui_ImplOpenGL3_NewFrame();
  ImGui::NewFrame();
  const bool mouse_free = !ImGui::GetIO().WantCaptureMouse;
  Keys();
  Gamepad();
  Handle3d(mouse_free);
  RenderMain();
  ImDrawList* bg = ImGui::GetBackgroundDrawList();
  bg->AddImage(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(shown_texture)), ImVec2(0, 0),
               ImVec2(float(model.width), float(model.height)));
  DrawOverlays(bg);
  Panels();
  Draw();
  return !window || !glfwWindowShouldClose(window);
}

namespace {

ViewerApp::Impl* g_app = nullptr;  // GLFW's callbacks reach the one window through it

void OnCursor(GLFWwindow*, double x, double y) {
  g_app->input.x = x;
  g_app->input.y = y;
}
void OnButton(GLFWwindow*, int button, int action, int mods) {
  if (button >= 0 && button < 3) g_app->input.down[button] = action == GLFW_PRESS;
  g_app->input.ctrl = mods & GLFW_MOD_CONTROL;
  g_app->input.shift = mods & GLFW_MOD_SHIFT;
}
void OnScroll(GLFWwindow*, double, double dy) { g_app->input.wheel += dy; }
void OnKey(GLFWwindow*, int key, int, int action, int mods) {
  if (key >= 0 && key <= GLFW_KEY_LAST) g_app->input.keys[key] = action != GLFW_RELEASE;
  if (action == GLFW_PRESS) g_app->input.pressed.push_back(key);
  g_app->input.ctrl = mods & GLFW_MOD_CONTROL;
  g_app->input.shift = mods & GLFW_MOD_SHIFT;
  g_app->input.alt = mods & GLFW_MOD_ALT;
}
void OnChar(GLFWwindow*, unsigned c) { g_app->input.chars.push_back(c); }

}  // namespace

ViewerApp::ViewerApp(ViewerModel& model, AppOptions options)
    : impl_(std::make_unique<Impl>(model, options)) {
  Impl& m = *impl_;
  model.width = options.width;
  model.height = options.height;
  if (!options.visible && ResolveGlBackend(options.gl) == GlBackend::kEgl)
    m.OpenHeadless();
  else
    m.OpenWindow();
  m.InitImGui();
  m.gl = std::make_unique<GlRenderer>(model.scene(), &model.session().study().prepared());
  m.shadow_map_size = options.shadow_map_size;
  m.map_index = options.shadow_map_size >= 4096   ? 3
                : options.shadow_map_size >= 2048 ? 2
                : options.shadow_map_size >= 1024 ? 1
                                                  : 0;
}

void ViewerApp::Impl::OpenHeadless() {
  headless = std::make_unique<GlContext>(GlBackend::kEgl);
  glGenTextures(1, &frame_color);
  glBindTexture(GL_TEXTURE_2D, frame_color);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, options.width, options.height, 0, GL_RGBA,
               GL_UNSIGNED_BYTE, nullptr);
  glGenFramebuffers(1, &frame_fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, frame_fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, frame_color, 0);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("pandora view: the headless window's framebuffer is incomplete");
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void ViewerApp::Impl::OpenWindow() {
  glfwSetErrorCallback(OnGlfwError);
  if (!glfwInit())
    throw std::runtime_error("pandora view: no display (" + g_glfw_error +
                             "); on a machine without one run under `xvfb-run -a`, or add "
                             "--hidden for a headless session (EGL)");
  glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window = glfwCreateWindow(options.width, options.height,
                            ("Pandora: " + model.scene().path).c_str(), nullptr, nullptr);
  if (!window) {
    glfwTerminate();
    throw std::runtime_error("pandora view: no OpenGL 3.3 core context (" + g_glfw_error +
                             "); install Mesa (libgl1-mesa-dri) or a GPU driver");
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  g_app = this;
  glfwSetCursorPosCallback(window, OnCursor);
  glfwSetMouseButtonCallback(window, OnButton);
  glfwSetScrollCallback(window, OnScroll);
  glfwSetKeyCallback(window, OnKey);
  glfwSetCharCallback(window, OnChar);
}

void ViewerApp::Impl::InitImGui() {
  Impl& m = *this;
  IMGUI_CHECKVERSION();
  m.imgui = ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // the same layout every start (and in tests)
  io.KeyMap[ImGuiKey_Tab] = GLFW_KEY_TAB;
  io.KeyMap[ImGuiKey_LeftArrow] = GLFW_KEY_LEFT;
  io.KeyMap[ImGuiKey_RightArrow] = GLFW_KEY_RIGHT;
  io.KeyMap[ImGuiKey_UpArrow] = GLFW_KEY_UP;
  io.KeyMap[ImGuiKey_DownArrow] = GLFW_KEY_DOWN;
  io.KeyMap[ImGuiKey_Backspace] = GLFW_KEY_BACKSPACE;
  io.KeyMap[ImGuiKey_Delete] = GLFW_KEY_DELETE;
  io.KeyMap[ImGuiKey_Enter] = GLFW_KEY_ENTER;
  io.KeyMap[ImGuiKey_Escape] = GLFW_KEY_ESCAPE;
  io.KeyMap[ImGuiKey_Home] = GLFW_KEY_HOME;
  io.KeyMap[ImGuiKey_End] = GLFW_KEY_END;
  io.KeyMap[ImGuiKey_A] = GLFW_KEY_A;
  io.KeyMap[ImGuiKey_C] = GLFW_KEY_C;
  io.KeyMap[ImGuiKey_V] = GLFW_KEY_V;
  io.KeyMap[ImGuiKey_X] = GLFW_KEY_X;
  io.KeyMap[ImGuiKey_Z] = GLFW_KEY_Z;
  ImGui::StyleColorsDark();
  ImGui::GetStyle().WindowRounding = 3.0f;
  ImGui_ImplOpenGL3_Init("#version 330 core");
}

ViewerApp::~ViewerApp() {
  Impl& m = *impl_;
  if (m.window)
    glfwMakeContextCurrent(m.window);
  else
    m.headless->MakeCurrent();
  m.gl.reset();
  if (m.main_texture) glDeleteTextures(1, &m.main_texture);
  for (auto& [c, v] : m.camera_views)
    if (v.texture) glDeleteTextures(1, &v.texture);
  for (auto& [name, v] : m.station_views)
    if (v.texture) glDeleteTextures(1, &v.texture);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui::DestroyContext(m.imgui);
  if (m.window) {
    glfwDestroyWindow(m.window);
    glfwTerminate();
    g_app = nullptr;
  } else {
    glDeleteFramebuffers(1, &m.frame_fbo);
    glDeleteTextures(1, &m.frame_color);
  }
}

bool ViewerApp::Frame() {
  if (impl_->window) glfwPollEvents();
  impl_->readback_bytes = impl_->upload_bytes = 0;
  impl_->map_cpu_seconds = 0;
  const bool open = impl_->OneFrame();
  impl_->last_transfer = {impl_->readback_bytes, impl_->upload_bytes, impl_->map_cpu_seconds};
  impl_->Present();
  return open;
}

void ViewerApp::SetMotionScale(double scale, double target_hz) {
  impl_->options.motion_scale = scale;
  impl_->options.target_hz = target_hz;
  impl_->motion_now = scale;
  impl_->main_key.clear();  // draw the next frame anew
}

double ViewerApp::MotionScaleNow() const { return impl_->motion_now; }

FrameTransfer ViewerApp::LastFrameTransfer() const { return impl_->last_transfer; }

std::string ViewerApp::GlDescription() const {
  if (impl_->headless) return impl_->headless->Description() + " (headless)";
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(renderer ? renderer : "?") + ", " + (version ? version : "?") +
         " [GLFW window]";
}

void ViewerApp::Loop() {
  while (Frame()) {
  }
}

void ViewerApp::Screenshot(const ViewerModel& model, const std::string& path, int camera) {
  if (camera >= 0) {
    CpuFrontend().Screenshot(model, path, camera);
    return;
  }
  // Two frames, so that panels placed in the first are drawn in place in the second; then the back
  // buffer as it would be shown.
  Impl& m = *impl_;
  m.full_now = true;
  m.OneFrame();
  m.Present();
  m.OneFrame();
  m.full_now = false;
  int fw = 0, fh = 0;
  m.FramebufferSize(&fw, &fh);
  std::vector<unsigned char> pixels(std::size_t(fw) * fh * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.FrameFramebuffer());
  glReadBuffer(m.window ? GL_BACK : GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  m.Present();
  // To linear RGB for WritePng (which applies the sRGB curve again), rows flipped to y down.
  Image image;
  image.width = fw;
  image.height = fh;
  image.rgb.resize(std::size_t(fw) * fh * 3);
  for (int y = 0; y < fh; ++y)
    for (int x = 0; x < fw; ++x)
      for (int k = 0; k < 3; ++k)
        image.rgb[(std::size_t(y) * fw + x) * 3 + k] =
            float(LinearFromSrgb(pixels[(std::size_t(fh - 1 - y) * fw + x) * 4 + k] / 255.0));
  WritePng(image, path);
}

void ViewerApp::Input(ViewerModel&, const Action& a) {
  Impl& m = *impl_;
  using Kind = Action::Kind;
  const int button = a.text2 == "right" ? 1 : a.text2 == "middle" ? 2 : 0;
  switch (a.kind) {
    case Kind::kMouse: {
      double x = a.number3, y = a.number2;
      const Projector P(m.model.MainView());
      auto pixel = [&](const Vec3& w) {
        const auto q = P.Point(w);
        if (!q) throw InputError(a.where, "", "the point is behind the main view's eye");
        x = q->x;
        y = q->y;
      };
      if (a.has_a) {
        pixel(a.a);
      } else if (a.gizmo >= 0) {
        // The handle as it was when the drag began: a move "by" d aims where the handle's grip
        // point would be after moving d metres along the axis (turning d degrees on a ring).
        if (a.text == "press" || !m.script_gizmo) {
          const auto o = m.GizmoOrigin();
          if (!o)
            throw InputError(a.where, "",
                             "no gizmo: select a camera or pick a station point first");
          m.script_gizmo = std::make_pair(*o, m.GizmoLength());
        }
        const auto [o, len] = *m.script_gizmo;
        const int k = a.gizmo % 3;
        const Vec3 axis = Vec3::Unit(k);
        if (a.gizmo < 3) {
          pixel(o + (0.6 * len + a.number) * axis);
        } else {
          const Vec3 u = Vec3::Unit((k + 1) % 3), v = Vec3::Unit((k + 2) % 3);
          const double t = 0.6 + a.number * kRadPerDeg;  // the grip at 0.6 rad round the ring
          pixel(o + 0.8 * len * (std::cos(t) * u + std::sin(t) * v));
        }
        if (a.text == "release") m.script_gizmo.reset();
      }
      m.input.x = x;
      m.input.y = y;
      if (a.text == "press") m.input.down[button] = true;
      if (a.text == "release") m.input.down[button] = false;
      Frame();
      break;
    }
    case Kind::kScroll:
      m.input.x = a.number3;
      m.input.y = a.number2;
      m.input.wheel += a.number;
      Frame();
      break;
    case Kind::kKey: {
      // "ctrl+shift+z": modifiers, then one key (a letter, a digit, or escape/enter/tab/delete).
      std::string key = a.text;
      m.input.ctrl = m.input.shift = m.input.alt = false;
      for (;;) {
        const auto plus = key.find('+');
        if (plus == std::string::npos) break;
        const std::string mod = key.substr(0, plus);
        if (mod == "ctrl")
          m.input.ctrl = true;
        else if (mod == "shift")
          m.input.shift = true;
        else if (mod == "alt")
          m.input.alt = true;
        else
          throw InputError(a.where, "", "unknown modifier '" + mod + "'", "use ctrl, shift, alt");
        key = key.substr(plus + 1);
      }
      static const std::map<std::string, int> named = {{"escape", GLFW_KEY_ESCAPE},
                                                       {"enter", GLFW_KEY_ENTER},
                                                       {"tab", GLFW_KEY_TAB},
                                                       {"delete", GLFW_KEY_DELETE}};
      int code = -1;
      if (key.size() == 1 && std::isalpha(static_cast<unsigned char>(key[0])))
        code = GLFW_KEY_A + (std::tolower(key[0]) - 'a');
      else if (key.size() == 1 && std::isdigit(static_cast<unsigned char>(key[0])))
        code = GLFW_KEY_0 + (key[0] - '0');
      else if (named.count(key))
        code = named.at(key);
      if (code < 0)
        throw InputError(a.where, "", "unknown key '" + key + "'",
                         "a letter, a digit, escape, enter, tab or delete");
      m.input.keys[code] = true;
      m.input.pressed.push_back(code);
      Frame();
      m.input.keys[code] = false;
      m.input.ctrl = m.input.shift = m.input.alt = false;
      Frame();
      break;
    }
    case Kind::kFrames:
      for (int i = 0; i < int(a.number); ++i) Frame();
      break;
    default:
      break;
  }
}

}  // namespace pandora::viewer
