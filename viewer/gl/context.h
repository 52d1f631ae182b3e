#pragma once
/// \file context.h
/// An OpenGL 3.3 core context without a visible window: a hidden GLFW window whose context the
/// GPU renderer (viewer/gl/renderer.h) draws into offscreen framebuffers. Needs an X display; in
/// tests and CI that is Xvfb (`xvfb-run -a`) with Mesa's llvmpipe (software GL 4.5). Light header:
/// no GL or GLFW in it.

#include <memory>
#include <string>

namespace pandora {

/// Owns a hidden GLFW window with a GL 3.3 core (forward-compatible) context and makes it current
/// on the constructing thread. One at a time per process is what the tests need; GLFW is
/// initialised with the first and terminated with the last.
class GlContext {
 public:
  /// Throws std::runtime_error naming the cause and what to do (no display: run under
  /// `xvfb-run -a`; no GL 3.3 core: install libgl1-mesa-dri) when the context cannot be created.
  GlContext();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Makes the context current on the calling thread.
  void MakeCurrent();
  /// GL_RENDERER and GL_VERSION, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), 4.5 (Core Profile) Mesa
  /// 22.3.6", for logs and benchmark tables.
  std::string Description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pandora
