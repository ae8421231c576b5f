#pragma once
// The time source of the haptic loop, so tests can drive the loop's schedule without waiting.
#include <atomic>
#include <cstdint>

namespace hysim::haptics {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t nowNs() = 0;
  // Returns at (or after) the absolute time t_ns; returns at once when t_ns has passed.
  virtual void sleepUntilNs(std::int64_t t_ns) = 0;
};

// CLOCK_MONOTONIC with absolute-time sleeps, so a loop's deadlines never drift.
class SteadyClock final : public Clock {
 public:
  std::int64_t nowNs() override;
  void sleepUntilNs(std::int64_t t_ns) override;
};

// Time that moves only when told: sleepUntilNs jumps to the target (plus an injected
// lateness, to test overruns). Its members may be called from any thread.
class FakeClock final : public Clock {
 public:
  explicit FakeClock(std::int64_t start_ns = 0) : now_ns_(start_ns) {}

  std::int64_t nowNs() override { return now_ns_.load(); }
  void sleepUntilNs(std::int64_t t_ns) override;

  void setNowNs(std::int64_t t_ns) { now_ns_.store(t_ns); }
  void advanceNs(std::int64_t dt_ns) { now_ns_.fetch_add(dt_ns); }
  // The sleep after the next `after_sleeps` sleeps wakes late_ns late (one at a time).
  void injectLatenessNs(std::int64_t late_ns, std::int64_t after_sleeps = 0);
  std::int64_t sleeps() const { return sleeps_.load(); }

 private:
  std::atomic<std::int64_t> now_ns_;
  std::atomic<std::int64_t> sleeps_{0};
  std::atomic<std::int64_t> late_ns_{0};
  std::atomic<std::int64_t> late_on_sleep_{-1};  // index of the late sleep; -1 = none
};

}  // namespace hysim::haptics
