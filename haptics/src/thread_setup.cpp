#include "thread_setup.hpp"

#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <cstdio>
#include <cstring>

namespace hysim::haptics::detail {

void nameThisThread(const char* name) {
  char truncated[16] = {};
  std::strncpy(truncated, name, sizeof(truncated) - 1);
  pthread_setname_np(pthread_self(), truncated);
}

bool tryRealtimePriority(int priority) {
  sched_param param{};
  param.sched_priority = priority;
  const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (error == 0) return true;
  static std::atomic<bool> warned{false};
  if (!warned.exchange(true)) {
    std::fprintf(stderr, "hysim: haptic thread runs without real-time priority (SCHED_FIFO refused: %s)\n",
                 std::strerror(error));
  }
  return false;
}

}  // namespace hysim::haptics::detail
