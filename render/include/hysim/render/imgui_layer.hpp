#pragma once
// Dear ImGui on an SdlWindow: owns the ImGui context and its SDL2 + OpenGL3 backends.
// Per frame: processEvent() for every SDL event, newFrame(), ImGui:: calls, render()
// (draws into the framebuffer bound at the time, normally the window's, after
// Renderer::blitTo). ImGui's backends are global, so only one layer may exist at a time.
#include <memory>

#include "hysim/cutting/result.hpp"
#include "hysim/render/sdl_window.hpp"

union SDL_Event;

namespace hysim::render {

class ImGuiLayer {
 public:
  // Needs `window`'s GL context current; `window` must outlive the layer.
  static hysim::Result<std::unique_ptr<ImGuiLayer>> create(SdlWindow& window);
  ~ImGuiLayer();
  ImGuiLayer(const ImGuiLayer&) = delete;
  ImGuiLayer& operator=(const ImGuiLayer&) = delete;

  // Hands an event to ImGui. Returns true when ImGui wants it (a text field or a panel
  // under the mouse has focus): the app should then not act on it itself.
  bool processEvent(const SDL_Event& event);
  bool wantsKeyboard() const;
  bool wantsMouse() const;

  void newFrame();
  void render();

 private:
  ImGuiLayer() = default;
  bool sdl_backend_ = false;
  bool gl_backend_ = false;
};

}  // namespace hysim::render
