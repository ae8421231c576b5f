#include "hysim/haptics/haptic_loop.hpp"

#include <algorithm>
#include <cmath>

#include "thread_setup.hpp"

namespace hysim::haptics {

namespace {

ForceSafetyOptions cappedSafety(ForceSafetyOptions safety, const Device& device) {
  safety.max_force_n = std::min(safety.max_force_n, device.info().max_force_n);
  return safety;
}

// Single-writer counter: a load and a store, no read-modify-write on the haptic thread.
void bump(std::atomic<long>& counter, long by = 1) {
  counter.store(counter.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}

}  // namespace

HapticLoop::HapticLoop(std::unique_ptr<Device> device, HapticLoopOptions options)
    : HapticLoop(std::move(device), std::make_unique<SteadyClock>(), options) {}

HapticLoop::HapticLoop(std::unique_ptr<Device> device, std::unique_ptr<Clock> clock, HapticLoopOptions options)
    : HapticLoop(std::move(device), *clock, options) {
  owned_clock_ = std::move(clock);
}

HapticLoop::HapticLoop(std::unique_ptr<Device> device, Clock& clock, HapticLoopOptions options)
    : device_(std::move(device)),
      clock_(clock),
      options_(options),
      period_ns_(std::max<std::int64_t>(std::llround(1e9 / options.rate_hz), 1)),
      safety_(cappedSafety(options.safety, *device_)),
      watchdog_(options.watchdog_s, options.fade_s) {}

HapticLoop::~HapticLoop() { stop(); }

void HapticLoop::start() {
  if (running()) return;
  stop_request_.store(false);
  thread_ = std::thread([this] { threadMain(); });
}

void HapticLoop::stop() {
  if (!running()) return;
  stop_request_.store(true);
  thread_.join();
}

void HapticLoop::threadMain() {
  detail::nameThisThread("hysim-haptic");
  if (options_.realtime_priority > 0) realtime_.store(detail::tryRealtimePriority(options_.realtime_priority));
  runScheduled(-1);
}

void HapticLoop::runTicks(long count) {
  if (!running()) runScheduled(count);
}

// Ticks at absolute times t0 + k * period, so sleeps never accumulate drift. A tick that runs
// late is caught up at once while the backlog is short; past resync_after_periods the
// schedule jumps to its next slot instead of bursting through the missed ones.
void HapticLoop::runScheduled(long max_ticks) {
  measure_period_ = false;  // the pause before this run is no period
  std::int64_t next_ns = clock_.nowNs();
  const std::int64_t resync_ns = options_.resync_after_periods * period_ns_;
  for (long k = 0; (max_ticks < 0 || k < max_ticks) && !stop_request_.load(std::memory_order_relaxed); ++k) {
    clock_.sleepUntilNs(next_ns);
    const std::int64_t start_ns = clock_.nowNs();
    tick(start_ns);
    const std::int64_t end_ns = clock_.nowNs();
    tick_durations_.add(end_ns - start_ns);
    next_ns += period_ns_;
    if (end_ns - next_ns > resync_ns) {
      next_ns += ((end_ns - next_ns) / period_ns_ + 1) * period_ns_;
      bump(resyncs_);
    }
  }
}

void HapticLoop::tick(std::int64_t now_ns) {
  applyRequests();
  recordPeriod(now_ns);
  const double time_s = options_.start_time_s + 1e-9 * static_cast<double>(now_ns - first_tick_ns_);
  const DeviceState state = device_->read(time_s);
  states_.publish(state);
  const double f0_scale = watchdog_.update(takeNewModel(), now_ns);
  f0_scale_.store(f0_scale, std::memory_order_relaxed);
  const Eigen::Vector3d command_n = model_.force(state.pose.tip, state.velocity_mm_s, f0_scale);
  device_->commandForce(safety_.filter(command_n, now_ns));
  publishSafety();
  bump(ticks_);
}

void HapticLoop::applyRequests() {
  if (reset_request_.exchange(false)) safety_.reset();
  if (estop_request_.exchange(false)) safety_.eStop();
}

void HapticLoop::recordPeriod(std::int64_t now_ns) {
  if (!ticked_) {
    ticked_ = true;
    first_tick_ns_ = now_ns;
  } else if (measure_period_) {
    const std::int64_t period_ns = now_ns - last_tick_ns_;
    periods_.add(period_ns);
    if (2 * period_ns > 3 * period_ns_) bump(overruns_);
  }
  measure_period_ = true;
  last_tick_ns_ = now_ns;
}

// Takes the newest published model; true when it carries a step not seen before.
bool HapticLoop::takeNewModel() {
  if (!models_.read(incoming_) || incoming_.step == model_.step) return false;
  model_ = options_.limit_model_to_device
               ? limitToDevice(incoming_, device_->info(), 1e-9 * static_cast<double>(period_ns_))
               : incoming_;
  return true;
}

void HapticLoop::publishSafety() {
  safety_state_.store(safety_.state(), std::memory_order_relaxed);
  fault_reason_.store(safety_.faultReason(), std::memory_order_relaxed);
  ticks_clamped_.store(safety_.ticksClamped(), std::memory_order_relaxed);
  faults_.store(safety_.faults(), std::memory_order_relaxed);
}

HapticStats HapticLoop::stats() const {
  HapticStats s;
  s.ticks = ticks_.load(std::memory_order_relaxed);
  s.overruns = overruns_.load(std::memory_order_relaxed);
  s.resyncs = resyncs_.load(std::memory_order_relaxed);
  s.ticks_clamped = ticks_clamped_.load(std::memory_order_relaxed);
  s.faults = faults_.load(std::memory_order_relaxed);
  const DurationSummary period = periods_.summary();
  s.period_p50_us = period.p50_us;
  s.period_p99_us = period.p99_us;
  s.period_max_us = period.max_us;
  const DurationSummary tick = tick_durations_.summary();
  s.tick_p50_us = tick.p50_us;
  s.tick_p99_us = tick.p99_us;
  s.tick_max_us = tick.max_us;
  return s;
}

}  // namespace hysim::haptics
