#include "app_session_store.hpp"

#include <imgui.h>

#include <cstdio>

#include "app_debrief_data.hpp"
#include "hysim/engine/assessment.hpp"

namespace hysim::tools {

void AppSessionStore::configure(const std::string& data_dir, const std::string& trainee) {
  if (!trainee.empty()) trainee_ = trainee;
  store_ = std::make_unique<SessionStore>(data_dir.empty() ? defaultDataFolder() : data_dir);
  note(store_->open());
}

void AppSessionStore::note(const Status& st) {
  if (st.ok()) return;
  problem_ = st.error();
  std::printf("hysim-app: %s\n", problem_.c_str());
}

void AppSessionStore::begin(const engine::Scene& scene, const std::string& recording, bool hands_on) {
  if (!store_) return;
  record_ = SessionRecord{};
  record_.trainee = trainee_;
  record_.case_name = scene.name;
  record_.scene = scene.path;
  record_.mode = hands_on ? "hands-on" : "demo";
  record_.recording = recording;
  note(store_->begin(record_));
  open_ = !record_.file.empty();
}

void AppSessionStore::finish(const engine::Scene& scene, const GuidanceNumbers& n, bool hands_on) {
  if (!store_ || !open_) return;
  open_ = false;
  record_.mode = hands_on ? "hands-on" : "demo";
  record_.duration_s = n.elapsed_s;
  record_.myoma_resected_pct = n.myoma_resected_pct;
  record_.healthy_removed_mm3 = n.healthy_removed_mm3;
  record_.perforations = n.perforations;
  record_.electrode_active_s = n.electrode_active_s;
  record_.passes = n.passes;
  const engine::Assessment a = engine::assess(scene.assessment, assessedOutcome(n));
  record_.score = a.score;
  record_.passed = a.passed;
  note(store_->finish(record_));
  finished_ = true;
}

void AppSessionStore::drawPanel() const {
  ImGui::Text("trainee      %s", trainee_.c_str());
  if (finished_) {
    ImGui::Text("last session %.0f of 100, %s", record_.score, record_.passed ? "passed" : "not passed");
  }
  if (!problem_.empty()) {
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "session store:");
    ImGui::TextWrapped("%s", problem_.c_str());
  }
}

}  // namespace hysim::tools
