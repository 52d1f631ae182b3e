// A hidden GLFW window holding a GL 3.3 core context (viewer/gl/context.h).
#include "viewer/gl/context.h"

#include <epoxy/gl.h>
// GLFW after epoxy: epoxy provides the GL declarations, GLFW must not include its own.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <mutex>
#include <stdexcept>

namespace pandora {
namespace {

std::mutex g_mutex;
int g_contexts = 0;
std::string g_last_error;

void OnGlfwError(int code, const char* description) {
  g_last_error = std::string(description) + " (GLFW error " + std::to_string(code) + ")";
}

}  // namespace

struct GlContext::Impl {
  GLFWwindow* window = nullptr;
};

GlContext::GlContext() : impl_(std::make_unique<Impl>()) {
  std::lock_guard<std::mutex> lock(g_mutex);
  glfwSetErrorCallback(OnGlfwError);
  if (g_contexts == 0 && !glfwInit())
    throw std::runtime_error("GlContext: GLFW could not start: " + g_last_error +
                             "; without a display run under `xvfb-run -a` (Debian package xvfb)");
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  impl_->window = glfwCreateWindow(16, 16, "pandora", nullptr, nullptr);
  if (!impl_->window) {
    if (g_contexts == 0) glfwTerminate();
    throw std::runtime_error("GlContext: no OpenGL 3.3 core context: " + g_last_error +
                             "; install Mesa (libgl1-mesa-dri) or a GPU driver");
  }
  ++g_contexts;
  glfwMakeContextCurrent(impl_->window);
}

GlContext::~GlContext() {
  std::lock_guard<std::mutex> lock(g_mutex);
  glfwDestroyWindow(impl_->window);
  if (--g_contexts == 0) glfwTerminate();
}

void GlContext::MakeCurrent() { glfwMakeContextCurrent(impl_->window); }

std::string GlContext::Description() const {
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  return std::string(renderer ? renderer : "?") + ", " + (version ? version : "?");
}

}  // namespace pandora
