#pragma once
/// \file context.h
/// An OpenGL 3.3 core context without a visible window, which the GPU renderer
/// (viewer/gl/renderer.h) draws into offscreen framebuffers. Two backends:
/// - EGL (headless): a context on an EGL device (EGL_EXT_platform_device: a GPU server's driver,
///   or Mesa's software device), with no surface; no X display needed. Polyscope's openGL3_egl.
/// - GLFW: a hidden GLFW window's context; needs an X display (in tests and CI Xvfb).
/// Chosen by PANDORA_GL (`egl`, `glfw`, `auto`) or the caller; `auto` is GLFW where a display is
/// set (DISPLAY or WAYLAND_DISPLAY) and EGL elsewhere. Light header: no GL, EGL or GLFW in it.

#include <memory>
#include <string>

namespace pandora {

enum class GlBackend {
  kAuto,  ///< PANDORA_GL if set, else GLFW with a display and EGL without
  kGlfw,
  kEgl,
};

/// "auto", "glfw" or "egl".
const char* GlBackendName(GlBackend backend);
/// Parses a backend name; returns false (out untouched) for anything else.
bool ParseGlBackend(const std::string& name, GlBackend* out);
/// What kAuto resolves to here: PANDORA_GL when set (an unknown value throws
/// std::invalid_argument naming it), else kGlfw when DISPLAY or WAYLAND_DISPLAY is set, else kEgl.
GlBackend ResolveGlBackend(GlBackend requested);

/// Owns a GL 3.3 core (forward-compatible) context and makes it current on the constructing
/// thread. One at a time per process is what the tests need; GLFW is initialised with the first
/// GLFW context and terminated with the last, an EGL display likewise.
class GlContext {
 public:
  /// Throws std::runtime_error naming the backend, the cause and what to do (GLFW without a
  /// display: run under `xvfb-run -a` or use PANDORA_GL=egl; EGL without a device: install
  /// libegl-mesa0 or a GPU driver; no GL 3.3 core: install libgl1-mesa-dri) when the context
  /// cannot be created.
  explicit GlContext(GlBackend backend = GlBackend::kAuto);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Makes the context current on the calling thread.
  void MakeCurrent();
  /// The backend in use (never kAuto).
  GlBackend backend() const;
  /// The context's GL version as 10 * major + minor (33 for 3.3), from GL_MAJOR/MINOR_VERSION.
  int Version() const;
  /// GL_RENDERER and GL_VERSION with the backend, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), 4.5
  /// (Core Profile) Mesa 22.3.6 [EGL device 0 of 1]", for logs and benchmark tables.
  std::string Description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pandora
