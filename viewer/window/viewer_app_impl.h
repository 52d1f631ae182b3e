#pragma once
/// \file viewer_app_impl.h
/// The window's state and steps (ViewerApp::Impl), private to viewer/window: viewer_app.cpp holds
/// the frame, the input and the 3D handlers; each panel and each drawn structure has its own file
/// (camera_panel.cpp, fields_panel.cpp, compare_panel.cpp, suggest_panel.cpp, display_panel.cpp,
/// overlays.cpp), as Polyscope gives each structure its own file.

#include <epoxy/gl.h>

#include "viewer/window/viewer_app.h"
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

inline unsigned char ToSrgb8(double linear) {
  return static_cast<unsigned char>(std::lround(255.0 * SrgbFromLinear(linear)));
}

// Linear RGB (3 floats per pixel) to 8-bit sRGB RGBA, opaque.
inline std::vector<unsigned char> ToRgba8(const std::vector<float>& rgb) {
  std::vector<unsigned char> rgba(rgb.size() / 3 * 4);
  for (std::size_t i = 0; i < rgb.size() / 3; ++i) {
    for (int k = 0; k < 3; ++k) rgba[4 * i + k] = ToSrgb8(rgb[3 * i + k]);
    rgba[4 * i + 3] = 255;
  }
  return rgba;
}

inline ImU32 Color(const Vec3& rgb, double alpha = 1.0) {
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

inline double SegmentDistance(const ImVec2& p, const ImVec2& a, const ImVec2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / len2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  const double ex = a.x + t * dx - p.x, ey = a.y + t * dy - p.y;
  return std::sqrt(ex * ex + ey * ey);
}

// A camera's frustum outline: rays through its image border (distortion included), `length` metres.
inline std::vector<Vec3> FrustumBorder(const Camera& cam, double length) {
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

struct ViewerApp::Impl {
  ViewerModel& model;
  AppOptions options;
  GLFWwindow* window = nullptr;  // null when headless
  // Headless (AppOptions::gl resolved to EGL for a hidden window): the context, and the offscreen
  // framebuffer that stands in for the window's (RGBA8, width x height).
  std::unique_ptr<GlContext> headless;
  GLuint frame_fbo = 0, frame_color = 0;
  // The window's framebuffer and its size in pixels.
  GLuint FrameFramebuffer() const { return frame_fbo; }
  void FramebufferSize(int* w, int* h) const {
    if (window) {
      glfwGetFramebufferSize(window, w, h);
    } else {
      *w = options.width;
      *h = options.height;
    }
  }
  std::unique_ptr<GlRenderer> gl;
  GlRenderOptions gl_options;
  GLuint main_texture = 0;   // the main view drawn on the CPU (PTZ "all"), uploaded
  GLuint shown_texture = 0;  // what the window shows: main_texture or the GPU renderer's own
  std::string main_key;      // what the shown texture shows
  bool main_full = false;    // ... at full resolution
  bool full_now = false;     // a screenshot: draw in full whatever moved just before
  std::chrono::steady_clock::time_point last_change, last_rig_change;
  std::int64_t main_rig_version = -1;
  double motion_now = 0.5;  // the scale of the next moving frame (adapted to AppOptions::target_hz)
  double overhead_seconds = 0;  // the frame's time besides the main picture (running mean)
  double frame_gl_seconds = 0;  // this frame's main picture, 0 when it was kept
  static constexpr double kMinMotionScale = 0.2;
  static constexpr double kTargetHeadroom = 1.15;  // moving frames aim at 1.15 x target_hz
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
    std::int64_t version = -1;  // station views: what the texture shows
    std::string key;            // camera views: what the texture shows
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

  void Do(const Action& a);
  Action Make(Action::Kind kind, std::vector<std::string> cameras = {}) const;
  int Primary() const { return model.selection.empty() ? -1 : model.selection.front(); }
  std::vector<std::string> SelectedIds() const;
  // The selection after a click on camera `id`: that camera alone, or with ctrl the selection with
  // it added (or removed when it was in).
  std::vector<std::string> ToggledSelection(const std::string& id) const;
  std::optional<Ray> MouseRay(double x, double y) const;
  // The picked station point, when the station still exists.
  std::optional<Vec3> StationPoint() const;
  // Where the gizmo sits: the picked station point, else the primary camera's centre.
  std::optional<Vec3> GizmoOrigin() const;
  double GizmoLength() const;

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

  void UploadAllTrace();

  void RenderMain();

  // Uploads an 8-bit RGBA image into *texture (made at first use), counted in upload_bytes.
  void Upload(GLuint* texture, int w, int h, const std::vector<unsigned char>& rgba);
  // Bytes this frame moved between CPU and GPU for pictures (LastFrameTransfer).
  std::int64_t readback_bytes = 0, upload_bytes = 0;
  double map_cpu_seconds = 0;  // CPU time preparing the GPU renderer's maps this frame
  FrameTransfer last_transfer;

  // The display settings for the small exact views (a camera's, a station's display): the light
  // and surfaces as in the main view, without the slice, isosurface, key or float layers.
  RenderOptions InsetOptions() const;

  void RenderCameraView(int c);

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
  void Line(const Projector& P, const Vec3& a, const Vec3& b, ImU32 col, float width);
  void Dot(const Projector& P, const Vec3& p, ImU32 col, float radius);
  void FlushOverlayPieces(ImDrawList* dl);

  // Camera bodies, frusta, the selection, the suggestion's ghosts, the slice, the gizmo.
  void DrawOverlays(ImDrawList* dl);

  // Viewing stations: each display textured with the scene as its viewer's eye sees it through the
  // display (exact CPU renderer, the display's off-axis camera), the eye's lines to the display's
  // corners, and the tracker's range as a red wireframe.
  void DrawStations(ImDrawList* dl, const Projector& P);

  void DrawSlice(ImDrawList* dl, const Projector& P);

  // The isosurface of the live fields as translucent triangles, back to front, shaded as the CPU
  // renderer shades it (0.35 + 0.65 |n . d|); where the scene hides a triangle (its centre) from
  // the eye it is drawn at a quarter of the opacity. The mesh is extracted again only when the
  // fields or the iso choice change; the order and the hidden flags only when the view does.
  void DrawIso(ImDrawList* dl, const Projector& P);
  std::int64_t iso_version = -2;
  std::string iso_key, iso_view_key;
  TriangleMesh iso_mesh;
  std::vector<int> iso_order;
  std::vector<double> iso_shade;
  std::vector<uint8_t> iso_hidden;

  // Translate handles along world X, Y, Z and rotation rings about them, at the primary camera.
  void DrawGizmo(ImDrawList* dl, const Projector& P);

  // Which gizmo handle is under the mouse: 0..2 axes, 3..5 rings, -1 none.
  int HandleAt(double x, double y) const;

  // The 3D view's handling of the mouse when no panel wants it.
  void Handle3d(bool mouse_free);

  void DragGizmo(double x, double y);

  void Click(double x, double y);

  void Keys();

  // A connected gamepad moves the primary camera (or, with none selected, flies the view).
  void Gamepad();

  void Panels();

  void CameraPanel();

  // A PTZ camera's head (docs/ptz.md, "In the viewer"): pan, tilt and zoom sliders over its ranges,
  // its presets, re-centre, and the traces of the main view; each a script action.
  float trace_seconds = NAN;  // the "all" budget shown (NaN: the head's trace_s)
  void PtzControls(const Camera& cam);

  // On/off, colour, resolution, lens model and coefficients, working range: each a script action.
  void LensControls(const Camera& cam);
  std::string resolution_camera;
  int resolution[2] = {0, 0};
  bool resolution_active = false;

  std::int64_t fields_numbers_version = -2;  // -2: never read
  std::string fields_numbers;
  VoxelLattice fields_lattice;

  void FieldsPanel();

  // The edited rig against the rig as last saved and, optionally, another rig of the scene: the
  // report's headline rows (coverage, resolution, sigma_max percentiles), computed on the button
  // (the saved and other rigs evaluated once and kept), the best of each row in green.
  void ComparePanel();
  int compare_other = 0;

  void SuggestPanel();
  bool waiting_for_suggestion = false;
  int mount = 0;
  float mount_axis[3] = {1, 0, 0}, mount_box[6] = {-1, -1, 0, 1, 1, 3};
  std::vector<std::array<float, 6>> keep_outs;
  bool zoom_on = false;
  float clearance = 0.1f, zoom[2] = {30, 60};
  float weights[3] = {1, 1, 1};
  bool over_time = false, with_region = false;
  char surfaces[256] = "";

  void DisplayPanel();
  int map_index = 2;

  void Draw();
  // Opening: a hidden window's headless EGL context and framebuffer, or a GLFW window; then Dear
  // ImGui and its OpenGL 3 backend (no platform backend: FeedImGui gives it our input).
  void OpenHeadless();
  void OpenWindow();
  void InitImGui();
  // The drawn frame to the screen (a swap), or finished (headless).
  void Present() {
    if (window)
      glfwSwapBuffers(window);
    else
      glFlush();
  }

  void FeedImGui();

  bool OneFrame();
};

}  // namespace pandora::viewer
