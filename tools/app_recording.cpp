#include "app_recording.hpp"

#include <imgui.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>

#include "hysim/engine/replay.hpp"

namespace fs = std::filesystem;

namespace hysim::tools {
namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::string(v) : std::string();
}

// A file name from the local date and time and the scene's name (letters, digits, - and _).
std::string sessionFileName(const std::string& scene_name) {
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%d-%H%M%S", &local);
  std::string name;
  for (char c : scene_name) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
                       c == '_';
    name += plain ? c : '_';
  }
  return std::string(stamp) + "-" + (name.empty() ? "session" : name) + ".hyrec";
}

}  // namespace

std::string recordingsFolder() {
  std::string base = env("HYSIM_DATA_DIR");
  if (base.empty() && !env("XDG_DATA_HOME").empty()) base = env("XDG_DATA_HOME") + "/hysim";
  if (base.empty()) base = (env("HOME").empty() ? std::string(".") : env("HOME")) + "/.local/share/hysim";
  return base + "/recordings";
}

void AppRecording::start(const engine::Scene& scene, engine::Simulation& sim, const std::string& path) {
  finish();
  problem_.clear();
  path_ = path;
  if (path_.empty()) {
    std::error_code ec;
    fs::create_directories(recordingsFolder(), ec);
    if (ec) {
      problem_ = "cannot create '" + recordingsFolder() + "': " + ec.message();
      std::fprintf(stderr, "hysim-app: not recording: %s\n", problem_.c_str());
      return;
    }
    path_ = (fs::path(recordingsFolder()) / sessionFileName(scene.name)).string();
  }
  auto header = engine::recordingHeader(scene, {}, sim.device().info().name);
  auto writer = std::make_unique<haptics::RecordingWriter>();
  std::string error;
  if (!header.ok() || !writer->open(path_, *header, error)) {
    problem_ = header.ok() ? error : header.error();
    std::fprintf(stderr, "hysim-app: not recording: %s\n", problem_.c_str());
    return;
  }
  if (Status st = sim.recordInputTo(writer.get()); !st.ok()) {
    problem_ = st.error();
    std::fprintf(stderr, "hysim-app: not recording: %s\n", problem_.c_str());
    writer->discard();
    return;
  }
  writer_ = std::move(writer);
  sim_ = &sim;
}

void AppRecording::finish() {
  if (!writer_) return;
  if (sim_ != nullptr) (void)sim_->recordInputTo(nullptr);
  std::string error;
  if (writer_->finish(error)) {
    std::printf("hysim-app: session recorded in %s (%llu states; hysim replay %s)\n", path_.c_str(),
                static_cast<unsigned long long>(writer_->records()), path_.c_str());
  } else {
    std::fprintf(stderr, "hysim-app: the recording is lost: %s\n", error.c_str());
  }
  writer_.reset();
  sim_ = nullptr;
}

void AppRecording::drawPanel() const {
  if (writer_) {
    ImGui::TextWrapped("recording    %s", fs::path(path_).filename().c_str());
  } else if (!problem_.empty()) {
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "not recording:");
    ImGui::TextWrapped("%s", problem_.c_str());
  }
}

}  // namespace hysim::tools
