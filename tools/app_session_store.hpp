#pragma once
// The app's side of the stored sessions (session_store.hpp): each trainee session gets its file
// and row when it starts and its outcome and score when it ends; what went wrong with the store
// is shown on the panel instead of stopping the session.
#include <memory>
#include <string>

#include "app_guidance.hpp"
#include "hysim/engine/scene.hpp"
#include "session_store.hpp"

namespace hysim::tools {

class AppSessionStore {
 public:
  // The data folder (empty: defaultDataFolder()) and the trainee's name, for every session.
  void configure(const std::string& data_dir, const std::string& trainee);
  // Begins a stored session of `scene` (its recording at `recording`, if any).
  void begin(const engine::Scene& scene, const std::string& recording, bool hands_on);
  // Ends it with the session's numbers, assessed against the scene's thresholds.
  void finish(const engine::Scene& scene, const GuidanceNumbers& numbers, bool hands_on);
  // The trainee, the last finished session's score, and any problem, in the panel.
  void drawPanel() const;

 private:
  void note(const Status& st);
  std::unique_ptr<SessionStore> store_;
  std::string trainee_ = "trainee";
  SessionRecord record_;
  bool open_ = false;      // a session begun and not finished
  bool finished_ = false;  // record_ holds a finished session
  std::string problem_;
};

}  // namespace hysim::tools
