// Trainee sessions: the file first, then the row; a corrupt or locked database or an unusable
// folder is a clear error and never a lost session; `hysim run --trainee` and
// `hysim sessions list|export` as a user runs them, including a run killed mid-session.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "run_hysim.hpp"
#include "spawn_hysim.hpp"
#include "session_store.hpp"
#include "test_dir.hpp"

namespace hysim::tools {
namespace {

namespace fs = std::filesystem;

SessionRecord sample(const std::string& trainee) {
  SessionRecord r;
  r.trainee = trainee;
  r.case_name = "default";
  r.scene = "scenes/default.yaml";
  r.mode = "hands-on";
  return r;
}

void finishWithOutcome(SessionStore& store, SessionRecord& r) {
  r.duration_s = 96.7;
  r.myoma_resected_pct = 91.0;
  r.healthy_removed_mm3 = 338.5;
  r.passes = 50;
  r.score = 100.0;
  r.passed = true;
  ASSERT_TRUE(store.finish(r).ok());
}

// An empty data folder of the running test's own.
std::string freshData() {
  const fs::path data = testing::testDir("Sessions") / "data";
  fs::remove_all(data);
  return data.string();
}

TEST(Sessions, FileThenRowAndTheOutcomeOnFinish) {
  SessionStore store(freshData());
  ASSERT_TRUE(store.open().ok());
  SessionRecord a = sample("Ann");
  ASSERT_TRUE(store.begin(a).ok());
  EXPECT_TRUE(fs::exists(a.file));
  EXPECT_GE(a.id, 1);
  auto rows = store.list();
  ASSERT_TRUE(rows.ok()) << rows.error();
  ASSERT_EQ(rows->size(), 1u);
  EXPECT_FALSE((*rows)[0].complete);  // running (or killed) until finished
  finishWithOutcome(store, a);
  SessionRecord b = sample("Ben");
  ASSERT_TRUE(store.begin(b).ok());
  rows = store.list("Ann");
  ASSERT_TRUE(rows.ok());
  ASSERT_EQ(rows->size(), 1u);
  const SessionRecord& got = (*rows)[0];
  EXPECT_TRUE(got.complete);
  EXPECT_EQ(got.id, a.id);
  EXPECT_EQ(got.file, a.file);
  EXPECT_EQ(got.myoma_resected_pct, 91.0);
  EXPECT_EQ(got.passes, 50);
  EXPECT_TRUE(got.passed);
  auto file = readSessionFile(a.file);
  ASSERT_TRUE(file.ok()) << file.error();
  EXPECT_TRUE(file->complete);
  EXPECT_EQ(file->healthy_removed_mm3, 338.5);
  EXPECT_EQ(store.list()->size(), 2u);
}

TEST(Sessions, CorruptDatabaseLosesNoSessionAndIsRebuiltFromTheFiles) {
  const fs::path dir = fs::path(freshData()).parent_path();
  {
    SessionStore store((dir / "data").string());
    ASSERT_TRUE(store.open().ok());
    SessionRecord a = sample("Ann");
    ASSERT_TRUE(store.begin(a).ok());
    finishWithOutcome(store, a);
  }
  std::ofstream(dir / "data" / "sessions.sqlite", std::ios::trunc) << "this is not a database, just text........";
  SessionStore store((dir / "data").string());
  const Status opened = store.open();
  ASSERT_FALSE(opened.ok());
  EXPECT_NE(opened.error().find("sessions.sqlite"), std::string::npos) << opened.error();
  EXPECT_NE(opened.error().find("not a database"), std::string::npos) << opened.error();
  SessionRecord b = sample("Ben");
  const Status begun = store.begin(b);
  ASSERT_FALSE(begun.ok());
  EXPECT_NE(begun.error().find("kept in"), std::string::npos) << begun.error();
  EXPECT_TRUE(fs::exists(b.file));
  // The instructor moves the broken database away: every session comes back from its file.
  fs::rename(dir / "data" / "sessions.sqlite", dir / "data" / "sessions.sqlite.broken");
  SessionStore again((dir / "data").string());
  ASSERT_TRUE(again.open().ok());
  auto rows = again.list();
  ASSERT_TRUE(rows.ok());
  ASSERT_EQ(rows->size(), 2u);
  EXPECT_TRUE((*rows)[0].trainee == "Ann" ? (*rows)[0].complete : (*rows)[1].complete);
}

TEST(Sessions, LockedDatabaseIsAnErrorAndTheRowFollowsLater) {
  SessionStore store(freshData());
  ASSERT_TRUE(store.open().ok());
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(store.databasePath().c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr), SQLITE_OK);
  SessionRecord a = sample("Ann");
  const Status begun = store.begin(a);
  EXPECT_FALSE(begun.ok());
  EXPECT_NE(begun.error().find("locked"), std::string::npos) << begun.error();
  EXPECT_TRUE(fs::exists(a.file));
  sqlite3_exec(other, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(other);
  finishWithOutcome(store, a);  // the row is added when the database is free again
  auto rows = store.list();
  ASSERT_TRUE(rows.ok());
  ASSERT_EQ(rows->size(), 1u);
  EXPECT_TRUE((*rows)[0].complete);
}

TEST(Sessions, AFolderThatCannotBeMadeIsAClearError) {
  const fs::path dir = testing::testDir("Sessions");
  std::ofstream(dir / "a_file") << "x";
  SessionStore store((dir / "a_file" / "data").string());
  const Status opened = store.open();
  ASSERT_FALSE(opened.ok());
  EXPECT_NE(opened.error().find("cannot create the session folder"), std::string::npos) << opened.error();
  SessionRecord a = sample("Ann");
  const Status begun = store.begin(a);
  ASSERT_FALSE(begun.ok());
  EXPECT_NE(begun.error().find("a_file"), std::string::npos) << begun.error();
}

TEST(Sessions, ExportQuotesTextAndKeepsEverySession) {
  SessionRecord a = sample("Smith, \"Jo\"");
  a.id = 7;
  a.started_utc = "2026-11-29T12:00:00Z";
  a.complete = true;
  a.score = 72.5;
  const std::string csv = sessionsCsv({a, sample("Ben")});
  EXPECT_EQ(csv.rfind("id,trainee,case,", 0), 0u);
  EXPECT_NE(csv.find("7,\"Smith, \"\"Jo\"\"\",default,hands-on,2026-11-29T12:00:00Z,1,"), std::string::npos) << csv;
  const nlohmann::json j = nlohmann::json::parse(sessionsJson({a}));
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["trainee"], "Smith, \"Jo\"");
  EXPECT_EQ(j[0]["score"], 72.5);
}

TEST(SessionsCli, RunAsTraineeThenListAndExport) {
  const std::string data = testing::freshOutputDir("SessionsCli", "run");
  const auto run = testing::runHysim("run --steps 300 --quiet --trainee Ann --data-dir " + data);
  ASSERT_EQ(run.exit_code, 0) << run.text;
  const auto list = testing::runHysim("sessions --data-dir " + data + " list");
  ASSERT_EQ(list.exit_code, 0) << list.text;
  EXPECT_NE(list.text.find("Ann"), std::string::npos) << list.text;
  EXPECT_NE(list.text.find("complete"), std::string::npos) << list.text;
  const auto json = testing::runHysim("sessions --data-dir " + data + " export --json");
  ASSERT_EQ(json.exit_code, 0) << json.text;
  const nlohmann::json j = nlohmann::json::parse(json.text);
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["case"], "default");
  EXPECT_EQ(j[0]["mode"], "demo");
  EXPECT_NEAR(j[0]["duration_s"].get<double>(), 0.3, 1e-9);
  EXPECT_TRUE(j[0]["complete"].get<bool>());
  // The options go before or after the subcommand.
  const auto other = testing::runHysim("sessions list --data-dir " + data + " --trainee Nobody");
  ASSERT_EQ(other.exit_code, 0) << other.text;
  EXPECT_EQ(other.text.find("Ann"), std::string::npos) << other.text;
  const auto both = testing::runHysim("sessions --data-dir " + data + " export --csv --json");
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_NE(both.text.find("exactly one of --csv and --json"), std::string::npos) << both.text;
}

// A run killed mid-session (SIGKILL: no chance to clean up) shows as incomplete, file and row.
TEST(SessionsCli, KilledRunIsListedIncomplete) {
  const std::string data = testing::freshOutputDir("SessionsCli", "killed");
  const pid_t pid = testing::spawnHysim({"run", "--quiet", "--trainee", "Bob", "--data-dir", data});
  ASSERT_GT(pid, 0);
  const fs::path sessions = fs::path(data) / "sessions";
  const bool begun = testing::waitForFileEndingIn(sessions, ".json");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  kill(pid, SIGKILL);
  const int status = testing::waitStatus(pid);
  ASSERT_TRUE(begun) << "no session file appeared";
  ASSERT_EQ(status, 128 + SIGKILL) << "the run ended before it was killed";
  const auto list = testing::runHysim("sessions --data-dir " + data + " list");
  ASSERT_EQ(list.exit_code, 0) << list.text;
  EXPECT_NE(list.text.find("Bob"), std::string::npos) << list.text;
  EXPECT_NE(list.text.find("INCOMPLETE"), std::string::npos) << list.text;
  for (const auto& e : fs::directory_iterator(sessions)) {
    EXPECT_EQ(e.path().extension(), ".json") << "left behind: " << e.path();
    EXPECT_TRUE(readSessionFile(e.path().string()).ok());
  }
}

}  // namespace
}  // namespace hysim::tools
