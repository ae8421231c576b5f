#include "app_haptics.hpp"

#include <imgui.h>

namespace hysim::tools {

AppHaptics::AppHaptics() {
  auto device = std::make_unique<haptics::MirroredDevice>();
  device_ = device.get();
  loop_ = std::make_unique<haptics::HapticLoop>(std::move(device));
  loop_->start();
}

AppHaptics::~AppHaptics() { loop_->stop(); }

void AppHaptics::publish(const engine::Simulation& sim) {
  const auto step = static_cast<std::int64_t>(sim.state().steps);
  if (step == last_step_) return;  // nothing new (paused): not a fresh model
  last_step_ = step;
  device_->publish(sim.deviceState());
  loop_->publishModel(sim.hapticModel());
}

void AppHaptics::drawPanel() {
  const haptics::SafetyState state = loop_->safetyState();
  const bool latched = state == haptics::SafetyState::Fault || state == haptics::SafetyState::EStopped;
  const ImVec4 red(1.0f, 0.35f, 0.3f, 1.0f), green(0.5f, 0.9f, 0.5f, 1.0f), amber(1.0f, 0.75f, 0.3f, 1.0f);
  const ImVec4 colour = latched ? red : state == haptics::SafetyState::Engaged ? green : amber;
  ImGui::Text("force feedback");
  ImGui::SameLine();
  ImGui::TextColored(colour, "%s", haptics::safetyStateName(state));
  if (state == haptics::SafetyState::Fault) {
    ImGui::TextColored(red, "FAULT: %s", haptics::faultReasonName(loop_->faultReason()));
  }
  if (latched) ImGui::TextColored(red, "force off until reset (F)");
  ImGui::Text("hand force   %8.3f N", device_->renderedForceN());
  if (loop_->f0Scale() < 1.0) ImGui::TextColored(amber, "no fresh force model (paused or late): F0 faded");
  if (ImGui::Button("E-stop (X)", ImVec2(140, 0))) eStop();
  ImGui::SameLine();
  if (ImGui::Button("Reset force (F)", ImVec2(-1, 0))) resetSafety();
}

}  // namespace hysim::tools
