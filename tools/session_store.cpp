#include "session_store.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tool_common.hpp"

namespace fs = std::filesystem;

namespace hysim::tools {
namespace {

constexpr const char* kSchema =
    "CREATE TABLE IF NOT EXISTS sessions ("
    " id INTEGER PRIMARY KEY, file TEXT UNIQUE NOT NULL, trainee TEXT NOT NULL, case_name TEXT NOT NULL,"
    " scene TEXT, mode TEXT, started_utc TEXT, complete INTEGER, duration_s REAL, myoma_resected_pct REAL,"
    " healthy_removed_mm3 REAL, perforations INTEGER, electrode_active_s REAL, passes INTEGER, score REAL,"
    " passed INTEGER, recording TEXT)";

// The columns after id, in the order the statements below bind and read them.
constexpr const char* kColumns =
    "file, trainee, case_name, scene, mode, started_utc, complete, duration_s, myoma_resected_pct, "
    "healthy_removed_mm3, perforations, electrode_active_s, passes, score, passed, recording";

// A prepared statement, finalized when it goes out of scope.
class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql) { rc_ = sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt_, nullptr); }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  bool ok() const { return rc_ == SQLITE_OK; }
  sqlite3_stmt* get() const { return stmt_; }
  void text(int i, const std::string& s) { sqlite3_bind_text(stmt_, i, s.c_str(), -1, SQLITE_TRANSIENT); }
  void real(int i, double v) { sqlite3_bind_double(stmt_, i, v); }
  void integer(int i, long long v) { sqlite3_bind_int64(stmt_, i, v); }
  std::string columnText(int i) const {
    const unsigned char* t = sqlite3_column_text(stmt_, i);
    return t ? reinterpret_cast<const char*>(t) : "";
  }

 private:
  sqlite3_stmt* stmt_ = nullptr;
  int rc_ = SQLITE_ERROR;
};

std::string utcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// Letters, digits, '-' and '_' of `s` (others become '_'), at most 40 of them: a file name part.
std::string namePart(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (out.size() >= 40) break;
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    out += plain ? c : '_';
  }
  return out.empty() ? "_" : out;
}

// started_utc without separators, trainee and case: a new file in `dir` (-2, -3, ... when taken).
std::string newSessionFile(const fs::path& dir, const SessionRecord& r) {
  std::string stamp;
  for (const char c : r.started_utc)
    if (c >= '0' && c <= '9') stamp += c;
  // (The process id keeps two sessions begun in the same second by two programs apart.)
  const std::string base =
      stamp + "-" + namePart(r.trainee) + "-" + namePart(r.case_name) + "-" + std::to_string(::getpid());
  fs::path p = dir / (base + ".json");
  for (int k = 2; fs::exists(p); ++k) p = dir / (base + "-" + std::to_string(k) + ".json");
  return p.string();
}

nlohmann::ordered_json toJson(const SessionRecord& r) {
  return {{"trainee", r.trainee},
          {"case", r.case_name},
          {"scene", r.scene},
          {"mode", r.mode},
          {"started_utc", r.started_utc},
          {"complete", r.complete},
          {"duration_s", r.duration_s},
          {"myoma_resected_pct", r.myoma_resected_pct},
          {"healthy_removed_mm3", r.healthy_removed_mm3},
          {"perforations", r.perforations},
          {"electrode_active_s", r.electrode_active_s},
          {"passes", r.passes},
          {"score", r.score},
          {"passed", r.passed},
          {"recording", r.recording}};
}

// Binds r to the statement's ?1..?16 in kColumns' order (the file by its name only).
void bindRecord(Statement& s, const SessionRecord& r) {
  s.text(1, fs::path(r.file).filename().string());
  s.text(2, r.trainee);
  s.text(3, r.case_name);
  s.text(4, r.scene);
  s.text(5, r.mode);
  s.text(6, r.started_utc);
  s.integer(7, r.complete);
  s.real(8, r.duration_s);
  s.real(9, r.myoma_resected_pct);
  s.real(10, r.healthy_removed_mm3);
  s.integer(11, r.perforations);
  s.real(12, r.electrode_active_s);
  s.integer(13, r.passes);
  s.real(14, r.score);
  s.integer(15, r.passed);
  s.text(16, r.recording);
}

// The row the statement stands on: id, then kColumns.
SessionRecord readRow(const Statement& s, const fs::path& dir) {
  sqlite3_stmt* st = s.get();
  SessionRecord r;
  r.id = sqlite3_column_int64(st, 0);
  r.file = (dir / s.columnText(1)).string();
  r.trainee = s.columnText(2);
  r.case_name = s.columnText(3);
  r.scene = s.columnText(4);
  r.mode = s.columnText(5);
  r.started_utc = s.columnText(6);
  r.complete = sqlite3_column_int(st, 7) != 0;
  r.duration_s = sqlite3_column_double(st, 8);
  r.myoma_resected_pct = sqlite3_column_double(st, 9);
  r.healthy_removed_mm3 = sqlite3_column_double(st, 10);
  r.perforations = sqlite3_column_int(st, 11);
  r.electrode_active_s = sqlite3_column_double(st, 12);
  r.passes = sqlite3_column_int(st, 13);
  r.score = sqlite3_column_double(st, 14);
  r.passed = sqlite3_column_int(st, 15) != 0;
  r.recording = s.columnText(16);
  return r;
}

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

std::string defaultDataFolder() {
  if (const char* d = std::getenv("HYSIM_DATA_DIR"); d && *d) return d;
  if (const char* x = std::getenv("XDG_DATA_HOME"); x && *x) return (fs::path(x) / "hysim").string();
  const char* home = std::getenv("HOME");
  return (fs::path(home && *home ? home : ".") / ".local" / "share" / "hysim").string();
}

SessionStore::SessionStore(std::string folder) : folder_(std::move(folder)) {}

SessionStore::~SessionStore() { sqlite3_close(db_); }

std::string SessionStore::databasePath() const { return (fs::path(folder_) / "sessions.sqlite").string(); }

Error SessionStore::databaseError(const std::string& doing) const {
  return Error{"session database '" + databasePath() + "': " + doing + ": " + (db_ ? sqlite3_errmsg(db_) : "not open")};
}

Status SessionStore::exec(const std::string& sql) const {
  char* message = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message) == SQLITE_OK) return Status::Ok();
  const std::string text = message ? message : "unknown error";
  sqlite3_free(message);
  return Error{"session database '" + databasePath() + "': " + text};
}

Status SessionStore::open() {
  std::error_code ec;
  fs::create_directories(fs::path(folder_) / "sessions", ec);
  if (ec) return Error{"cannot create the session folder '" + (fs::path(folder_) / "sessions").string() + "': " + ec.message()};
  if (sqlite3_open_v2(databasePath().c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    const Error e = databaseError("cannot open");
    sqlite3_close(db_);
    db_ = nullptr;
    return e;
  }
  sqlite3_busy_timeout(db_, 2000);  // another hysim writing: wait a little, then say it is locked
  if (Status st = exec(kSchema); !st.ok()) {
    sqlite3_close(db_);
    db_ = nullptr;
    return st;
  }
  // Rows that could not be recovered now (e.g. another process holds the lock) are recovered
  // by a later open; the database stays usable meanwhile.
  return addMissingRows();
}

Status SessionStore::writeFile(const SessionRecord& r) const {
  return writeFileAtomically(r.file, toJson(r).dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n");
}

Status SessionStore::upsertRow(SessionRecord& r) {
  if (!db_) return Error{"session database '" + databasePath() + "' is not open"};
  std::string sql = std::string("INSERT INTO sessions (") + kColumns +
                    ") VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16) "
                    "ON CONFLICT(file) DO UPDATE SET trainee = ?2, case_name = ?3, scene = ?4, mode = ?5, "
                    "started_utc = ?6, complete = ?7, duration_s = ?8, myoma_resected_pct = ?9, "
                    "healthy_removed_mm3 = ?10, perforations = ?11, electrode_active_s = ?12, passes = ?13, "
                    "score = ?14, passed = ?15, recording = ?16 RETURNING id";
  Statement s(db_, sql);
  if (!s.ok()) return databaseError("cannot prepare the session row");
  bindRecord(s, r);
  if (sqlite3_step(s.get()) != SQLITE_ROW) return databaseError("cannot write the session row");
  const long long id = sqlite3_column_int64(s.get(), 0);
  // With RETURNING the row is committed when the statement runs to its end, which can fail.
  if (sqlite3_step(s.get()) != SQLITE_DONE) return databaseError("cannot write the session row");
  r.id = id;
  return Status::Ok();
}

Status SessionStore::addMissingRows() {
  // The folder is read inside the write transaction: a session finished by another process
  // meanwhile cannot be overwritten by what its file said before.
  if (Status st = exec("BEGIN IMMEDIATE"); !st.ok()) return st;
  std::vector<SessionRecord> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(fs::path(folder_) / "sessions", ec)) {
    if (entry.path().extension() != ".json") continue;
    auto r = readSessionFile(entry.path().string());
    if (r.ok()) files.push_back(*r);  // (an unreadable file is skipped, never deleted)
  }
  if (ec) {
    (void)exec("ROLLBACK");
    return Error{"cannot list the session folder: " + ec.message()};
  }
  for (SessionRecord& r : files) {
    if (Status st = upsertRow(r); !st.ok()) {
      (void)exec("ROLLBACK");
      return st;
    }
  }
  return exec("COMMIT");
}

Status SessionStore::begin(SessionRecord& r) {
  if (r.started_utc.empty()) r.started_utc = utcNow();
  r.complete = false;
  r.id = -1;
  std::error_code ec;
  const fs::path dir = fs::path(folder_) / "sessions";
  fs::create_directories(dir, ec);
  if (ec) return Error{"cannot create the session folder '" + dir.string() + "': " + ec.message()};
  r.file = newSessionFile(dir, r);
  if (Status st = writeFile(r); !st.ok()) return Error{"the session cannot be saved: " + st.error()};
  if (Status st = upsertRow(r); !st.ok()) return Error{st.error() + " (the session is kept in '" + r.file + "')"};
  return Status::Ok();
}

Status SessionStore::finish(SessionRecord& r, bool complete) {
  r.complete = complete;
  if (Status st = writeFile(r); !st.ok()) return Error{"the session cannot be saved: " + st.error()};
  if (Status st = upsertRow(r); !st.ok()) return Error{st.error() + " (the session is kept in '" + r.file + "')"};
  return Status::Ok();
}

Result<std::vector<SessionRecord>> SessionStore::list(const std::string& trainee) const {
  if (!db_) return Error{"session database '" + databasePath() + "' is not open"};
  Statement s(db_, std::string("SELECT id, ") + kColumns + " FROM sessions" +
                       (trainee.empty() ? "" : " WHERE trainee = ?1") + " ORDER BY started_utc, id");
  if (!s.ok()) return databaseError("cannot read the sessions");
  if (!trainee.empty()) s.text(1, trainee);
  std::vector<SessionRecord> out;
  int rc = 0;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) out.push_back(readRow(s, fs::path(folder_) / "sessions"));
  if (rc != SQLITE_DONE) return databaseError("cannot read the sessions");
  return out;
}

Result<SessionRecord> readSessionFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open the session file"};
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return Error{path + ": not a session file (not a JSON object)"};
  SessionRecord r;
  try {
    r.file = fs::absolute(path).lexically_normal().string();
    r.trainee = j.at("trainee").get<std::string>();
    r.case_name = j.at("case").get<std::string>();
    r.scene = j.value("scene", "");
    r.mode = j.value("mode", "");
    r.started_utc = j.at("started_utc").get<std::string>();
    r.complete = j.at("complete").get<bool>();
    r.duration_s = j.value("duration_s", 0.0);
    r.myoma_resected_pct = j.value("myoma_resected_pct", 0.0);
    r.healthy_removed_mm3 = j.value("healthy_removed_mm3", 0.0);
    r.perforations = j.value("perforations", 0);
    r.electrode_active_s = j.value("electrode_active_s", 0.0);
    r.passes = j.value("passes", 0);
    r.score = j.value("score", 0.0);
    r.passed = j.value("passed", false);
    r.recording = j.value("recording", "");
  } catch (const nlohmann::json::exception& e) {
    return Error{path + ": not a session file (" + e.what() + ")"};
  }
  return r;
}

std::string sessionsCsv(const std::vector<SessionRecord>& sessions) {
  std::ostringstream out;
  out << "id,trainee,case,mode,started_utc,complete,duration_s,myoma_resected_pct,healthy_removed_mm3,perforations,"
         "electrode_active_s,passes,score,passed,recording,file\r\n";
  for (const SessionRecord& r : sessions) {
    out << r.id << ',' << csvField(r.trainee) << ',' << csvField(r.case_name) << ',' << csvField(r.mode) << ','
        << r.started_utc << ',' << (r.complete ? 1 : 0) << ',' << r.duration_s << ',' << r.myoma_resected_pct << ','
        << r.healthy_removed_mm3 << ',' << r.perforations << ',' << r.electrode_active_s << ',' << r.passes << ','
        << r.score << ',' << (r.passed ? 1 : 0) << ',' << csvField(r.recording) << ',' << csvField(r.file) << "\r\n";
  }
  return out.str();
}

std::string sessionsJson(const std::vector<SessionRecord>& sessions) {
  nlohmann::ordered_json a = nlohmann::ordered_json::array();
  for (const SessionRecord& r : sessions) {
    nlohmann::ordered_json j = {{"id", r.id}};
    j.update(toJson(r));
    j["file"] = r.file;
    a.push_back(j);
  }
  return a.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace hysim::tools
