#pragma once
// Runs the hysim binary as a user would (from the source tree root) and captures its output.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

namespace hysim::testing {

struct Output {
  int exit_code = -1;
  std::string text;  // stdout and stderr
};

// `prefix` runs before the binary (e.g. "taskset -c 0").
inline Output runHysim(const std::string& args, const std::string& prefix = "") {
  Output out;
  const std::string cmd = std::string("cd ") + HYSIM_SOURCE_DIR + " && " + prefix + " " + HYSIM_BINARY + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return out;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.text.append(buf.data(), n);
  const int status = pclose(pipe);
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

// An empty folder under the test output folder.
inline std::string freshOutputDir(const std::string& group, const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(HYSIM_TEST_OUTPUT_DIR) / group / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

}  // namespace hysim::testing
