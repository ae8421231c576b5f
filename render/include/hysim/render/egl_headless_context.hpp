#pragma once
// Headless OpenGL through EGL: no X server, no Wayland, no window. Filament-style platform
// class: it only provides a current GL 3.3 core context; the Renderer draws into its own
// framebuffer object, so a windowed platform (SDL2) can reuse the same Renderer.
#include <memory>
#include <string>

#include "hysim/cutting/result.hpp"

namespace hysim::render {

enum class EglPlatform {
  Auto,         // surfaceless (Mesa), then the EGL devices in order
  Surfaceless,  // EGL_MESA_platform_surfaceless only (Mesa llvmpipe / any Mesa driver)
  Device,       // EGL_EXT_platform_device only (NVIDIA, Mesa with DRM devices)
};

struct EglOptions {
  EglPlatform platform = EglPlatform::Auto;
  int device_index = -1;  // with Device: which device; -1 = first one that works
};

class EglHeadlessContext {
 public:
  // Creates a display, an OpenGL 3.3 core context and makes it current on the calling
  // thread without any surface. Fails (never aborts) when EGL, a headless platform or
  // a GL 3.3 driver is missing; the message says what was tried.
  static hysim::Result<std::unique_ptr<EglHeadlessContext>> create(const EglOptions& options = {});

  ~EglHeadlessContext();
  EglHeadlessContext(const EglHeadlessContext&) = delete;
  EglHeadlessContext& operator=(const EglHeadlessContext&) = delete;

  // Makes the context current on the calling thread (needed after switching threads).
  hysim::Status makeCurrent();
  // "EGL 1.5 (Mesa Project) surfaceless; GL: Mesa llvmpipe (LLVM 15...) 4.5 (Core Profile)".
  const std::string& description() const { return description_; }

 private:
  EglHeadlessContext() = default;
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  std::string description_;
};

}  // namespace hysim::render
