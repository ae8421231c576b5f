#pragma once
// A desktop window through SDL2 with an OpenGL 3.3 core context: the windowed platform
// class beside EglHeadlessContext (Filament style, one class per windowing system). It only
// provides the window and a current GL context; the Renderer draws into its own
// framebuffer and Renderer::blitTo() puts the frame on screen.
//
// SDL types stay out of this header (apps that only show a frame do not need SDL's
// headers); nativeWindow()/glContext() hand them out for ImGui's backends and event code.
#include <memory>
#include <mutex>
#include <string>

#include "hysim/cutting/result.hpp"
#include "hysim/render/image.hpp"

struct SDL_Window;

namespace hysim::render {

struct SdlWindowOptions {
  std::string title = "hysim";
  int width = 1024;        // window size in screen coordinates
  int height = 768;
  bool resizable = true;
  bool vsync = true;       // swap interval 1 (adaptive -1 tried first); ignored if unsupported
  bool high_dpi = true;    // drawable may be larger than the window (see drawableSize)
  // SDL falls back to its invisible "offscreen"/"dummy" video drivers when there is no
  // display. A window nobody sees is an error unless this is set or the user asked for
  // such a driver explicitly (SDL_VIDEODRIVER=offscreen, e.g. for a smoke test).
  bool allow_invisible = false;
};

class SdlWindow {
 public:
  // Initialises SDL's video subsystem, opens the window and makes an OpenGL 3.3 core
  // context current on the calling thread. Without a display (no DISPLAY / WAYLAND_DISPLAY,
  // e.g. CI) or without a GL 3.3 driver it returns an error saying so; it never aborts.
  static hysim::Result<std::unique_ptr<SdlWindow>> create(const SdlWindowOptions& options = {});

  // Destroys the context and the window and quits SDL's video subsystem.
  ~SdlWindow();
  SdlWindow(const SdlWindow&) = delete;
  SdlWindow& operator=(const SdlWindow&) = delete;

  hysim::Status makeCurrent();
  // Shows the back buffer; first writes it as a PNG when a capture was asked for.
  void swapBuffers();
  // The next swapBuffers writes the frame it shows to `png_path` (from any thread: scripted
  // input asks for pictures while whatever screen is up draws).
  void captureNextFrame(const std::string& png_path);
  // Binds the default framebuffer, sets the viewport to the drawable and clears it.
  void clear(float r, float g, float b);
  // Size of the default framebuffer in pixels (differs from the window size on HiDPI).
  void drawableSize(int& width, int& height) const;
  // Reads the back buffer of the default framebuffer (what the next swapBuffers shows)
  // into an RGBA image, row 0 = top. Call before swapBuffers.
  Image readBackBuffer() const;

  SDL_Window* nativeWindow() const { return window_; }
  void* glContext() const { return context_; }  // SDL_GLContext
  // "SDL 2.26.5 x11; GL: Mesa llvmpipe (LLVM 15...) 4.5 (Core Profile) Mesa 22.3.6".
  const std::string& description() const { return description_; }

 private:
  SdlWindow() = default;
  SDL_Window* window_ = nullptr;
  void* context_ = nullptr;
  std::string description_;
  std::mutex capture_mutex_;
  std::string capture_path_;  // under capture_mutex_; empty: none asked for
};

}  // namespace hysim::render
