#include "app_screen.hpp"

#include <chrono>
#include <cstdio>

#include "hysim/render/image.hpp"

namespace hysim::tools {

void Screen::drawScene(render::SdlWindow& window) { window.clear(0.07f, 0.07f, 0.08f); }

bool runScreen(render::SdlWindow& window, render::ImGuiLayer& layer, Screen& screen, const StartScreenExit& exit) {
  const auto start = std::chrono::steady_clock::now();
  bool closed = false;
  for (long frame = 1; !screen.done() && !closed; ++frame) {
    SDL_Event event;
    while (SDL_PollEvent(&event)) {
      const bool taken = layer.processEvent(event);
      if (event.type == SDL_QUIT) closed = true;
      if (event.type == SDL_KEYDOWN && !taken && event.key.repeat == 0) screen.onKey(event.key.keysym.sym);
    }
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool timed_out =
        (exit.quit_after_s >= 0.0 && elapsed >= exit.quit_after_s) || (exit.frames >= 0 && frame >= exit.frames);
    int w = 0, h = 0;
    SDL_GetWindowSize(window.nativeWindow(), &w, &h);
    screen.drawScene(window);
    layer.newFrame();
    screen.draw(static_cast<float>(w), static_cast<float>(h));
    layer.render();
    if (timed_out && !exit.screenshot.empty()) {
      if (Status st = render::writePng(exit.screenshot, window.readBackBuffer()); !st.ok()) {
        std::printf("hysim-app: %s\n", st.error().c_str());
      } else {
        std::printf("hysim-app: screenshot %s\n", exit.screenshot.c_str());
      }
    }
    window.swapBuffers();
    closed = closed || timed_out;
  }
  return closed;
}

}  // namespace hysim::tools
