// A GL 3.3 core context without a visible window: headless EGL or a hidden GLFW window
// (viewer/gl/context.h).
#include "viewer/gl/context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>
// GLFW after epoxy: epoxy provides the GL declarations, GLFW must not include its own.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace pandora {
namespace {

std::mutex g_mutex;
int g_glfw_contexts = 0;
std::map<EGLDisplay, int> g_egl_displays;  // contexts per initialised display
std::string g_last_error;

void OnGlfwError(int code, const char* description) {
  g_last_error = std::string(description) + " (GLFW error " + std::to_string(code) + ")";
}

bool HasExtension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

std::string EglErrorName(EGLint code) {
  switch (code) {
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
      return "EGL_BAD_SURFACE";
    default:
      return "EGL error " + std::to_string(code);
  }
}

}  // namespace

const char* GlBackendName(GlBackend backend) {
  switch (backend) {
    case GlBackend::kGlfw:
      return "glfw";
    case GlBackend::kEgl:
      return "egl";
    case GlBackend::kAuto:
      break;
  }
  return "auto";
}

bool ParseGlBackend(const std::string& name, GlBackend* out) {
  for (GlBackend b : {GlBackend::kAuto, GlBackend::kGlfw, GlBackend::kEgl})
    if (name == GlBackendName(b)) {
      *out = b;
      return true;
    }
  return false;
}

GlBackend ResolveGlBackend(GlBackend requested) {
  if (requested != GlBackend::kAuto) return requested;
  if (const char* env = std::getenv("PANDORA_GL"); env && *env) {
    GlBackend b;
    if (!ParseGlBackend(env, &b))
      throw std::invalid_argument(std::string("PANDORA_GL: '") + env +
                                  "' is not one of egl, glfw, auto");
    if (b != GlBackend::kAuto) return b;
  }
  const auto set = [](const char* name) {
    const char* v = std::getenv(name);
    return v && *v;
  };
  return set("DISPLAY") || set("WAYLAND_DISPLAY") ? GlBackend::kGlfw : GlBackend::kEgl;
}

struct GlContext::Impl {
  GlBackend backend = GlBackend::kGlfw;
  GLFWwindow* window = nullptr;
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;
  std::string where;  // which EGL display, for Description()

  void CreateGlfw();
  void CreateEgl();
  // A GL 3.3 core context on an initialised `display`; false (with the reason in *why) if none.
  bool ContextOn(EGLDisplay candidate, std::string* why);
  void ReleaseEglDisplay(EGLDisplay d);
};

void GlContext::Impl::CreateGlfw() {
  glfwSetErrorCallback(OnGlfwError);
  if (g_glfw_contexts == 0 && !glfwInit())
    throw std::runtime_error("GlContext (glfw): GLFW could not start: " + g_last_error +
                             "; without a display run under `xvfb-run -a` (Debian package xvfb) "
                             "or use the headless backend, PANDORA_GL=egl");
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window = glfwCreateWindow(16, 16, "pandora", nullptr, nullptr);
  if (!window) {
    if (g_glfw_contexts == 0) glfwTerminate();
    throw std::runtime_error("GlContext (glfw): no OpenGL 3.3 core context: " + g_last_error +
                             "; install Mesa (libgl1-mesa-dri) or a GPU driver");
  }
  ++g_glfw_contexts;
  glfwMakeContextCurrent(window);
}

void GlContext::Impl::ReleaseEglDisplay(EGLDisplay d) {
  const auto it = g_egl_displays.find(d);
  if (it == g_egl_displays.end()) return;
  if (--it->second <= 0) {
    eglTerminate(d);
    g_egl_displays.erase(it);
  }
}

bool GlContext::Impl::ContextOn(EGLDisplay candidate, std::string* why) {
  if (candidate == EGL_NO_DISPLAY) {
    *why = "no display (" + EglErrorName(eglGetError()) + ")";
    return false;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(candidate, &major, &minor)) {
    *why = "eglInitialize: " + EglErrorName(eglGetError());
    return false;
  }
  ++g_egl_displays[candidate];
  const char* extensions = eglQueryString(candidate, EGL_EXTENSIONS);
  if (!eglBindAPI(EGL_OPENGL_API)) {
    *why = "no desktop OpenGL (eglBindAPI: " + EglErrorName(eglGetError()) + ")";
    ReleaseEglDisplay(candidate);
    return false;
  }
  const EGLint config_attributes[] = {EGL_SURFACE_TYPE,
                                      EGL_PBUFFER_BIT,
                                      EGL_RENDERABLE_TYPE,
                                      EGL_OPENGL_BIT,
                                      EGL_RED_SIZE,
                                      8,
                                      EGL_GREEN_SIZE,
                                      8,
                                      EGL_BLUE_SIZE,
                                      8,
                                      EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  if (!eglChooseConfig(candidate, config_attributes, &config, 1, &configs)) configs = 0;
  const bool no_config = HasExtension(extensions, "EGL_KHR_no_config_context");
  if (configs < 1 && !no_config) {
    *why = "no EGL config for an OpenGL pbuffer";
    ReleaseEglDisplay(candidate);
    return false;
  }
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                       3,
                                       EGL_CONTEXT_MINOR_VERSION,
                                       3,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                       EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_CONTEXT_OPENGL_FORWARD_COMPATIBLE,
                                       EGL_TRUE,
                                       EGL_NONE};
  const EGLContext made = eglCreateContext(candidate, configs > 0 ? config : EGL_NO_CONFIG_KHR,
                                           EGL_NO_CONTEXT, context_attributes);
  if (made == EGL_NO_CONTEXT) {
    *why = "no OpenGL 3.3 core context (" + EglErrorName(eglGetError()) + ")";
    ReleaseEglDisplay(candidate);
    return false;
  }
  // The renderer draws into its own framebuffers: no surface where the display allows it, else
  // a 16x16 pbuffer to make the context current with.
  EGLSurface made_surface = EGL_NO_SURFACE;
  if (!HasExtension(extensions, "EGL_KHR_surfaceless_context") && configs > 0) {
    const EGLint pbuffer[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
    made_surface = eglCreatePbufferSurface(candidate, config, pbuffer);
  }
  if (!eglMakeCurrent(candidate, made_surface, made_surface, made)) {
    *why = "eglMakeCurrent: " + EglErrorName(eglGetError());
    if (made_surface != EGL_NO_SURFACE) eglDestroySurface(candidate, made_surface);
    eglDestroyContext(candidate, made);
    ReleaseEglDisplay(candidate);
    return false;
  }
  display = candidate;
  context = made;
  surface = made_surface;
  return true;
}

void GlContext::Impl::CreateEgl() {
  std::string reasons;
  const auto note = [&](const std::string& what, const std::string& why) {
    reasons += (reasons.empty() ? "" : "; ") + what + ": " + why;
  };
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  // Devices: hardware ones first (a GPU server lists its driver's and Mesa's software device),
  // or only PANDORA_EGL_DEVICE.
  std::vector<EGLDeviceEXT> devices;
  if (HasExtension(client, "EGL_EXT_device_enumeration") &&
      HasExtension(client, "EGL_EXT_platform_device")) {
    EGLint count = 0;
    if (eglQueryDevicesEXT(0, nullptr, &count) && count > 0) {
      devices.resize(std::size_t(count));
      if (!eglQueryDevicesEXT(count, devices.data(), &count)) count = 0;
      devices.resize(std::size_t(count));
    }
  }
  std::vector<int> order;
  const char* only = std::getenv("PANDORA_EGL_DEVICE");
  if (only && *only) {
    char* end = nullptr;
    const long k = std::strtol(only, &end, 10);
    if (*end != '\0' || k < 0 || k >= long(devices.size()))
      throw std::runtime_error("GlContext (egl): PANDORA_EGL_DEVICE=" + std::string(only) +
                               " is not one of the " + std::to_string(devices.size()) +
                               " EGL devices");
    order.push_back(int(k));
  } else {
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t k = 0; k < devices.size(); ++k) {
        const bool software = HasExtension(eglQueryDeviceStringEXT(devices[k], EGL_EXTENSIONS),
                                           "EGL_MESA_device_software");
        if (software == (pass == 1)) order.push_back(int(k));
      }
  }
  for (int k : order) {
    std::string why;
    if (ContextOn(
            eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[std::size_t(k)], nullptr),
            &why)) {
      where = "EGL device " + std::to_string(k) + " of " + std::to_string(devices.size());
      return;
    }
    note("device " + std::to_string(k), why);
  }
  if (!(only && *only) && HasExtension(client, "EGL_MESA_platform_surfaceless")) {
    std::string why;
    if (ContextOn(
            eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
            &why)) {
      where = "EGL surfaceless platform";
      return;
    }
    note("surfaceless platform", why);
  }
  if (reasons.empty()) reasons = client ? "no EGL device" : "no EGL library (libEGL.so.1)";
  throw std::runtime_error("GlContext (egl): no OpenGL 3.3 core context: " + reasons +
                           "; install libegl1 and libegl-mesa0 (software) or a GPU driver, or "
                           "use PANDORA_GL=glfw with a display");
}

GlContext::GlContext(GlBackend backend) : impl_(std::make_unique<Impl>()) {
  impl_->backend = ResolveGlBackend(backend);
  std::lock_guard<std::mutex> lock(g_mutex);
  if (impl_->backend == GlBackend::kEgl)
    impl_->CreateEgl();
  else
    impl_->CreateGlfw();
}

GlContext::~GlContext() {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (impl_->backend == GlBackend::kEgl) {
    eglMakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (impl_->surface != EGL_NO_SURFACE) eglDestroySurface(impl_->display, impl_->surface);
    eglDestroyContext(impl_->display, impl_->context);
    impl_->ReleaseEglDisplay(impl_->display);
    return;
  }
  glfwDestroyWindow(impl_->window);
  if (--g_glfw_contexts == 0) glfwTerminate();
}

void GlContext::MakeCurrent() {
  if (impl_->backend == GlBackend::kEgl)
    eglMakeCurrent(impl_->display, impl_->surface, impl_->surface, impl_->context);
  else
    glfwMakeContextCurrent(impl_->window);
}

GlBackend GlContext::backend() const { return impl_->backend; }

int GlContext::Version() const {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  return 10 * major + minor;
}

std::string GlContext::Description() const {
  const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const std::string where =
      impl_->backend == GlBackend::kEgl ? impl_->where : std::string("GLFW hidden window");
  return std::string(renderer ? renderer : "?") + ", " + (version ? version : "?") + " [" + where +
         "]";
}

}  // namespace pandora
