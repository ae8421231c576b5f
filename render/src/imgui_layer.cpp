// Dear ImGui context + the SDL2 and OpenGL3 backends (compiled from libimgui-dev's example
// sources into the imgui_backends library, see render/CMakeLists.txt).
#include "hysim/render/imgui_layer.hpp"

#include <SDL.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>
#include <imgui_impl_sdl.h>

namespace hysim::render {
namespace {
bool g_layer_alive = false;  // ImGui's backends keep global state: one layer at a time
}  // namespace

hysim::Result<std::unique_ptr<ImGuiLayer>> ImGuiLayer::create(SdlWindow& window) {
  if (g_layer_alive) return hysim::Error{"an ImGuiLayer already exists (ImGui's backends are global)"};
  IMGUI_CHECKVERSION();
  auto layer = std::unique_ptr<ImGuiLayer>(new ImGuiLayer());
  ImGui::CreateContext();
  g_layer_alive = true;  // from here on the destructor cleans up
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // do not drop imgui.ini into the working directory
  // No keyboard navigation: with it ImGui claims the keyboard whenever its panel has focus
  // (WantCaptureKeyboard), and the app's own keys (Esc, Space, ...) would stop working.
  // Now ImGui takes keys only while a text field is active.
  ImGui::StyleColorsDark();
  ImGui::GetStyle().WindowRounding = 4.0f;

  if (!ImGui_ImplSDL2_InitForOpenGL(window.nativeWindow(), window.glContext())) {
    return hysim::Error{"ImGui: the SDL2 backend failed to initialise"};
  }
  layer->sdl_backend_ = true;
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) {
    return hysim::Error{"ImGui: the OpenGL3 backend failed to initialise (needs GL 3.3 core)"};
  }
  layer->gl_backend_ = true;
  return layer;
}

ImGuiLayer::~ImGuiLayer() {
  if (gl_backend_) ImGui_ImplOpenGL3_Shutdown();
  if (sdl_backend_) ImGui_ImplSDL2_Shutdown();
  ImGui::DestroyContext();
  g_layer_alive = false;
}

bool ImGuiLayer::processEvent(const SDL_Event& event) {
  ImGui_ImplSDL2_ProcessEvent(&event);
  const ImGuiIO& io = ImGui::GetIO();
  switch (event.type) {
    case SDL_KEYDOWN:
    case SDL_KEYUP:
    case SDL_TEXTINPUT:
      return io.WantCaptureKeyboard;
    case SDL_MOUSEMOTION:
    case SDL_MOUSEBUTTONDOWN:
    case SDL_MOUSEBUTTONUP:
    case SDL_MOUSEWHEEL:
      return io.WantCaptureMouse;
    default:
      return false;
  }
}

bool ImGuiLayer::wantsKeyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }
bool ImGuiLayer::wantsMouse() const { return ImGui::GetIO().WantCaptureMouse; }

void ImGuiLayer::newFrame() {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplSDL2_NewFrame();
  ImGui::NewFrame();
}

void ImGuiLayer::render() {
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace hysim::render
