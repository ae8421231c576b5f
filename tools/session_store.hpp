#pragma once
// Trainee sessions kept in the user's data folder: one JSON file per session (the record that
// counts) and a row per session in an SQLite database (the index the progress screen and
// `hysim sessions` read). The file is written first and the row second, so a database that is
// corrupt, locked or read-only never loses a session: its file stays, and the next open()
// that reaches the database adds the rows it misses.
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"

struct sqlite3;

namespace hysim::tools {

struct SessionRecord {
  long long id = -1;        // the database's row id; -1: no row (yet)
  std::string file;         // the session file, absolute (its name is the session's key)
  std::string trainee;
  std::string case_name;    // the scene's name
  std::string scene;        // the scene file
  std::string mode;         // demo (the scripted course) or hands-on
  std::string started_utc;  // ISO 8601, e.g. 2026-11-29T12:40:05Z
  bool complete = false;    // false while running, and for a session that was killed
  double duration_s = 0.0;
  double myoma_resected_pct = 0.0;
  double healthy_removed_mm3 = 0.0;
  int perforations = 0;
  double electrode_active_s = 0.0;
  int passes = 0;
  double score = 0.0;  // the assessment's, 0..100
  bool passed = false;
  std::string recording;  // the session's recording file, if any
};

// $HYSIM_DATA_DIR, else $XDG_DATA_HOME/hysim, else $HOME/.local/share/hysim.
std::string defaultDataFolder();

class SessionStore {
 public:
  // Nothing is opened yet: sessions go to folder/sessions/, the database is folder/sessions.sqlite.
  explicit SessionStore(std::string folder);
  ~SessionStore();
  SessionStore(const SessionStore&) = delete;
  SessionStore& operator=(const SessionStore&) = delete;

  // Creates the folders, opens (or creates) the database and adds the rows missing for session
  // files. An error names the file and the reason; sessions can still be begun (files only).
  Status open();
  bool databaseOpen() const { return db_ != nullptr; }

  // Starts a session: writes its file (complete = false), then its row; sets record.file and
  // record.id. An error after the file was written says so: the session is not lost.
  Status begin(SessionRecord& record);
  // Ends it: the file rewritten with the outcome, then the row updated (added if missing).
  // complete = false keeps it listed as incomplete (a run stopped early), with what it did.
  Status finish(SessionRecord& record, bool complete = true);
  // The rows, oldest first; only `trainee`'s when it is not empty.
  Result<std::vector<SessionRecord>> list(const std::string& trainee = {}) const;

  const std::string& folder() const { return folder_; }
  std::string databasePath() const;

 private:
  Status writeFile(const SessionRecord& record) const;
  Status upsertRow(SessionRecord& record);
  Status addMissingRows();
  Status exec(const std::string& sql) const;
  Error databaseError(const std::string& doing) const;

  std::string folder_;
  sqlite3* db_ = nullptr;
};

// Reads a session file (as written by SessionStore); the error names the file.
Result<SessionRecord> readSessionFile(const std::string& path);

// Export: one header row then a row per session (RFC 4180 quoting), or a JSON array.
std::string sessionsCsv(const std::vector<SessionRecord>& sessions);
std::string sessionsJson(const std::vector<SessionRecord>& sessions);

}  // namespace hysim::tools
