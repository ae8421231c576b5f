#pragma once
// A folder of the running test's own under HYSIM_TEST_OUTPUT_DIR/<suite>/<test name>, for
// the files it writes: ctest runs the tests side by side as separate processes, and in a
// shared folder one could read a file (a mesh, a scene) while another is rewriting it.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace hysim::testing {

inline std::filesystem::path testDir(const std::string& suite) {
  const std::filesystem::path dir = std::filesystem::path(HYSIM_TEST_OUTPUT_DIR) / suite /
                                    ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace hysim::testing
