// SDL2 window + OpenGL 3.3 core context. Every failure is an Error with SDL's message and
// a hint; nothing here aborts (CI machines have no display and must get a clear message).
#include "hysim/render/sdl_window.hpp"

#include <SDL.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace hysim::render {
namespace {

std::string sdlError() {
  const char* e = SDL_GetError();
  return (e && *e) ? std::string(e) : std::string("unknown SDL error");
}

std::string glString(GLenum name) {
  const GLubyte* s = glGetString(name);
  return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
}

bool envSet(const char* name) {
  const char* v = std::getenv(name);
  return v && *v;
}

}  // namespace

hysim::Result<std::unique_ptr<SdlWindow>> SdlWindow::create(const SdlWindowOptions& options) {
  if (options.width <= 0 || options.height <= 0) {
    return hysim::Error{"window size must be positive, got " + std::to_string(options.width) + "x" +
                        std::to_string(options.height)};
  }
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0) {
    std::string message = "cannot open a window: SDL video initialisation failed: " + sdlError();
    if (!envSet("DISPLAY") && !envSet("WAYLAND_DISPLAY")) {
      message += " (no display: neither DISPLAY nor WAYLAND_DISPLAY is set; for headless runs use "
                 "`hysim run --frames DIR`, or run under xvfb-run)";
    }
    return hysim::Error{message};
  }
  // From here on, a failure must undo the SDL_InitSubSystem above (the destructor does).
  auto result = std::unique_ptr<SdlWindow>(new SdlWindow());
  const char* driver_name = SDL_GetCurrentVideoDriver();
  const std::string driver = driver_name ? driver_name : "";
  if ((driver == "offscreen" || driver == "dummy") && !options.allow_invisible &&
      !envSet("SDL_VIDEODRIVER")) {
    return hysim::Error{"cannot open a window: no display (neither DISPLAY nor WAYLAND_DISPLAY "
                        "is set, SDL found only its invisible '" + driver + "' video driver); "
                        "for headless runs use `hysim run --frames DIR`, or run under xvfb-run"};
  }

  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 3);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
  SDL_GL_SetAttribute(SDL_GL_CONTEXT_FLAGS, 0);
  SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
  SDL_GL_SetAttribute(SDL_GL_RED_SIZE, 8);
  SDL_GL_SetAttribute(SDL_GL_GREEN_SIZE, 8);
  SDL_GL_SetAttribute(SDL_GL_BLUE_SIZE, 8);
  SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 0);  // the Renderer has its own depth buffer
  SDL_GL_SetAttribute(SDL_GL_STENCIL_SIZE, 0);
  // Renderer::blitTo needs a single-sampled default framebuffer.
  SDL_GL_SetAttribute(SDL_GL_MULTISAMPLEBUFFERS, 0);
  SDL_GL_SetAttribute(SDL_GL_MULTISAMPLESAMPLES, 0);

  Uint32 flags = SDL_WINDOW_OPENGL | SDL_WINDOW_SHOWN;
  if (options.resizable) flags |= SDL_WINDOW_RESIZABLE;
  if (options.high_dpi) flags |= SDL_WINDOW_ALLOW_HIGHDPI;
  result->window_ = SDL_CreateWindow(options.title.c_str(), SDL_WINDOWPOS_CENTERED,
                                     SDL_WINDOWPOS_CENTERED, options.width, options.height, flags);
  if (!result->window_) {
    return hysim::Error{"cannot open a " + std::to_string(options.width) + "x" +
                        std::to_string(options.height) + " OpenGL window: " + sdlError()};
  }
  result->context_ = SDL_GL_CreateContext(result->window_);
  if (!result->context_) {
    return hysim::Error{"cannot create an OpenGL 3.3 core context for the window: " + sdlError() +
                        " (the display's GL driver may not offer GL 3.3 core)"};
  }
  if (SDL_GL_MakeCurrent(result->window_, result->context_) != 0) {
    return hysim::Error{"cannot make the window's GL context current: " + sdlError()};
  }
  if (options.vsync) {
    // Adaptive vsync first (late frames tear instead of waiting a whole refresh).
    if (SDL_GL_SetSwapInterval(-1) != 0) (void)SDL_GL_SetSwapInterval(1);
  } else {
    (void)SDL_GL_SetSwapInterval(0);
  }

  const int gl_version = epoxy_gl_version();  // 10 * major + minor
  if (gl_version < 33) {
    return hysim::Error{"the window's GL context is version " + std::to_string(gl_version / 10) + "." +
                        std::to_string(gl_version % 10) + ", need 3.3 core (" + glString(GL_RENDERER) +
                        ")"};
  }
  SDL_version linked;
  SDL_GetVersion(&linked);
  result->description_ = "SDL " + std::to_string(linked.major) + "." + std::to_string(linked.minor) + "." +
                         std::to_string(linked.patch) + " " + driver +
                         "; GL: " + glString(GL_RENDERER) + " " + glString(GL_VERSION);
  return result;
}

SdlWindow::~SdlWindow() {
  if (context_) SDL_GL_DeleteContext(static_cast<SDL_GLContext>(context_));
  if (window_) SDL_DestroyWindow(window_);
  SDL_QuitSubSystem(SDL_INIT_VIDEO);
}

hysim::Status SdlWindow::makeCurrent() {
  if (SDL_GL_MakeCurrent(window_, static_cast<SDL_GLContext>(context_)) != 0) {
    return hysim::Error{"cannot make the window's GL context current: " + sdlError()};
  }
  return hysim::Status::Ok();
}

void SdlWindow::swapBuffers() {
  std::string path;
  {
    std::lock_guard<std::mutex> lock(capture_mutex_);
    path.swap(capture_path_);
  }
  if (!path.empty()) {
    const Image shot = readBackBuffer();
    if (Status s = writePng(path, shot); !s.ok()) {
      std::fprintf(stderr, "hysim: %s\n", s.error().c_str());
    } else {
      std::printf("hysim: frame captured in %s (%dx%d)\n", path.c_str(), shot.width, shot.height);
    }
  }
  SDL_GL_SwapWindow(window_);
}

void SdlWindow::captureNextFrame(const std::string& png_path) {
  std::lock_guard<std::mutex> lock(capture_mutex_);
  capture_path_ = png_path;
}

void SdlWindow::clear(float r, float g, float b) {
  int w = 0, h = 0;
  drawableSize(w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, w, h);
  glDisable(GL_SCISSOR_TEST);
  glClearColor(r, g, b, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT);
}

void SdlWindow::drawableSize(int& width, int& height) const {
  SDL_GL_GetDrawableSize(window_, &width, &height);
}

Image SdlWindow::readBackBuffer() const {
  int w = 0, h = 0;
  drawableSize(w, h);
  Image image(std::max(w, 0), std::max(h, 0));
  if (!image.valid()) return image;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  // GL's row 0 is the bottom; the Image's row 0 is the top.
  const std::size_t row = static_cast<std::size_t>(w) * 4;
  for (int y = 0; y < h / 2; ++y) {
    std::uint8_t* a = image.rgba.data() + static_cast<std::size_t>(y) * row;
    std::uint8_t* b = image.rgba.data() + static_cast<std::size_t>(h - 1 - y) * row;
    std::swap_ranges(a, a + row, b);
  }
  for (std::size_t i = 3; i < image.rgba.size(); i += 4) image.rgba[i] = 255;  // opaque PNG
  return image;
}

}  // namespace hysim::render
