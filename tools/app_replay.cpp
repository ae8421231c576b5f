#include "app_replay.hpp"

#include <imgui.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app_guidance.hpp"
#include "app_screen.hpp"
#include "hysim/engine/replay.hpp"
#include "hysim/engine/sim_thread.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/replay_device.hpp"
#include "hysim/render/renderer.hpp"

namespace hysim::tools {
namespace {

// A recording ready to step: its simulation, the source its devices read, and a renderer.
struct ReplayRun {
  std::shared_ptr<haptics::ReplaySource> source;
  std::unique_ptr<engine::Simulation> sim;
  std::unique_ptr<render::Renderer> renderer;
  long steps_total = 0;
  std::string name;  // the recording's file name
};

// The recording's devices attach where the recorded session's did (engine::replay does the same).
void attachRecordedDevices(engine::Simulation& sim, const std::shared_ptr<haptics::ReplaySource>& source) {
  while (source->nextIsAttach()) sim.setDevice(std::make_unique<haptics::ReplayDevice>(source));
}

Result<ReplayRun> loadReplay(const std::string& path) {
  auto recording = std::make_shared<haptics::Recording>();
  std::string error;
  if (!haptics::readRecording(path, *recording, error)) return Error{"cannot replay: " + error};
  if (recording->states.empty() || !recording->states.front().attached) {
    return Error{"cannot replay " + path + ": it holds no device's states"};
  }
  auto scene = engine::loadReplayScene(*recording, false);
  if (!scene.ok()) return Error{"cannot replay: " + scene.error()};
  auto sim = engine::Simulation::create(scene->scene);
  if (!sim.ok()) return Error{"cannot replay: " + sim.error()};
  auto renderer = render::Renderer::create(scene->scene.render.width, scene->scene.render.height);
  if (!renderer.ok()) return Error{"cannot replay: the renderer: " + renderer.error()};
  ReplayRun run;
  for (const haptics::RecordedState& s : recording->states) run.steps_total += s.attached ? 0 : 1;
  run.source = std::make_shared<haptics::ReplaySource>(std::move(recording));
  run.sim = std::move(sim.value());
  run.renderer = std::move(renderer.value());
  run.name = std::filesystem::path(path).filename().string();
  attachRecordedDevices(*run.sim, run.source);
  return Result<ReplayRun>(std::move(run));
}

class ReplayScreen final : public Screen {
 public:
  // The recording plays on the simulation thread, paced to real time, and pauses at its end.
  explicit ReplayScreen(ReplayRun run) : run_(std::move(run)) {
    sim_thread_.attach(run_.sim.get(), [this](engine::Simulation& sim) { afterStep(sim); });
  }
  ~ReplayScreen() override { sim_thread_.attach(nullptr); }
  void onKey(SDL_Keycode key) override {
    if (key == SDLK_SPACE) paused_ = !paused_;
    if (key == SDLK_b || key == SDLK_BACKSPACE) back_ = true;
    if (key == SDLK_ESCAPE) quit_ = true;
  }
  void drawScene(render::SdlWindow& window) override;
  void draw(float w, float h) override;
  bool done() const override { return back_ || quit_; }
  bool quit() const { return quit_; }

 private:
  void afterStep(engine::Simulation& sim);
  void drawPanel();
  void reportEnd();
  ReplayRun run_;
  render::RenderSnapshot snapshot_;
  bool paused_ = false, back_ = false, quit_ = false;
  bool reported_ = false;
  engine::SimThread sim_thread_;  // last: stops stepping before the run goes
};

// On the simulation thread: the next step's recorded devices attach; at the recording's end
// the thread pauses.
void ReplayScreen::afterStep(engine::Simulation& sim) {
  attachRecordedDevices(sim, run_.source);
  if (static_cast<long>(sim.state().steps) >= run_.steps_total) {
    sim_thread_.setPaused(true);
    reportEnd();
  }
}

// Once, at the recording's end: the state hash, to compare with the session's last line (a
// replay of the same scene by the same build ends bit-identical).
void ReplayScreen::reportEnd() {
  if (reported_) return;
  reported_ = true;
  const engine::Simulation& sim = *run_.sim;
  std::printf("hysim-app: replay of %s finished: sim time %.3f s, %llu steps, perforations %d, state_hash %s\n",
              run_.name.c_str(), sim.state().time, static_cast<unsigned long long>(sim.state().steps),
              sim.perforations(), engine::hashHex(sim.stateHash()).c_str());
}

void ReplayScreen::drawScene(render::SdlWindow& window) {
  sim_thread_.access([this] {
    const bool finished = static_cast<long>(run_.sim->state().steps) >= run_.steps_total;
    sim_thread_.setPaused(paused_ || finished);
    run_.sim->fillSnapshot(snapshot_);
  });
  run_.renderer->draw(snapshot_);
  int dw = 0, dh = 0;
  window.drawableSize(dw, dh);
  const render::Renderer& r = *run_.renderer;
  const double fit = std::min(static_cast<double>(dw) / r.width(), static_cast<double>(dh) / r.height());
  const int vw = static_cast<int>(r.width() * fit), vh = static_cast<int>(r.height() * fit);
  window.clear(0.0f, 0.0f, 0.0f);
  r.blitTo(0, (dw - vw) / 2, (dh - vh) / 2, vw, vh);
}

void ReplayScreen::draw(float, float) {
  sim_thread_.access([this] { drawPanel(); });
}

// The replay's numbers and controls, between two steps.
void ReplayScreen::drawPanel() {
  const engine::Simulation& sim = *run_.sim;
  const GuidanceNumbers n = guidanceNumbers(sim);
  const double end_s = static_cast<double>(run_.steps_total) * sim.scene().sim.dt;
  const bool finished = static_cast<long>(sim.state().steps) >= run_.steps_total;
  ImGui::SetNextWindowPos(ImVec2(10, 10));
  ImGui::SetNextWindowBgAlpha(0.75f);
  ImGui::Begin("Replay", nullptr, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove);
  ImGui::Text("REPLAY of %s", run_.name.c_str());
  ImGui::ProgressBar(end_s > 0.0 ? static_cast<float>(sim.state().time / end_s) : 1.0f, ImVec2(260, 0));
  ImGui::Text("time %.1f of %.1f s%s", sim.state().time, end_s, finished ? "  (finished)" : paused_ ? "  (paused)" : "");
  ImGui::Text("myoma resected %.1f %%, healthy removed %.1f mm3", n.myoma_resected_pct, n.healthy_removed_mm3);
  ImGui::Text("passes %d, electrode active %.1f s", n.passes, n.electrode_active_s);
  if (n.perforations > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "perforations %d", n.perforations);
  } else {
    ImGui::Text("perforations 0");
  }
  if (sim.deviceState().pose.pedal) ImGui::TextColored(ImVec4(1.0f, 0.3f, 0.25f, 1.0f), "CUT");
  if (ImGui::Button(paused_ ? "Play (Space)" : "Pause (Space)")) paused_ = !paused_;
  ImGui::SameLine();
  if (ImGui::Button("Back to the debrief (B)")) back_ = true;
  ImGui::SameLine();
  if (ImGui::Button("Quit (Esc)")) quit_ = true;
  ImGui::End();
}

}  // namespace

ReplayEnd runReplay(render::SdlWindow& window, render::ImGuiLayer& layer, const std::string& recording_path,
                    const StartScreenExit& exit) {
  auto run = loadReplay(recording_path);
  if (!run.ok()) return {false, run.error()};
  ReplayScreen screen(std::move(run.value()));
  const bool closed = runScreen(window, layer, screen, exit);
  return {closed || screen.quit(), ""};
}

}  // namespace hysim::tools
