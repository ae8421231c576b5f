#include "cli_sessions.hpp"

#include <cstdio>
#include <iostream>

#include "session_store.hpp"
#include "tool_common.hpp"

namespace hysim::tools {
namespace {

int fail(const std::string& message) {
  std::cerr << "hysim: " << message << "\n";
  return 1;
}

Result<std::vector<SessionRecord>> storedSessions(const SessionsArgs& a) {
  SessionStore store(a.data_dir.empty() ? defaultDataFolder() : a.data_dir);
  if (Status st = store.open(); !st.ok()) return Error{st.error()};
  return store.list(a.trainee);
}

int listCommand(const SessionsArgs& a) {
  auto sessions = storedSessions(a);
  if (!sessions.ok()) return fail(sessions.error());
  std::printf("%-5s %-20s %-16s %-18s %-9s %-8s %9s %10s %5s %6s %5s\n", "id", "started (UTC)", "trainee", "case",
              "mode", "status", "resected", "healthy", "perf", "score", "pass");
  for (const SessionRecord& r : *sessions) {
    std::printf("%-5lld %-20s %-16.16s %-18.18s %-9.9s %-8s %8.1f%% %6.0f mm3 %5d %6.0f %5s\n", r.id,
                r.started_utc.c_str(), r.trainee.c_str(), r.case_name.c_str(), r.mode.c_str(),
                r.complete ? "complete" : "INCOMPLETE", r.myoma_resected_pct, r.healthy_removed_mm3, r.perforations,
                r.score, r.complete ? (r.passed ? "yes" : "no") : "-");
  }
  return 0;
}

int exportCommand(const SessionsArgs& a) {
  if (a.csv == a.json) return fail("sessions export: give exactly one of --csv and --json");
  auto sessions = storedSessions(a);
  if (!sessions.ok()) return fail(sessions.error());
  const std::string text = a.csv ? sessionsCsv(*sessions) : sessionsJson(*sessions);
  if (a.out.empty()) {
    std::cout << text;
    return 0;
  }
  if (Status st = writeFileAtomically(a.out, text); !st.ok()) return fail(st.error());
  return 0;
}

}  // namespace

std::shared_ptr<SessionsCommands> addSessionsCommands(CLI::App& app) {
  auto c = std::make_shared<SessionsCommands>();
  c->sessions = app.add_subcommand("sessions", "Trainee sessions stored in the data folder (list, export)");
  c->sessions->require_subcommand(1);
  c->sessions->fallthrough();  // `sessions list --trainee X` as well as `sessions --trainee X list`
  c->sessions->add_option("--data-dir", c->args.data_dir,
                          "Data folder (default: $HYSIM_DATA_DIR, $XDG_DATA_HOME/hysim or ~/.local/share/hysim)");
  c->sessions->add_option("--trainee", c->args.trainee, "Only this trainee's sessions");
  c->list = c->sessions->add_subcommand("list", "List the sessions, oldest first (killed ones as INCOMPLETE)");
  c->export_ = c->sessions->add_subcommand("export", "Write the sessions as CSV or JSON");
  c->export_->add_flag("--csv", c->args.csv, "CSV, one row per session");
  c->export_->add_flag("--json", c->args.json, "JSON, an array of sessions");
  c->export_->add_option("--out", c->args.out, "Write to this file (default: standard output)");
  return c;
}

std::optional<int> runSessionsCommands(const SessionsCommands& c) {
  if (!*c.sessions) return std::nullopt;
  if (*c.list) return listCommand(c.args);
  return exportCommand(c.args);
}

}  // namespace hysim::tools
