// The window of `pandora view` (viewer/window/viewer_app.h). Input from GLFW and from scripts lands
// in one InputState; each frame feeds it to Dear ImGui (no platform backend: the state is ours, so
// a script drives the panels exactly as a mouse does), then to the 3D handlers (orbit, pan, dolly,
// pick, gizmo), which turn it into the model's actions.
#include "viewer/window/viewer_app.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <imgui_internal.h>  // BringWindowToDisplayFront: the status bar above the panels

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "analysis/geometry/pose.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "render/isosurface.h"
#include "render/prepared_scene.h"
#include "viewer/core/manipulate.h"
#include "viewer/core/station.h"
#include "viewer/gl/renderer.h"
#include "volume/fields.h"
#include "volume/slice.h"
#include "volume/summary.h"

namespace pandora::viewer {
namespace {

std::string g_glfw_error;
void OnGlfwError(int code, const char* text) {
  g_glfw_error = std::string(text) + " (" + std::to_string(code) + ")";
}

unsigned char ToSrgb8(double linear) {
  return static_cast<unsigned char>(std::lround(255.0 * SrgbFromLinear(linear)));
}

// Linear RGB (3 floats per pixel) to 8-bit sRGB RGBA, opaque.
std::vector<unsigned char> ToRgba8(const std::vector<float>& rgb) {
  std::vector<unsigned char> rgba(rgb.size() / 3 * 4);
  for (std::size_t i = 0; i < rgb.size() / 3; ++i) {
    for (int k = 0; k < 3; ++k) rgba[4 * i + k] = ToSrgb8(rgb[3 * i + k]);
    rgba[4 * i + 3] = 255;
  }
  return rgba;
}

ImU32 Color(const Vec3& rgb, double alpha = 1.0) {
  return IM_COL32(ToSrgb8(rgb.x()), ToSrgb8(rgb.y()), ToSrgb8(rgb.z()), int(255 * alpha));
}

// What the mouse, the keys and the scroll wheel did: filled by GLFW callbacks or by a script.
struct InputState {
  double x = 0, y = 0;
  bool down[3] = {false, false, false};
  double wheel = 0;
  bool ctrl = false, shift = false, alt = false;
  bool keys[GLFW_KEY_LAST + 1] = {};
  std::vector<unsigned> chars;
  std::vector<int> pressed;  // keys pressed since the last frame
};

// The main view's projection for overlays (the renderer's convention: pixel centres at integers).
struct Projector {
  Eigen::Isometry3d camera_from_world;
  double f = 1, cx = 0, cy = 0;
  explicit Projector(const RenderView& v) {
    camera_from_world = LookAt(v.from, v.at, v.up)->inverse();
    f = 0.5 * v.width / std::tan(0.5 * v.fov_deg * kRadPerDeg);
    cx = 0.5 * v.width - 0.5;
    cy = 0.5 * v.height - 0.5;
  }
  ImVec2 Pixel(const Vec3& c) const {
    return ImVec2(float(cx + f * c.x() / c.z() + 0.5), float(cy + f * c.y() / c.z() + 0.5));
  }
  // The segment a-b clipped to the half space in front of the eye; false when none of it is.
  bool Segment(const Vec3& a, const Vec3& b, ImVec2* pa, ImVec2* pb) const {
    Vec3 p = camera_from_world * a, q = camera_from_world * b;
    const double near = 1e-3;
    if (p.z() < near && q.z() < near) return false;
    if (p.z() < near) p = p + (q - p) * ((near - p.z()) / (q.z() - p.z()));
    if (q.z() < near) q = q + (p - q) * ((near - q.z()) / (p.z() - q.z()));
    *pa = Pixel(p);
    *pb = Pixel(q);
    return true;
  }
  std::optional<ImVec2> Point(const Vec3& w) const {
    const Vec3 c = camera_from_world * w;
    if (c.z() < 1e-3) return std::nullopt;
    return Pixel(c);
  }
};

double SegmentDistance(const ImVec2& p, const ImVec2& a, const ImVec2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  const double ex = a.x + t * dx - p.x, ey = a.y + t * dy - p.y;
  return std::sqrt(ex * ex + ey * ey);
}

// A camera's frustum outline: rays through its image border (distortion included), `length` metres.
std::vector<Vec3> FrustumBorder(const Camera& cam, double length) {
  std::vector<Vec3> out;
  const CameraModel& m = cam.model;
  const double w = m.width() - 0.5, h = m.height() - 0.5;
  const int n = m.intrinsics().model == LensModel::kPinhole ? 1 : 8;
  auto add = [&](double u, double v) {
    if (const auto d = m.Unproject(Vec2(u, v)))
      out.push_back(cam.world_from_camera * (*d * length));
  };
  for (int i = 0; i < n; ++i) add(-0.5 + (w + 0.5) * i / n, -0.5);
  for (int i = 0; i < n; ++i) add(w, -0.5 + (h + 0.5) * i / n);
  for (int i = 0; i < n; ++i) add(w - (w + 0.5) * i / n, h);
  for (int i = 0; i < n; ++i) add(-0.5, h - (h + 0.5) * i / n);
  return out;
}

enum class Drag { kNone, kOrbit, kPan, kAxis, kRing, kClick };

}  // namespace

struct ViewerApp::Impl {
  ViewerModel& model;
  AppOptions options;
  GLFWwindow* window = nullptr;
  std::unique_ptr<GlRenderer> gl;
  GlRenderOptions gl_options;
  GLuint main_texture = 0;
  std::string main_key;    // what the main texture shows
  bool main_full = false;  // ... at full resolution
  bool full_now = false;   // a screenshot: draw in full whatever moved just before
  std::chrono::steady_clock::time_point last_change, last_rig_change;
  std::int64_t main_rig_version = -1;
  double motion_now = 0.5;  // the scale of the next moving frame (adapted to AppOptions::target_hz)
  double overhead_seconds = 0;  // the frame's time besides the main picture (running mean)
  double frame_gl_seconds = 0;  // this frame's main picture, 0 when it was kept
  static constexpr double kMinMotionScale = 0.2;
  int shadow_map_size = 2048;
  InputState input;
  ImGuiContext* imgui = nullptr;
  std::chrono::steady_clock::time_point last_frame = std::chrono::steady_clock::now();
  double frame_seconds = 0, gl_seconds = 0;

  // 3D interaction.
  Drag drag = Drag::kNone;
  int drag_handle = -1;  // axis 0..2
  double press_x = 0, press_y = 0, last_x = 0, last_y = 0;
  Ray drag_ray;
  double applied = 0;     // metres or degrees already applied in this drag
  int hover_handle = -1;  // 0..2 axes, 3..5 rings
  bool hover_ring = false;
  float move_step = 0.0f, rotate_step = 0.0f;  // snap steps (0: off)
  // A viewing station's eye or display centre picked for the gizmo (translation only); empty: none.
  std::string station;
  bool station_display = false;
  Vec3 station_start = Vec3::Zero();  // where the point was when the drag began
  std::optional<std::pair<Vec3, double>>
      script_gizmo;  // a script's gizmo drag: origin, length at its press

  // Camera views (exact, CPU) of the selected cameras.
  struct CameraView {
    GLuint texture = 0;
    std::int64_t version = -1;
    int width = 0, height = 0;
  };
  std::map<int, CameraView> camera_views;
  std::map<std::string, CameraView> station_views;  // each display's image

  // Field panel cache.
  std::int64_t slice_version = -2;
  std::string slice_key;
  FieldSlice slice;
  std::string slice_view_key;         // the view and slice slice_hidden was tested for
  std::vector<uint8_t> slice_hidden;  // per slice voxel: the scene hides its centre from the eye

  // Suggest panel settings.
  int objective = 0;
  float max_move = 0.3f, max_rotate = 10.0f;
  int points = 1500;       // pandora suggest's --points
  std::string error;       // the last action's error, shown in the status bar (all of it on hover)
  std::string error_line;  // ... its reason and hint, first in the status bar

  Impl(ViewerModel& m, AppOptions o) : model(m), options(o) { motion_now = o.motion_scale; }

  void Do(const Action& a) {
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
  Action Make(Action::Kind kind, std::vector<std::string> cameras = {}) const {
    Action a;
    a.kind = kind;
    a.where = "the window";
    a.cameras = std::move(cameras);
    return a;
  }
  int Primary() const { return model.selection.empty() ? -1 : model.selection.front(); }
  std::vector<std::string> SelectedIds() const {
    std::vector<std::string> ids;
    for (int c : model.selection) ids.push_back(model.rig().cameras[c].id);
    return ids;
  }
  // The selection after a click on camera `id`: that camera alone, or with ctrl the selection with
  // it added (or removed when it was in).
  std::vector<std::string> ToggledSelection(const std::string& id) const {
    std::vector<std::string> ids = input.ctrl ? SelectedIds() : std::vector<std::string>();
    const auto it = std::find(ids.begin(), ids.end(), id);
    if (it != ids.end())
      ids.erase(it);
    else
      ids.push_back(id);
    return ids;
  }
  std::optional<Ray> MouseRay(double x, double y) const {
    return PixelRay(model.rig(), model.MainView(), x, y);
  }
  // The picked station point, when the station still exists.
  std::optional<Vec3> StationPoint() const {
    const auto it = model.stations.find(station);
    if (station.empty() || it == model.stations.end()) return std::nullopt;
    return station_display ? it->second.display_center : it->second.eye;
  }
  // Where the gizmo sits: the picked station point, else the primary camera's centre.
  std::optional<Vec3> GizmoOrigin() const {
    if (const auto p = StationPoint()) return p;
    const int c = Primary();
    if (c < 0) return std::nullopt;
    return model.rig().cameras[c].center();
  }
  double GizmoLength() const {
    const auto o = GizmoOrigin();
    if (!o) return 0.3;
    return 0.12 * (*o - model.view.Eye()).norm();
  }

  // The "all" PTZ trace rendered in the background: each completed pass of the progressive CPU
  // frame (coarse first) is uploaded on the next frame. Shared with the job, which may outlive a
  // frame.
  struct AllTraceSlot {
    std::mutex mutex;
    Image image;
    bool fresh = false;
    std::int64_t generation = 0;  // of the newest frame asked for; older jobs' passes are dropped
  };
  std::shared_ptr<AllTraceSlot> all_trace = std::make_shared<AllTraceSlot>();
  std::string all_trace_key;  // the main view's key of the newest "all" frame asked for

  void UploadAllTrace() {
    std::lock_guard<std::mutex> lock(all_trace->mutex);
    if (!all_trace->fresh) return;
    all_trace->fresh = false;
    if (model.ptz_trace != "all") return;  // a pass that finished after the mode changed
    Upload(&main_texture, all_trace->image.width, all_trace->image.height,
           ToRgba8(all_trace->image.rgb));
  }

  void RenderMain() {
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
    if (key == main_key && main_texture && (moving || main_full)) return;
    main_key = key;
    main_full = !moving;
    if (moving) {
      view.width = std::max(16, int(std::lround(view.width * motion_now)));
      view.height = std::max(16, int(std::lround(view.height * motion_now)));
    }
    // Maps: at most 1024 texels while the eye moves (drawn once, then reused), 512 while cameras
    // move (their maps are drawn every frame).
    gl_options.shadow_map_size =
        !moving ? shadow_map_size
                : std::min(shadow_map_size, since(last_rig_change) < 0.3 ? 512 : 1024);
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
        all_trace_key = key;
      } else if (key != all_trace_key) {
        // Coarse first (1/64 of the pixels), then refined; a newer frame cancels this one.
        all_trace_key = key;
        const std::int64_t generation = next_generation();
        auto slot = all_trace;
        model.session().RenderInBackground(
            traced, model.MainView(), o, nullptr,
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
      const GlImage image =
          gl->Render(model.ptz_trace == "single" ? model.rig() : model.TracedRig(nullptr), view, o);
      Upload(&main_texture, image.width, image.height, ToRgba8(image.rgb));
    }
    gl_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    frame_gl_seconds = gl_seconds;
    // Adaptive resolution while moving: the next moving frame's scale aims at the target rate
    // from this frame's light and the rest of the frame (panels, overlays, swap: overhead_seconds),
    // the picture's cost taken as proportional to its pixels; at most 30 % per frame, within
    // [kMinMotionScale, 1].
    if (moving && options.target_hz > 0) {
      const double total = gl_seconds + overhead_seconds;
      const double factor =
          std::clamp(std::sqrt((1.0 / options.target_hz) / std::max(total, 1e-4)), 0.7, 1.3);
      motion_now = std::clamp(motion_now * factor, kMinMotionScale, 1.0);
    }
  }

  static void Upload(GLuint* texture, int w, int h, const std::vector<unsigned char>& rgba) {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!*texture) glGenTextures(1, texture);
    glBindTexture(GL_TEXTURE_2D, *texture);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  }

  // The display settings for the small exact views (a camera's, a station's display): the light
  // and surfaces as in the main view, without the slice, isosurface, key or float layers.
  RenderOptions InsetOptions() const {
    RenderOptions o = model.display;
    o.layers = false;
    o.overlays.slice_field.clear();
    o.overlays.iso_field.clear();
    o.overlays.key = false;
    return o;
  }

  void RenderCameraView(int c) {
    CameraView& v = camera_views[c];
    const std::int64_t version =
        model.session().rig().camera_version(c) * 1000003 + model.session().rig().version();
    if (v.texture && v.version == version) return;
    const CameraModel& m = model.rig().cameras[c].model;
    const double scale = std::min(1.0, 256.0 / m.width());
    RenderView view;
    view.camera = c;
    view.width = std::max(16, int(std::lround(m.width() * scale)));
    view.height = std::max(16, int(std::lround(m.height() * scale)));
    const Image image = model.session().Render(view, InsetOptions());
    Upload(&v.texture, image.width, image.height, ToRgba8(image.rgb));
    v.version = version;
    v.width = image.width;
    v.height = image.height;
  }

  // Overlay lines and points tested against the scene: each line is cut into pieces of about
  // 8 pixels and each piece (each point) is hidden when the scene is between the eye and its middle
  // (one occlusion ray, exact, as the isosurface's triangles); hidden ones are drawn faded.
  // Collected while the overlays are drawn, tested in one batch and drawn by FlushOverlayPieces.
  struct OverlayPiece {
    Vec3 mid;
    ImVec2 a, b;
    ImU32 color;
    float width;
    float radius;  // > 0: a filled dot at a
  };
  std::vector<OverlayPiece> pieces;
  void Line(const Projector& P, const Vec3& a, const Vec3& b, ImU32 col, float width) {
    ImVec2 pa, pb;
    if (!P.Segment(a, b, &pa, &pb)) return;
    const double pixels = std::hypot(pb.x - pa.x, pb.y - pa.y);
    const int n = std::clamp(int(pixels / 8.0), 1, 64);
    for (int i = 0; i < n; ++i) {
      const Vec3 p = a + (b - a) * (double(i) / n), q = a + (b - a) * (double(i + 1) / n);
      ImVec2 qa, qb;
      if (P.Segment(p, q, &qa, &qb)) pieces.push_back({0.5 * (p + q), qa, qb, col, width, 0.0f});
    }
  }
  void Dot(const Projector& P, const Vec3& p, ImU32 col, float radius) {
    if (const auto q = P.Point(p)) pieces.push_back({p, *q, *q, col, 0.0f, radius});
  }
  void FlushOverlayPieces(ImDrawList* dl) {
    const Vec3 eye = model.MainView().from;
    std::vector<Ray> rays(pieces.size());
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const Vec3 d = pieces[i].mid - eye;
      const double len = d.norm();
      // Short of the point by a millimetre or 1e-4 of the distance: a line on a wall stays visible.
      rays[i] =
          Ray{eye, d / std::max(len, 1e-12), 0.0, std::max(0.0, len - std::max(1e-3, 1e-4 * len))};
    }
    std::vector<uint8_t> hidden;
    model.session().study().caster().OccludedBatch(rays, &hidden);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const OverlayPiece& p = pieces[i];
      ImU32 col = p.color;
      if (hidden[i])
        col = (col & 0x00FFFFFF) | (ImU32((col >> 24) * 0.3) << 24);  // a third of the opacity
      if (p.radius > 0)
        dl->AddCircleFilled(p.a, hidden[i] ? 0.75f * p.radius : p.radius, col);
      else
        dl->AddLine(p.a, p.b, col, hidden[i] ? std::max(1.0f, 0.7f * p.width) : p.width);
    }
    pieces.clear();
  }

  // Camera bodies, frusta, the selection, the suggestion's ghosts, the slice, the gizmo.
  void DrawOverlays(ImDrawList* dl) {
    const Projector P(model.MainView());
    const Rig& rig = model.rig();
    auto line = [&](const Vec3& a, const Vec3& b, ImU32 col, float width) {
      Line(P, a, b, col, width);
    };
    // The slice: its voxels as translucent quads in the plane.
    if (!model.display.overlays.slice_field.empty()) DrawSlice(dl, P);
    if (!model.display.overlays.iso_field.empty()) DrawIso(dl, P);
    auto frustum = [&](const Camera& cam, ImU32 col, float width) {
      const std::vector<Vec3> border = FrustumBorder(cam, 0.6);
      const Vec3 o = cam.center();
      const std::size_t n = border.size();
      for (std::size_t i = 0; i < n; ++i) line(border[i], border[(i + 1) % n], col, width);
      if (n >= 4)
        for (std::size_t i = 0; i < n; i += n / 4) line(o, border[i], col, width);
    };
    for (int c = 0; c < int(rig.cameras.size()); ++c) {
      const Camera& cam = rig.cameras[c];
      const bool selected = std::count(model.selection.begin(), model.selection.end(), c) > 0;
      const ImU32 col =
          cam.enabled ? Color(cam.color, selected ? 1.0 : 0.8) : IM_COL32(110, 110, 110, 160);
      frustum(cam, col, selected ? 2.5f : 1.2f);
      Dot(P, cam.center(), col, selected ? 6.0f : 4.0f);
      if (const auto p = P.Point(cam.center())) {
        if (selected) dl->AddCircle(*p, 9.0f, IM_COL32(255, 255, 255, 230), 0, 1.5f);
        dl->AddText(ImVec2(p->x + 7, p->y - 7), col, cam.id.c_str());
      }
    }
    if (model.suggestion)
      for (const CameraChange& ch : model.suggestion->cameras) {
        Camera ghost = rig.cameras[ch.index];
        ghost.world_from_camera = ch.after;
        frustum(ghost, IM_COL32(255, 255, 255, 200), 1.5f);
        line(ch.before.translation(), ch.after.translation(), IM_COL32(255, 255, 255, 160), 1.0f);
      }
    DrawStations(dl, P);
    // The suggest panel's keep-out boxes (red) and the box mount (white), while the panel uses
    // them.
    auto box = [&](const float* b, ImU32 col) {
      const Vec3 lo(std::min(b[0], b[3]), std::min(b[1], b[4]), std::min(b[2], b[5]));
      const Vec3 hi(std::max(b[0], b[3]), std::max(b[1], b[4]), std::max(b[2], b[5]));
      auto corner = [&](int k) {
        return Vec3(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
      };
      for (int k = 0; k < 8; ++k)
        for (int bit : {1, 2, 4})
          if (!(k & bit)) line(corner(k), corner(k | bit), col, 1.5f);
    };
    for (const auto& k : keep_outs) box(k.data(), IM_COL32(235, 60, 60, 230));
    if (mount == 3) box(mount_box, IM_COL32(240, 240, 240, 200));
    FlushOverlayPieces(dl);
    DrawGizmo(dl, P);  // always on top
  }

  // Viewing stations: each display textured with the scene as its viewer's eye sees it through the
  // display (exact CPU renderer, the display's off-axis camera), the eye's lines to the display's
  // corners, and the tracker's range as a red wireframe.
  void DrawStations(ImDrawList* dl, const Projector& P) {
    auto line = [&](const Vec3& a, const Vec3& b, ImU32 col, float width) {
      Line(P, a, b, col, width);
    };
    for (const auto& [name, st] : model.stations) {
      CameraView& v = station_views[name];
      const std::int64_t version =
          model.session().rig().version() * 1000003 + model.stations_version;
      if (!v.texture || v.version != version) {
        Rig rig = model.rig();
        rig.cameras.push_back(DisplayCamera(st));
        RenderView view;
        view.camera = int(rig.cameras.size()) - 1;
        const double scale = std::min(1.0, 320.0 / st.pixels_wide);
        view.width = std::max(16, int(std::lround(st.pixels_wide * scale)));
        view.height = std::max(16, int(std::lround(st.pixels_high * scale)));
        RenderOptions o = InsetOptions();
        o.overlays.cameras = false;
        const Image image = pandora::Render(model.session().study().prepared(), rig, view, o);
        Upload(&v.texture, image.width, image.height, ToRgba8(image.rgb));
        v.version = version;
      }
      const std::array<Vec3, 4> c = DisplayCorners(st);
      std::optional<ImVec2> q[4];
      bool visible = true;
      for (int k = 0; k < 4; ++k) visible &= bool(q[k] = P.Point(c[k]));
      // The textured face only when its front (the viewer's side) faces the main view's eye.
      if (visible && (model.view.Eye() - st.display_center).dot(st.display_normal) > 0)
        dl->AddImageQuad(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(v.texture)), *q[0],
                         *q[1], *q[2], *q[3], ImVec2(0, 0), ImVec2(1, 0), ImVec2(1, 1),
                         ImVec2(0, 1));
      for (int k = 0; k < 4; ++k) {
        line(c[k], c[(k + 1) % 4], IM_COL32(230, 230, 230, 255), 2.0f);
        line(st.eye, c[k], IM_COL32(230, 230, 230, 90), 1.0f);
      }
      if (const auto d = P.Point(st.display_center)) {
        const bool picked = station == name && station_display;
        const float r = picked ? 5.0f : 3.5f;
        dl->AddRectFilled(ImVec2(d->x - r, d->y - r), ImVec2(d->x + r, d->y + r),
                          IM_COL32(255, 255, 255, 255));
      }
      if (const auto e = P.Point(st.eye)) {
        if (station == name && !station_display)
          dl->AddCircle(*e, 8.0f, IM_COL32(255, 255, 255, 230), 0, 1.5f);
        dl->AddCircleFilled(*e, 4.0f, IM_COL32(255, 255, 255, 255));
        dl->AddText(ImVec2(e->x + 6, e->y - 7), IM_COL32(255, 255, 255, 255),
                    (name + " eye").c_str());
      }
      if (st.has_tracker) {
        const std::array<Vec3, 8> t = TrackerCorners(st);
        const ImU32 red = IM_COL32(235, 50, 50, 220);
        for (int k = 0; k < 4; ++k) {
          line(t[k], t[(k + 1) % 4], red, 1.2f);
          line(t[4 + k], t[4 + (k + 1) % 4], red, 1.2f);
          line(t[k], t[4 + k], red, 1.2f);
        }
        line(st.tracker_pose.translation(), t[0], red, 1.0f);
      }
    }
  }

  void DrawSlice(ImDrawList* dl, const Projector& P) {
    const OverlayOptions& ov = model.display.overlays;
    std::int64_t version = -1;
    char key[256];
    std::snprintf(key, sizeof key, "%s %d %.17g", ov.slice_field.c_str(), ov.slice_axis,
                  ov.slice_position);
    version = slice_version;
    model.session().TryReadFields([&](const Fields& f, std::int64_t v) {  // busy: keep the last one
      version = v;
      if (v == slice_version && key == slice_key) return;
      try {
        slice =
            SliceField(f, ov.slice_field, ov.slice_axis,
                       std::isnan(ov.slice_position)
                           ? f.lattice.origin[ov.slice_axis] +
                                 0.5 * f.lattice.voxel_size * (f.lattice.dims[ov.slice_axis] - 1)
                           : ov.slice_position,
                       false);
      } catch (const std::exception&) {
        slice = FieldSlice();
      }
    });
    slice_version = version;
    slice_key = key;
    if (slice.index < 0 || slice.width == 0) return;
    const double h = slice.voxel_size;
    const int ua = slice.u_axis(), va = slice.v_axis();
    const double lo = std::isfinite(ov.slice_min) ? ov.slice_min : slice.min;
    const double hi = std::isfinite(ov.slice_max) ? ov.slice_max : slice.max;
    // Voxels the scene hides from the eye (the ray to the voxel's centre is blocked) at a third of
    // the opacity; tested again only when the view or the slice changes.
    const RenderView view = model.MainView();
    char vkey[512];
    std::snprintf(vkey, sizeof vkey, "%s %lld %.17g %.17g %.17g", key,
                  static_cast<long long>(slice_version), view.from.x(), view.from.y(),
                  view.from.z());
    if (vkey != slice_view_key) {
      slice_view_key = vkey;
      std::vector<Ray> rays(std::size_t(slice.width) * slice.height);
      for (int row = 0; row < slice.height; ++row)
        for (int col = 0; col < slice.width; ++col) {
          Vec3 c = Vec3::Zero();
          c[slice.axis] = slice.coordinate;
          c[ua] = slice.u_min + h * col;
          c[va] = slice.v_max - h * row;
          const Vec3 d = c - view.from;
          const double len = d.norm();
          rays[std::size_t(row) * slice.width + col] =
              Ray{view.from, d / std::max(len, 1e-12), 0.0,
                  std::max(0.0, len - std::max(1e-3, 1e-4 * len))};
        }
      model.session().study().caster().OccludedBatch(rays, &slice_hidden);
    }
    for (int row = 0; row < slice.height; ++row)
      for (int col = 0; col < slice.width; ++col) {
        const std::size_t o = std::size_t(row) * slice.width + col;
        if (!slice.has_value[o]) continue;
        const double t = hi > lo ? (slice.values[o] - lo) / (hi - lo) : 0.5;
        const Vec3 rgb = ViridisLinear(t);
        Vec3 c = Vec3::Zero();
        c[slice.axis] = slice.coordinate;
        c[ua] = slice.u_min + h * col;
        c[va] = slice.v_max - h * row;
        Vec3 corners[4];
        for (int k = 0; k < 4; ++k) {
          corners[k] = c;
          corners[k][ua] += (k == 1 || k == 2 ? 0.5 : -0.5) * h;
          corners[k][va] += (k >= 2 ? 0.5 : -0.5) * h;
        }
        std::optional<ImVec2> q[4];
        bool ok = true;
        for (int k = 0; k < 4 && ok; ++k) ok = bool(q[k] = P.Point(corners[k]));
        if (ok)
          dl->AddQuadFilled(*q[0], *q[1], *q[2], *q[3],
                            Color(rgb, ov.slice_opacity * (slice_hidden[o] ? 0.33 : 1.0)));
      }
  }

  // The isosurface of the live fields as translucent triangles, back to front, shaded as the CPU
  // renderer shades it (0.35 + 0.65 |n . d|); where the scene hides a triangle (its centre) from
  // the eye it is drawn at a quarter of the opacity. The mesh is extracted again only when the
  // fields or the iso choice change; the order and the hidden flags only when the view does.
  void DrawIso(ImDrawList* dl, const Projector& P) {
    const OverlayOptions& ov = model.display.overlays;
    char key[256];
    std::snprintf(key, sizeof key, "%s %.17g", ov.iso_field.c_str(), ov.iso_value);
    model.session().TryReadFields([&](const Fields& f, std::int64_t v) {  // busy: keep the last one
      if (v == iso_version && key == iso_key) return;
      iso_version = v;
      iso_key = key;
      iso_view_key.clear();
      try {
        iso_mesh = FieldIsosurface(f, ov.iso_field, ov.iso_value);
      } catch (const std::exception&) {
        iso_mesh = TriangleMesh();
      }
    });
    const std::size_t n = iso_mesh.triangles.size();
    if (n == 0) return;
    const RenderView view = model.MainView();
    char vkey[256];
    std::snprintf(vkey, sizeof vkey, "%.17g %.17g %.17g %d %d", view.from.x(), view.from.y(),
                  view.from.z(), view.width, view.height);
    if (vkey != iso_view_key) {
      iso_view_key = vkey;
      std::vector<std::pair<double, int>> depth(n);
      std::vector<Ray> rays(n);
      for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3i& t = iso_mesh.triangles[i];
        const Vec3 c =
            (iso_mesh.vertices[t[0]] + iso_mesh.vertices[t[1]] + iso_mesh.vertices[t[2]]) / 3.0;
        const double d = (c - view.from).norm();
        depth[i] = {-d, int(i)};
        rays[i] =
            Ray{view.from, (c - view.from) / std::max(d, 1e-12), 0.0, std::max(0.0, d - 1e-3)};
      }
      std::sort(depth.begin(), depth.end());  // farthest first
      model.session().study().caster().OccludedBatch(rays, &iso_hidden);
      iso_order.resize(n);
      iso_shade.resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        iso_order[i] = depth[i].second;
        const Eigen::Vector3i& t = iso_mesh.triangles[depth[i].second];
        const Vec3 a = iso_mesh.vertices[t[0]], b = iso_mesh.vertices[t[1]],
                   c = iso_mesh.vertices[t[2]];
        const Vec3 normal = (b - a).cross(c - a).normalized();
        iso_shade[i] = 0.35 + 0.65 * std::abs(normal.dot(rays[depth[i].second].direction));
      }
    }
    // No anti-aliased fringes: adjacent triangles share their edges, and the fringes would triple
    // the vertices (and show the mesh's edges through the translucency).
    const ImDrawListFlags flags = dl->Flags;
    dl->Flags &= ~ImDrawListFlags_AntiAliasedFill;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3i& t = iso_mesh.triangles[iso_order[i]];
      const auto a = P.Point(iso_mesh.vertices[t[0]]), b = P.Point(iso_mesh.vertices[t[1]]),
                 c = P.Point(iso_mesh.vertices[t[2]]);
      if (!a || !b || !c) continue;
      const double alpha = ov.iso_opacity * (iso_hidden[iso_order[i]] ? 0.25 : 1.0);
      dl->AddTriangleFilled(*a, *b, *c, Color(iso_shade[i] * ov.iso_color, alpha));
    }
    dl->Flags = flags;
  }
  std::int64_t iso_version = -2;
  std::string iso_key, iso_view_key;
  TriangleMesh iso_mesh;
  std::vector<int> iso_order;
  std::vector<double> iso_shade;
  std::vector<uint8_t> iso_hidden;

  // Translate handles along world X, Y, Z and rotation rings about them, at the primary camera.
  void DrawGizmo(ImDrawList* dl, const Projector& P) {
    const auto origin = GizmoOrigin();
    if (!origin) return;
    const Vec3 o = *origin;
    const bool rings = !StationPoint();  // a station point only moves
    const double len = GizmoLength();
    const ImU32 axis_col[3] = {IM_COL32(230, 60, 60, 255), IM_COL32(60, 200, 60, 255),
                               IM_COL32(70, 110, 240, 255)};
    for (int k = 0; k < 3; ++k) {
      ImVec2 a, b;
      const bool hot =
          (drag == Drag::kAxis && drag_handle == k) || (drag == Drag::kNone && hover_handle == k);
      if (P.Segment(o, o + len * Vec3::Unit(k), &a, &b))
        dl->AddLine(a, b, axis_col[k], hot ? 4.0f : 2.5f);
      // The ring in the plane normal to axis k.
      if (!rings) continue;
      const Vec3 u = Vec3::Unit((k + 1) % 3), v = Vec3::Unit((k + 2) % 3);
      const bool ring_hot = (drag == Drag::kRing && drag_handle == k) ||
                            (drag == Drag::kNone && hover_handle == k + 3);
      for (int i = 0; i < 48; ++i) {
        const double t0 = 2 * kPi * i / 48, t1 = 2 * kPi * (i + 1) / 48;
        const Vec3 p0 = o + 0.8 * len * (std::cos(t0) * u + std::sin(t0) * v);
        const Vec3 p1 = o + 0.8 * len * (std::cos(t1) * u + std::sin(t1) * v);
        if (P.Segment(p0, p1, &a, &b))
          dl->AddLine(a, b, axis_col[k] & 0xB0FFFFFF, ring_hot ? 3.5f : 1.5f);
      }
    }
  }

  // Which gizmo handle is under the mouse: 0..2 axes, 3..5 rings, -1 none.
  int HandleAt(double x, double y) const {
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

  // The 3D view's handling of the mouse when no panel wants it.
  void Handle3d(bool mouse_free) {
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

  void DragGizmo(double x, double y) {
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

  void Click(double x, double y) {
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

  void Keys() {
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

  // A connected gamepad moves the primary camera (or, with none selected, flies the view).
  void Gamepad() {
    GLFWgamepadstate s;
    if (!glfwJoystickIsGamepad(GLFW_JOYSTICK_1) || !glfwGetGamepadState(GLFW_JOYSTICK_1, &s))
      return;
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

  void Panels() {
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
      if (on)
        ImGui::PushStyleColor(ImGuiCol_Button, ImGui::GetStyleColorVec4(ImGuiCol_ButtonActive));
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

    // Camera's-eye views of up to four selected cameras, exact (CPU), distortion included.
    for (std::size_t i = 0; i < model.selection.size() && i < 4; ++i) {
      const int c = model.selection[i];
      RenderCameraView(c);
      const CameraView& v = camera_views[c];
      ImGui::SetNextWindowPos(
          ImVec2(float(model.width - v.width - 24), float(8 + i * (v.height + 44))),
          ImGuiCond_FirstUseEver);
      ImGui::Begin(("View " + rig.cameras[c].id).c_str(), nullptr,
                   ImGuiWindowFlags_AlwaysAutoResize);
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

  void CameraPanel() {
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

  // A PTZ camera's head (docs/ptz.md, "In the viewer"): pan, tilt and zoom sliders over its ranges,
  // its presets, re-centre, and the traces of the main view; each a script action.
  float trace_seconds = NAN;  // the "all" budget shown (NaN: the head's trace_s)
  void PtzControls(const Camera& cam) {
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
    if (ImGui::SliderFloat("tilt deg", &tilt, float(h.tilt_min_deg), float(h.tilt_max_deg),
                           "%.1f")) {
      a.tilt_deg = tilt;
      Do(a);
    }
    if (h.focal_max > h.focal_min) {
      if (ImGui::SliderFloat("zoom hfov deg", &zoom, hfov(h.focal_min), hfov(h.focal_max),
                             "%.1f")) {
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

  // On/off, colour, resolution, lens model and coefficients, working range: each a script action.
  void LensControls(const Camera& cam) {
    const Intrinsics& k = cam.model.intrinsics();
    bool on = cam.enabled;
    if (ImGui::Checkbox("on", &on))
      Do(Make(on ? Action::Kind::kEnable : Action::Kind::kDisable, {cam.id}));
    ImGui::SameLine();
    float rgb[3] = {float(cam.color.x()), float(cam.color.y()), float(cam.color.z())};
    if (ImGui::ColorEdit3("colour", rgb,
                          ImGuiColorEditFlags_NoInputs | ImGuiColorEditFlags_Float)) {
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
      if (ImGui::DragFloat(kLensCoefficientNames[i], &v, i == 2 || i == 3 ? 0.0001f : 0.001f,
                           -10.0f, 10.0f, "%.4f")) {
        Action a = Make(Action::Kind::kIntrinsics, {cam.id});
        a.coefficients[i] = v;
        a.drag = true;
        Do(a);
      }
    }
    if (k.model == LensModel::kPinhole) ImGui::TextDisabled("no distortion");
  }
  std::string resolution_camera;
  int resolution[2] = {0, 0};
  bool resolution_active = false;

  std::int64_t fields_numbers_version = -2;  // -2: never read
  std::string fields_numbers;
  VoxelLattice fields_lattice;

  void FieldsPanel() {
    ImGui::SetNextWindowPos(ImVec2(266, float(std::max(40, model.height - 230))),
                            ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(250, 195), ImGuiCond_FirstUseEver);
    ImGui::Begin("Fields");
    // The numbers of the fields' latest version, worked out once per version (the median copies
    // and partially sorts every sigma); while an update holds the fields, the last ones stay.
    model.session().TryReadFields([&](const Fields& f, std::int64_t version) {
      if (version == fields_numbers_version) return;
      fields_numbers_version = version;
      fields_lattice = f.lattice;
      fields_numbers.clear();
      const std::vector<double> shares = CoverageAtLeast(f.stats.coverage_histogram);
      for (std::size_t k = 1; k <= shares.size() && k <= 3; ++k) {
        char cell[48];
        std::snprintf(cell, sizeof cell, ">=%zu %.1f%%  ", k, 100.0 * shares[k - 1]);
        fields_numbers += cell;
      }
      const auto p50 = NearestRankPercentile(f.stats.sigma_max_mm, 50);
      if (p50) fields_numbers += "\nsigma_max p50 " + std::to_string(*p50).substr(0, 5) + " mm";
    });
    const VoxelLattice& lattice = fields_lattice;
    const std::string numbers =
        fields_numbers +
        (fields_numbers_version == model.session().rig().version() ? "" : "\n(updating)");
    ImGui::TextUnformatted(fields_numbers_version == -2 ? "evaluating..." : numbers.c_str());
    // With people (time samples): the live fields above are the empty volume's; these are the
    // numbers with the people at every sample, as `pandora analyze` reports them.
    if (const auto time = model.session().TimeNumbers()) {
      const TimeSummary& t = time->first;
      const double worst = t.samples.empty() ? 0.0 : t.samples[t.worst_sample].ge_k;
      ImGui::Text("with people, %zu samples, >=%d:\nalways %.1f%%  worst sample %.1f%%%s",
                  t.samples.size(), t.min_cameras, 100.0 * t.always, 100.0 * worst,
                  time->second == model.session().rig().version() ? "" : " (updating)");
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "The fields above are the static scene's (the volume without the moving objects).\n"
            "These are over the time samples with them: the share of voxels covered by >= %d\n"
            "cameras at every sample where they are free, and in the worst sample.",
            t.min_cameras);
    }
    const char* fields[] = {"", "coverage", "resolution", "sigma_max"};
    const OverlayOptions& ov = model.display.overlays;
    int current = 0;
    for (int i = 1; i < 4; ++i)
      if (ov.slice_field == fields[i]) current = i;
    int axis = ov.slice_axis;
    float at =
        std::isnan(ov.slice_position)
            ? float(lattice.origin[axis] + 0.5 * lattice.voxel_size * (lattice.dims[axis] - 1))
            : float(ov.slice_position);
    bool changed = ImGui::Combo("slice", &current, "off\0coverage\0resolution\0sigma_max\0");
    changed |= ImGui::RadioButton("x", &axis, 0);
    ImGui::SameLine();
    changed |= ImGui::RadioButton("y", &axis, 1);
    ImGui::SameLine();
    changed |= ImGui::RadioButton("z", &axis, 2);
    const float lo = float(lattice.origin[axis]),
                hi = float(lattice.origin[axis] +
                           lattice.voxel_size * std::max(0, lattice.dims[axis] - 1));
    changed |= ImGui::SliderFloat("at m", &at, lo, std::max(hi, lo + 1e-3f), "%.3f");
    if (changed) {
      Action a = Make(Action::Kind::kSlice);
      a.text = fields[current];
      a.flag = a.text.empty();
      a.text2 = axis == 0 ? "x" : axis == 1 ? "y" : "z";
      a.number = at;
      Do(a);
    }
    // The isosurface: field and value.
    int iso_current = 0;
    for (int i = 1; i < 4; ++i)
      if (ov.iso_field == fields[i]) iso_current = i;
    float iso_value = float(ov.iso_value);
    bool iso_changed = ImGui::Combo("iso", &iso_current, "off\0coverage\0resolution\0sigma_max\0");
    iso_changed |= ImGui::DragFloat("iso value", &iso_value, 0.05f, -1e6f, 1e6f, "%.2f");
    if (iso_changed) {
      Action a = Make(Action::Kind::kIso);
      a.text = fields[iso_current];
      a.flag = a.text.empty();
      a.number = iso_value;
      Do(a);
    }
    ImGui::End();
  }

  // The edited rig against the rig as last saved and, optionally, another rig of the scene: the
  // report's headline rows (coverage, resolution, sigma_max percentiles), computed on the button
  // (the saved and other rigs evaluated once and kept), the best of each row in green.
  void ComparePanel() {
    ImGui::SetNextWindowPos(ImVec2(266, 34), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(400, 330), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);
    ImGui::Begin("Compare");
    std::vector<std::string> rigs = {"(none)"};
    for (const Rig& r : model.scene().rigs)
      if (r.name != model.rig().name) rigs.push_back(r.name);
    compare_other = std::clamp(compare_other, 0, int(rigs.size()) - 1);
    if (ImGui::BeginCombo("other rig", rigs[compare_other].c_str())) {
      for (int i = 0; i < int(rigs.size()); ++i)
        if (ImGui::Selectable(rigs[i].c_str(), i == compare_other)) compare_other = i;
      ImGui::EndCombo();
    }
    if (ImGui::Button("Compare with saved")) {
      Action a = Make(Action::Kind::kCompare, {"saved"});
      if (compare_other > 0) a.cameras.push_back(rigs[compare_other]);
      Do(a);
    }
    const std::optional<RigComparison>& cmp = model.comparison;
    if (cmp) {
      if (model.comparison_rig_version != model.session().rig().version()) {
        ImGui::SameLine();
        ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "rig edited since");
      }
      const int n = int(cmp->rigs.size());
      if (ImGui::BeginTable("comparison", n + 1, ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg)) {
        // Short headers: "edited", "saved", the other rig's name.
        ImGui::TableSetupColumn("", ImGuiTableColumnFlags_WidthFixed, 170.0f);
        for (const std::string& r : cmp->rigs) {
          const auto open = r.rfind(" (");
          const std::string head = open != std::string::npos && r.back() == ')'
                                       ? r.substr(open + 2, r.size() - open - 3)
                                       : r;
          ImGui::TableSetupColumn(head.c_str(), ImGuiTableColumnFlags_WidthStretch);
        }
        ImGui::TableHeadersRow();
        ImGui::TableNextRow();
        ImGui::TableSetColumnIndex(0);
        ImGui::TextUnformatted("Cameras on");
        for (int i = 0; i < n; ++i) {
          ImGui::TableSetColumnIndex(i + 1);
          ImGui::Text("%d", cmp->enabled_cameras[i]);
        }
        for (const ComparisonRow& row : cmp->rows) {
          if (std::none_of(row.values.begin(), row.values.end(),
                           [](const std::optional<double>& v) { return v.has_value(); }))
            continue;  // a row no rig has (a field that is not live)
          ImGui::TableNextRow();
          ImGui::TableSetColumnIndex(0);
          ImGui::TextUnformatted(row.label.c_str());
          for (int i = 0; i < n; ++i) {
            ImGui::TableSetColumnIndex(i + 1);
            const std::string text = row.Text(i);
            if (row.best[i])
              ImGui::TextColored(ImVec4(0.4f, 0.95f, 0.45f, 1.0f), "%s", text.c_str());
            else
              ImGui::TextUnformatted(text.c_str());
          }
        }
        ImGui::EndTable();
      }
    } else {
      ImGui::TextDisabled(
          "the edited rig's live fields against the rig as saved\n(evaluated once on the button)");
    }
    ImGui::End();
  }
  int compare_other = 0;

  void SuggestPanel() {
    ImGui::SetNextWindowPos(ImVec2(float(model.width - 290), float(model.height - 290)),
                            ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(280, 250), ImGuiCond_FirstUseEver);
    ImGui::Begin("Suggest");
    const char* objectives[] = {"coverage2",  "coverage3",    "sigma-p90",   "sigma-mean",
                                "resolution", "coverage3-n1", "calibration", "mix"};
    if (model.suggestion) {  // the panel shows what the suggestion on screen was asked for
      for (int i = 0; i < IM_ARRAYSIZE(objectives); ++i)
        if (ObjectiveName(model.suggestion->objective) == objectives[i]) objective = i;
      over_time = model.suggestion_over_time;
    }
    ImGui::Combo("objective", &objective, objectives, IM_ARRAYSIZE(objectives));
    if (std::string(objectives[objective]) == "mix")
      ImGui::DragFloat3("weights c s r", weights, 0.05f, 0.0f, 100.0f, "%.2f");
    // The points the objective is evaluated on, as `pandora suggest`: the study region, named
    // surfaces (--target-surface, with --with-region), or the study's targets over time
    // (--over-time).
    const bool has_targets = model.scene().study.targets.has_value();
    if (!has_targets) over_time = false;
    if (has_targets) ImGui::Checkbox("over time (the study's targets)", &over_time);
    if (!over_time) {
      ImGui::InputText("target surfaces", surfaces, sizeof surfaces);
      if (surfaces[0]) ImGui::Checkbox("and region points", &with_region);
    }
    ImGui::DragFloat("max move m", &max_move, 0.01f, 0.0f, 10.0f, "%.2f");
    ImGui::DragFloat("max turn deg", &max_rotate, 0.5f, 0.0f, 179.0f, "%.1f");
    ImGui::DragInt("points", &points, 10, 50, 20000);
    // Mount of the selected cameras: free, on a rail (a line), on a plane (a wall), or in a box.
    ImGui::Combo("mount", &mount, "free\0rail\0plane\0box\0");
    if (mount == 1 || mount == 2)
      ImGui::DragFloat3(mount == 1 ? "rail direction" : "plane normal", mount_axis, 0.05f);
    if (mount == 3) {
      ImGui::DragFloat3("box min m", mount_box, 0.01f);
      ImGui::DragFloat3("box max m", mount_box + 3, 0.01f);
    }
    // Keep-out boxes (drawn in red in the view): no suggested camera centre inside any of them.
    for (std::size_t i = 0; i < keep_outs.size(); ++i) {
      ImGui::PushID(int(i));
      ImGui::DragFloat3("keep-out min m", keep_outs[i].data(), 0.01f);
      ImGui::DragFloat3("keep-out max m", keep_outs[i].data() + 3, 0.01f);
      const bool remove = ImGui::SmallButton("remove keep-out box");
      ImGui::PopID();
      if (remove) {
        keep_outs.erase(keep_outs.begin() + long(i));
        break;
      }
    }
    if (ImGui::Button("add keep-out box")) {
      // Around the view's target, half a metre each way, floor to 2 m.
      const Vec3 t = model.view.target;
      keep_outs.push_back({float(t.x() - 0.5), float(t.y() - 0.5), 0.0f, float(t.x() + 0.5),
                           float(t.y() + 0.5), 2.0f});
    }
    ImGui::DragFloat("clearance m", &clearance, 0.005f, 0.0f, 2.0f, "%.3f");
    ImGui::Checkbox("zoom", &zoom_on);
    if (zoom_on) ImGui::DragFloat2("hfov range deg", zoom, 0.5f, 1.0f, 179.0f, "%.1f");
    const session::JobStatus s = model.session().jobs().Status("suggest");
    const bool running =
        s.state == session::JobState::kRunning || s.state == session::JobState::kQueued;
    if (model.selection.empty()) {
      ImGui::TextDisabled("select the cameras that may move");
    } else if (running) {
      ImGui::Text("suggesting... %.0f %%", 100 * s.progress);
      ImGui::SameLine();
      // Stops the search where it is (SuggestOptions::cancel); nothing is offered.
      if (ImGui::Button("Cancel")) model.session().jobs().Cancel("suggest");
    } else if (ImGui::Button(("Suggest for " + std::to_string(model.selection.size()) + " cameras")
                                 .c_str())) {
      Action a = Make(Action::Kind::kSuggest, SelectedIds());
      a.text = objectives[objective];
      a.number = max_move;
      a.number2 = max_rotate;
      a.number3 = points;
      a.clearance = clearance;
      if (mount == 1 || mount == 2) {
        a.mount = mount == 1 ? "rail" : "plane";
        a.a = Vec3(mount_axis[0], mount_axis[1], mount_axis[2]);
      } else if (mount == 3) {
        a.mount = "box";
        a.mount_box.min = Vec3(mount_box[0], mount_box[1], mount_box[2]);
        a.mount_box.max = Vec3(mount_box[3], mount_box[4], mount_box[5]);
      }
      for (const auto& k : keep_outs) {
        Aabb b;
        b.min = Vec3(k[0], k[1], k[2]);
        b.max = Vec3(k[3], k[4], k[5]);
        a.keep_out.push_back(b);
      }
      if (zoom_on) {
        a.min_hfov = zoom[0];
        a.max_hfov = zoom[1];
      }
      if (std::string(objectives[objective]) == "mix")
        a.weights = Vec3(weights[0], weights[1], weights[2]);
      a.over_time = over_time;
      if (!over_time) {
        std::string list = surfaces, item;
        for (char ch : list + ",")
          if (ch == ',') {
            if (!item.empty()) a.target_surfaces.push_back(item);
            item.clear();
          } else if (ch != ' ') {
            item += ch;
          }
        a.with_region = with_region && !a.target_surfaces.empty();
      }
      Do(a);
      waiting_for_suggestion = true;
    }
    if (waiting_for_suggestion && !running) {
      waiting_for_suggestion = false;
      Action a = Make(Action::Kind::kWait);
      a.text = "suggest";
      Do(a);
    }
    if (model.suggestion) {
      const Suggestion& g = *model.suggestion;
      ImGui::Separator();
      ImGui::Text("%s: %.4g -> %.4g%s", ObjectiveName(g.objective).c_str(), g.before.objective,
                  g.after.objective, g.improved ? "" : " (no improvement)");
      ImGui::TextDisabled("over %s", model.suggestion_targets.c_str());
      if (!g.improved) {  // as `pandora accept`: nothing to accept
        if (ImGui::Button("Reject")) Do(Make(Action::Kind::kReject));
        ImGui::End();
        return;
      }
      for (const CameraChange& ch : g.cameras) {
        ImGui::PushID(ch.index);
        ImGui::Text("%s: %.3f m, %.1f deg", ch.id.c_str(), ch.move_m, ch.rotate_deg);
        ImGui::SameLine();
        if (ImGui::SmallButton("accept")) {
          Do(Make(Action::Kind::kAccept, {ch.id}));
          ImGui::PopID();
          break;
        }
        ImGui::PopID();
      }
      if (model.suggestion && ImGui::Button("Accept all")) Do(Make(Action::Kind::kAccept));
      ImGui::SameLine();
      if (model.suggestion && ImGui::Button("Reject")) Do(Make(Action::Kind::kReject));
    }
    ImGui::End();
  }
  bool waiting_for_suggestion = false;
  int mount = 0;
  float mount_axis[3] = {1, 0, 0}, mount_box[6] = {-1, -1, 0, 1, 1, 3};
  std::vector<std::array<float, 6>> keep_outs;
  bool zoom_on = false;
  float clearance = 0.1f, zoom[2] = {30, 60};
  float weights[3] = {1, 1, 1};
  bool over_time = false, with_region = false;
  char surfaces[256] = "";

  void DisplayPanel() {
    ImGui::SetNextWindowPos(ImVec2(266, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(230, 130), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);
    ImGui::Begin("Display");
    int pattern = model.display.pattern == Pattern::kGrid ? 1 : 0;
    bool changed = ImGui::Combo("light", &pattern, "uniform\0grid\0");
    int grid = model.display.grid_pixels;
    changed |= ImGui::DragInt("grid px", &grid, 1, 1, 1000);
    // The paper's display modes: material colours, black, hidden-line edges, contours.
    int surface = int(model.display.surface);
    changed |= ImGui::Combo("surfaces", &surface, "material\0black\0hidden-line\0contours\0");
    bool automatic = std::isnan(model.display.brightness);
    float brightness = automatic ? float(DefaultBrightness(model.rig().enabled_count()))
                                 : float(model.display.brightness);
    changed |= ImGui::Checkbox("auto brightness", &automatic);
    if (!automatic)
      changed |= ImGui::DragFloat("brightness", &brightness, 0.01f, 0.01f, 10.0f, "%.2f");
    if (ImGui::Combo("shadow map", &map_index,
                     "512\0"
                     "1024\0"
                     "2048\0"
                     "4096\0"))
      shadow_map_size = 512 << map_index;
    if (changed) {
      Action a = Make(Action::Kind::kLight);
      a.text = PatternName(pattern ? Pattern::kGrid : Pattern::kUniform);
      a.number = grid;
      a.number2 = automatic ? NAN : brightness;
      a.text2 = SurfaceName(static_cast<Surface>(std::clamp(surface, 0, 3)));
      Do(a);
    }
    ImGui::End();
  }
  int map_index = 2;

  void Draw() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.02f, 0.02f, 0.03f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  }

  void FeedImGui() {
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

  bool OneFrame() {
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
    glfwGetWindowSize(window, &w, &h);
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
    bg->AddImage(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(main_texture)), ImVec2(0, 0),
                 ImVec2(float(model.width), float(model.height)));
    DrawOverlays(bg);
    Panels();
    Draw();
    return !glfwWindowShouldClose(window);
  }
};

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
  glfwSetErrorCallback(OnGlfwError);
  if (!glfwInit())
    throw std::runtime_error("pandora view: no display (" + g_glfw_error +
                             "); on a machine without one run under `xvfb-run -a`");
  glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  model.width = options.width;
  model.height = options.height;
  m.window = glfwCreateWindow(options.width, options.height,
                              ("Pandora: " + model.scene().path).c_str(), nullptr, nullptr);
  if (!m.window) {
    glfwTerminate();
    throw std::runtime_error("pandora view: no OpenGL 3.3 core context (" + g_glfw_error +
                             "); install Mesa (libgl1-mesa-dri) or a GPU driver");
  }
  glfwMakeContextCurrent(m.window);
  glfwSwapInterval(1);
  g_app = &m;
  glfwSetCursorPosCallback(m.window, OnCursor);
  glfwSetMouseButtonCallback(m.window, OnButton);
  glfwSetScrollCallback(m.window, OnScroll);
  glfwSetKeyCallback(m.window, OnKey);
  glfwSetCharCallback(m.window, OnChar);
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
  m.gl = std::make_unique<GlRenderer>(model.scene(), &model.session().study().prepared());
  m.shadow_map_size = options.shadow_map_size;
  m.map_index = options.shadow_map_size >= 4096   ? 3
                : options.shadow_map_size >= 2048 ? 2
                : options.shadow_map_size >= 1024 ? 1
                                                  : 0;
}

ViewerApp::~ViewerApp() {
  Impl& m = *impl_;
  glfwMakeContextCurrent(m.window);
  m.gl.reset();
  if (m.main_texture) glDeleteTextures(1, &m.main_texture);
  for (auto& [c, v] : m.camera_views)
    if (v.texture) glDeleteTextures(1, &v.texture);
  for (auto& [name, v] : m.station_views)
    if (v.texture) glDeleteTextures(1, &v.texture);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui::DestroyContext(m.imgui);
  glfwDestroyWindow(m.window);
  glfwTerminate();
  g_app = nullptr;
}

bool ViewerApp::Frame() {
  glfwPollEvents();
  const bool open = impl_->OneFrame();
  glfwSwapBuffers(impl_->window);
  return open;
}

void ViewerApp::SetMotionScale(double scale, double target_hz) {
  impl_->options.motion_scale = scale;
  impl_->options.target_hz = target_hz;
  impl_->motion_now = scale;
  impl_->main_key.clear();  // draw the next frame anew
}

double ViewerApp::MotionScaleNow() const { return impl_->motion_now; }

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
  glfwSwapBuffers(m.window);
  m.OneFrame();
  m.full_now = false;
  int fw = 0, fh = 0;
  glfwGetFramebufferSize(m.window, &fw, &fh);
  std::vector<unsigned char> pixels(std::size_t(fw) * fh * 4);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  glfwSwapBuffers(m.window);
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
