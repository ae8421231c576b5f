#pragma once
// The haptic thread: at a fixed rate (1 kHz by default) it reads the device, publishes the
// device state for the simulation, evaluates the newest local force model the simulation
// published, passes the force through the watchdog and ForceSafety and commands the device.
// The simulation and the app talk to it only through lock-free mailboxes and atomics.
#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>

#include "hysim/haptics/clock.hpp"
#include "hysim/haptics/device.hpp"
#include "hysim/haptics/duration_histogram.hpp"
#include "hysim/haptics/force_safety.hpp"
#include "hysim/haptics/latest_value.hpp"
#include "hysim/haptics/local_force_model.hpp"
#include "hysim/haptics/model_watchdog.hpp"

namespace hysim::haptics {

struct HapticLoopOptions {
  double rate_hz = 1000.0;
  double start_time_s = 0.0;         // device time at the first tick
  double watchdog_s = 0.05;          // no new model for this long: F0 fades out ...
  double fade_s = 0.01;              // ... over this long
  int resync_after_periods = 3;      // later than this: skip to the schedule, don't burst
  bool limit_model_to_device = true; // limitToDevice() on each new model
  int realtime_priority = 40;        // SCHED_FIFO priority asked for (1..99); 0 = don't ask
  ForceSafetyOptions safety;         // max_force_n is further capped by the device's own
};

struct HapticStats {
  long ticks = 0;
  long overruns = 0;       // periods longer than 1.5x nominal
  long resyncs = 0;        // times the schedule skipped ahead after a long overrun
  long ticks_clamped = 0;  // ForceSafety's magnitude clamp was active
  long faults = 0;
  double period_p50_us = 0, period_p99_us = 0, period_max_us = 0;  // between tick starts
  double tick_p50_us = 0, tick_p99_us = 0, tick_max_us = 0;        // tick() durations (scheduled runs)
};

class HapticLoop {
 public:
  explicit HapticLoop(std::unique_ptr<Device> device, HapticLoopOptions options = {});  // SteadyClock
  HapticLoop(std::unique_ptr<Device> device, std::unique_ptr<Clock> clock, HapticLoopOptions options = {});
  HapticLoop(std::unique_ptr<Device> device, Clock& clock, HapticLoopOptions options = {});
  ~HapticLoop();
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;

  // Spawns the "hysim-haptic" thread ticking at t0 + k * period; stop() joins it.
  void start();
  void stop();
  bool running() const { return thread_.joinable(); }
  // Runs `count` scheduled ticks on the calling thread (same schedule as the thread; for
  // tests with a FakeClock). Only while not running.
  void runTicks(long count);
  // One tick at time now_ns. Only from the haptic thread, or while not running.
  void tick(std::int64_t now_ns);

  // Simulation thread (the one writer): the model for the ticks that follow. Each new model
  // needs a new step value (>= 0); the watchdog counts only those.
  void publishModel(const LocalForceModel& model) { models_.publish(model); }
  // One reader thread (the simulation): the newest device state; false before the first tick.
  bool latestState(DeviceState& state) { return states_.read(state); }

  // Any thread; take effect at the next tick (within one period). An e-stop requested
  // together with a reset wins.
  void eStop() { estop_request_.store(true); }
  void resetSafety() { reset_request_.store(true); }
  SafetyState safetyState() const { return safety_state_.load(); }
  FaultReason faultReason() const { return fault_reason_.load(); }
  HapticStats stats() const;  // any thread; allocates (not for the haptic thread)
  bool realtime() const { return realtime_.load(); }
  // The watchdog's scale of F0 at the last tick (1: models arrive; 0: faded out). Any thread.
  double f0Scale() const { return f0_scale_.load(std::memory_order_relaxed); }

  // Only while not running.
  Device& device() { return *device_; }
  std::int64_t periodNs() const { return period_ns_; }

 private:
  void threadMain();
  void runScheduled(long max_ticks);
  void applyRequests();
  void recordPeriod(std::int64_t now_ns);
  bool takeNewModel();
  void publishSafety();

  std::unique_ptr<Device> device_;
  std::unique_ptr<Clock> owned_clock_;
  Clock& clock_;
  HapticLoopOptions options_;
  std::int64_t period_ns_;
  ForceSafety safety_;
  ModelWatchdog watchdog_;
  LatestValue<DeviceState> states_;
  LatestValue<LocalForceModel> models_;

  // Haptic thread only.
  LocalForceModel incoming_;
  LocalForceModel model_;
  bool ticked_ = false;
  bool measure_period_ = false;  // false at the first tick of a run
  std::int64_t first_tick_ns_ = 0;
  std::int64_t last_tick_ns_ = 0;

  // Shared with other threads.
  std::atomic<bool> stop_request_{false};
  std::atomic<bool> estop_request_{false};
  std::atomic<bool> reset_request_{false};
  std::atomic<bool> realtime_{false};
  std::atomic<SafetyState> safety_state_{SafetyState::WaitingForSmall};
  std::atomic<FaultReason> fault_reason_{FaultReason::None};
  std::atomic<double> f0_scale_{1.0};
  std::atomic<long> ticks_{0};
  std::atomic<long> overruns_{0};
  std::atomic<long> resyncs_{0};
  std::atomic<long> ticks_clamped_{0};
  std::atomic<long> faults_{0};
  DurationHistogram periods_;
  DurationHistogram tick_durations_;
  std::thread thread_;
};

}  // namespace hysim::haptics
