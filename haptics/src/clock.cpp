#include "hysim/haptics/clock.hpp"

#include <cerrno>
#include <ctime>

namespace hysim::haptics {

namespace {
constexpr std::int64_t kNsPerS = 1'000'000'000;
}

std::int64_t SteadyClock::nowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

void SteadyClock::sleepUntilNs(std::int64_t t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / kNsPerS);
  ts.tv_nsec = static_cast<long>(t_ns % kNsPerS);
  // A signal interrupts the sleep; the absolute deadline makes restarting it exact.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

void FakeClock::sleepUntilNs(std::int64_t t_ns) {
  const std::int64_t index = sleeps_.fetch_add(1);
  std::int64_t wake_ns = t_ns > now_ns_.load() ? t_ns : now_ns_.load();
  if (index == late_on_sleep_.load()) wake_ns += late_ns_.load();
  now_ns_.store(wake_ns);
}

void FakeClock::injectLatenessNs(std::int64_t late_ns, std::int64_t after_sleeps) {
  late_ns_.store(late_ns);
  late_on_sleep_.store(sleeps_.load() + after_sleeps);
}

}  // namespace hysim::haptics
