#pragma once
// Starts the hysim binary in the background (from the source tree root, output discarded), for
// tests that signal or kill a run midway.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace hysim::testing {

inline pid_t spawnHysim(const std::vector<std::string>& args) {
  std::vector<std::string> argv_text{HYSIM_BINARY};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, 1);
    dup2(null, 2);
    if (chdir(HYSIM_SOURCE_DIR) != 0) _exit(126);
    execv(HYSIM_BINARY, argv.data());
    _exit(127);
  }
  return pid;
}

// Waits for the process; its exit status, or 128 + the signal that ended it.
inline int waitStatus(pid_t pid) {
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Waits (at most 60 s) until `dir` holds a file ending in `extension` (a run's session file,
// not only its temporary): the run has got that far.
inline bool waitForFileEndingIn(const std::filesystem::path& dir, const std::string& extension) {
  for (int i = 0; i < 600; ++i) {
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec))
      if (e.path().extension() == extension) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

}  // namespace hysim::testing
