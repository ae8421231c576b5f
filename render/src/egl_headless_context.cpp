// Headless EGL: picks a display that needs no window system (Mesa's surfaceless platform
// or an EGL device), creates an OpenGL 3.3 core context and makes it current with no
// surface at all (EGL_KHR_surfaceless_context); the Renderer draws into an FBO.
#include "hysim/render/egl_headless_context.hpp"

#include <epoxy/gl.h>  // before any other GL header; EGL headers do not pull GL in
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <map>
#include <mutex>
#include <vector>

namespace hysim::render {
namespace {

const char* eglErrorName(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

std::string lastEglError() { return eglErrorName(eglGetError()); }

// Whole-word search in a space-separated extension string.
bool hasExtension(const char* extensions, const char* name) {
  if (extensions == nullptr) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = extensions; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == extensions || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

// EGL displays are per-process singletons: two contexts on the same platform share one,
// and eglTerminate would pull it from under the other. Count our users per display.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

void retainDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  ++g_display_users[display];
}

void releaseDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  auto it = g_display_users.find(display);
  if (it == g_display_users.end()) return;
  if (--it->second == 0) {
    g_display_users.erase(it);
    eglTerminate(display);
  }
}

struct Candidate {
  std::string name;  // for messages: "surfaceless", "device 0 (EGL_MESA_device_software)"
  EGLDisplay display;
};

// Creates a GL 3.3 core context on an initialised display and makes it current without
// a surface. Returns the context or an error text.
hysim::Result<EGLContext> makeContext(EGLDisplay display) {
  const char* display_ext = eglQueryString(display, EGL_EXTENSIONS);
  if (!hasExtension(display_ext, "EGL_KHR_surfaceless_context")) {
    return hysim::Error{"no EGL_KHR_surfaceless_context"};
  }
  if (!eglBindAPI(EGL_OPENGL_API)) return hysim::Error{"eglBindAPI(OpenGL) failed"};

  // The FBO carries colour and depth, so the config only has to offer desktop GL. Some
  // drivers expose no pbuffer configs on device displays: fall back to any surface type,
  // then to no config at all.
  EGLConfig config = nullptr;
  EGLint count = 0;
  const EGLint with_pbuffer[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE,
                                 EGL_OPENGL_BIT, EGL_NONE};
  const EGLint any_surface[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                EGL_NONE};
  if (!eglChooseConfig(display, with_pbuffer, &config, 1, &count) || count < 1) {
    if (!eglChooseConfig(display, any_surface, &config, 1, &count) || count < 1) {
      if (!hasExtension(display_ext, "EGL_KHR_no_config_context")) {
        return hysim::Error{"no EGL config with OpenGL support"};
      }
      config = EGL_NO_CONFIG_KHR;
    }
  }
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3,
                                    EGL_CONTEXT_MINOR_VERSION, 3,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                    EGL_NONE};
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
  if (context == EGL_NO_CONTEXT) {
    return hysim::Error{"eglCreateContext(OpenGL 3.3 core) failed: " + lastEglError()};
  }
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    std::string message = "eglMakeCurrent without surface failed: " + lastEglError();
    eglDestroyContext(display, context);
    return hysim::Error{message};
  }
  return context;
}

}  // namespace

hysim::Result<std::unique_ptr<EglHeadlessContext>> EglHeadlessContext::create(
    const EglOptions& options) {
  const std::string help =
      " Headless rendering needs an EGL driver with a surfaceless or device platform "
      "(on Debian: libegl1 libegl-mesa0 libgl1-mesa-dri; Mesa's llvmpipe runs on any CPU).";

  // Client extensions (EGL 1.5 or EGL_EXT_client_extensions) list the platforms.
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client_ext == nullptr) {
    return hysim::Error{"EGL: no client extensions (no EGL vendor library, or EGL < 1.5)." +
                        help};
  }
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_platform_display == nullptr || !hasExtension(client_ext, "EGL_EXT_platform_base")) {
    return hysim::Error{"EGL: EGL_EXT_platform_base missing; cannot open a display "
                        "without a window system." + help};
  }

  std::vector<Candidate> candidates;
  std::string tried;  // what did not work, for the error message
  const bool want_surfaceless = options.platform != EglPlatform::Device;
  const bool want_device = options.platform != EglPlatform::Surfaceless;

  if (want_surfaceless) {
    if (hasExtension(client_ext, "EGL_MESA_platform_surfaceless")) {
      EGLDisplay d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY,
                                          nullptr);
      if (d != EGL_NO_DISPLAY) {
        candidates.push_back({"surfaceless", d});
      } else {
        tried += " surfaceless: no display (" + lastEglError() + ");";
      }
    } else {
      tried += " surfaceless: EGL_MESA_platform_surfaceless not offered;";
    }
  }
  if (want_device) {
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(
        eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    EGLint num_devices = 0;
    if (hasExtension(client_ext, "EGL_EXT_platform_device") && query_devices != nullptr &&
        query_devices(0, nullptr, &num_devices) && num_devices > 0) {
      std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(num_devices));
      query_devices(num_devices, devices.data(), &num_devices);
      for (int i = 0; i < num_devices; ++i) {
        if (options.device_index >= 0 && i != options.device_index) continue;
        std::string name = "device " + std::to_string(i);
        if (query_device_string != nullptr) {
          const char* ext = query_device_string(devices[static_cast<std::size_t>(i)],
                                                EGL_EXTENSIONS);
          if (ext != nullptr && *ext != '\0') name += " (" + std::string(ext) + ")";
        }
        EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT,
                                            devices[static_cast<std::size_t>(i)], nullptr);
        if (d != EGL_NO_DISPLAY) {
          candidates.push_back({name, d});
        } else {
          tried += " " + name + ": no display (" + lastEglError() + ");";
        }
      }
      if (options.device_index >= num_devices) {
        tried += " device " + std::to_string(options.device_index) + ": only " +
                 std::to_string(num_devices) + " EGL device(s);";
      }
    } else {
      tried += " device: no EGL devices (EGL_EXT_platform_device / eglQueryDevicesEXT);";
    }
  }

  for (const Candidate& candidate : candidates) {
    EGLint major = 0, minor = 0;
    if (!eglInitialize(candidate.display, &major, &minor)) {
      tried += " " + candidate.name + ": eglInitialize failed (" + lastEglError() + ");";
      continue;
    }
    retainDisplay(candidate.display);
    hysim::Result<EGLContext> context = makeContext(candidate.display);
    if (!context.ok()) {
      tried += " " + candidate.name + ": " + context.error() + ";";
      releaseDisplay(candidate.display);
      continue;
    }
    // epoxy resolves GL entry points through the current EGL context from here on.
    const int gl_version = epoxy_gl_version();
    if (gl_version < 33) {
      tried += " " + candidate.name + ": context is GL " + std::to_string(gl_version / 10) +
               "." + std::to_string(gl_version % 10) + ", need 3.3;";
      eglMakeCurrent(candidate.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      eglDestroyContext(candidate.display, *context);
      releaseDisplay(candidate.display);
      continue;
    }
    auto result = std::unique_ptr<EglHeadlessContext>(new EglHeadlessContext());
    result->display_ = candidate.display;
    result->context_ = *context;
    const char* vendor = eglQueryString(candidate.display, EGL_VENDOR);
    const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    result->description_ = "EGL " + std::to_string(major) + "." + std::to_string(minor) +
                           " (" + (vendor ? vendor : "?") + ") " + candidate.name +
                           "; GL: " + (renderer ? renderer : "?") + ", " +
                           (version ? version : "?");
    return result;
  }
  return hysim::Error{"EGL: no headless display with OpenGL 3.3 core available. Tried:" +
                      tried + help};
}

EglHeadlessContext::~EglHeadlessContext() {
  if (context_ != nullptr) {
    if (eglGetCurrentContext() == context_) {
      eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    eglDestroyContext(display_, context_);
  }
  if (display_ != nullptr) releaseDisplay(display_);
}

hysim::Status EglHeadlessContext::makeCurrent() {
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
    return hysim::Error{"eglMakeCurrent failed: " + lastEglError()};
  }
  return hysim::Status::Ok();
}

}  // namespace hysim::render
