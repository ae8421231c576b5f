#pragma once
// Render tests skip where no headless EGL display exists, so that the suite runs on any
// machine; but a skip there also hides a broken EGL set-up. Where HYSIM_REQUIRE_GL=1 (CI on
// a machine whose EGL works, see .ci/run), a missing renderer fails the test instead.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace hysim::testing {

inline bool glRequired() {
  const char* value = std::getenv("HYSIM_REQUIRE_GL");
  return value != nullptr && std::string(value) == "1";
}

}  // namespace hysim::testing

// Ends the test: a failure when HYSIM_REQUIRE_GL=1, else a skip; `reason` is streamed.
// Use it inside braces (its if/else must not meet an outer else).
#define HYSIM_SKIP_OR_FAIL_WITHOUT_GL(reason)                                                 \
  if (::hysim::testing::glRequired()) {                                                        \
    FAIL() << reason << " (HYSIM_REQUIRE_GL=1: a missing EGL fails instead of skipping)";     \
  } else                                                                                       \
    GTEST_SKIP() << reason
