#pragma once
// The frame loop the app's screens after a case share (debrief, progress, replay): events to
// the screen's keys, the screen drawn full-window, and the exit options that let tests run a
// screen headless (leave after a time or a number of frames, with a screenshot of the last).
#include <SDL.h>

#include "app_start_screen.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

class Screen {
 public:
  virtual ~Screen() = default;
  // A key ImGui did not take (no repeats).
  virtual void onKey(SDL_Keycode key) = 0;
  // Before ImGui's frame: the screen's own GL drawing into the window (default: a plain clear).
  virtual void drawScene(render::SdlWindow& window);
  // The screen's ImGui windows, w x h screen coordinates.
  virtual void draw(float w, float h) = 0;
  // The screen was left (a button or key chose what comes next).
  virtual bool done() const = 0;
};

// Runs `screen` until it is done; true when it was left otherwise: the window closed, or the
// exit's time or frames ran out (the last frame then goes to exit.screenshot when one is asked).
bool runScreen(render::SdlWindow& window, render::ImGuiLayer& layer, Screen& screen, const StartScreenExit& exit);

}  // namespace hysim::tools
