#pragma once
// `hysim run --trainee NAME`: the run stored as a trainee session (session_store.hpp), begun
// before the first step (so a killed run shows as incomplete) and finished with its outcome.
#include <memory>
#include <string>

#include "hysim/cutting/result.hpp"
#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "session_store.hpp"

namespace hysim::tools {

struct RunSession {
  std::unique_ptr<SessionStore> store;
  SessionRecord record;
};

// Opens the store in `data_dir` (empty: the default) and begins the session. A database that
// cannot be used is a warning on standard error (the session file is still written); a session
// file that cannot be written is the error returned.
Status beginRunSession(const std::string& data_dir, const std::string& trainee, const std::string& mode,
                       const engine::Scene& scene, const std::string& recording, RunSession& session);

// The run's outcome and assessment into the record, then the store's finish (errors on
// standard error: the report is written either way).
void finishRunSession(const engine::RunReport& report, RunSession& session);

}  // namespace hysim::tools
