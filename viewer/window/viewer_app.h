#pragma once
/// \file viewer_app.h
/// The window of `pandora view`: GLFW + OpenGL 3.3 core + Dear ImGui over a ViewerModel
/// (viewer/core/model.h). It draws the model (the GPU projective light of viewer/gl/renderer.h,
/// camera bodies and frusta, the gizmo, the slice, the suggestion's ghosts, the panels) and turns
/// mouse, keyboard and gamepad input into the model's actions; scripted input goes through the same
/// handlers. Light header: no GL, GLFW or ImGui in it.

#include <cstdint>
#include <memory>
#include <string>

#include "viewer/core/model.h"
#include "viewer/gl/context.h"

namespace pandora::viewer {

struct AppOptions {
  int width = 1280, height = 720;  ///< Window size (the main view fills it).
  bool visible = true;             ///< false: a hidden window (scripts, tests).
  /// A hidden window's GL: kAuto is PANDORA_GL, else GLFW with a display and headless EGL
  /// without one (viewer/gl/context.h); headless, the window is an offscreen framebuffer of
  /// width x height that screenshots read. A visible window is always GLFW's.
  GlBackend gl = GlBackend::kAuto;
  int shadow_map_size = 2048;
  /// Frame times in the status bar (off in scripts, whose screenshots are compared with
  /// references).
  bool show_timing = true;
  /// While the view or the rig changes (and for 0.3 s after), the main view is drawn at this
  /// fraction of the window's resolution and with shadow maps of at most 1024 texels, then again
  /// in full once idle: interaction stays responsive on software GL (docs/viewer.md, "Frame rate").
  /// 1: always full. With target_hz, where moving frames start: each moving frame's scale is then
  /// adapted (0.2 .. 1) so that frames take about 1 / (1.15 target_hz): a margin above the target.
  double motion_scale = 0.5;
  /// The frame rate the reduced frames aim at while moving (0: keep motion_scale).
  double target_hz = 30;
};

/// What a frame of the window moved between CPU and GPU for its pictures, and the CPU time it
/// spent preparing shadow maps.
struct FrameTransfer {
  std::int64_t readback_bytes = 0;  ///< GPU -> CPU
  std::int64_t upload_bytes = 0;    ///< CPU -> GPU
  double map_cpu_seconds = 0;       ///< the maps' depth ranges (GlFrameStats::map_cpu_seconds)
};

class ViewerApp : public Frontend {
 public:
  /// Opens the window and its GL context. Throws std::runtime_error naming the cause (no display
  /// for a visible window: run under `xvfb-run -a`; no GL 3.3 core; no EGL device headless).
  ViewerApp(ViewerModel& model, AppOptions options);
  ~ViewerApp() override;

  /// One frame: input, panels, drawing, swap. False once the window was asked to close.
  bool Frame();
  /// Frames until the window closes.
  void Loop();
  /// AppOptions::motion_scale and target_hz from now on (the frame-rate bench measures both in one
  /// window: a second window would reconnect to the X server while it resets after the first).
  void SetMotionScale(double scale, double target_hz = 0);
  /// The scale the next moving frame is drawn at (adapted when target_hz is set).
  double MotionScaleNow() const;
  /// Picture bytes the last frame read back from the GPU and uploaded to it: 0 and 0 while the
  /// GPU renderer draws the main view (it stays on the GPU); the camera's-eye insets, the PTZ
  /// "all" view and screenshots are the exact CPU renderer's, uploaded.
  FrameTransfer LastFrameTransfer() const;
  /// The GL the window draws with: GL_RENDERER, GL_VERSION and "[GLFW window]" or, headless, the
  /// EGL device ("[EGL device 0 of 1]"), for benchmark tables.
  std::string GlDescription() const;

  // Frontend: the window's own picture (after a frame is drawn), or a camera's exact view.
  void Screenshot(const ViewerModel& model, const std::string& path, int camera) override;
  void Input(ViewerModel& model, const Action& action) override;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace pandora::viewer
