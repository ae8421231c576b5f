#include "hysim/engine/sim_thread.hpp"

#include <pthread.h>

#include <algorithm>

namespace hysim::engine {

namespace {
double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }
}  // namespace

SimThread::SimThread() : last_(Clock::now()), thread_([this] { loop(); }) {
  pthread_setname_np(thread_.native_handle(), "hysim-sim");
}

SimThread::~SimThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void SimThread::attach(Simulation* sim, AfterStep after_step) {
  {
    waiting_.store(true, std::memory_order_release);
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_.store(false, std::memory_order_release);
    sim_ = sim;
    after_step_ = std::move(after_step);
    pacer_ = Pacer(sim != nullptr ? sim->scene().sim.dt : 1e-3);
    step_times_.clear();
    stats_ = PaceStats{};
    last_ = window_start_ = Clock::now();
    window_sim_start_ = sim != nullptr ? sim->state().time : 0.0;
  }
  wake_.notify_one();
}

void SimThread::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!quit_) {
    const Clock::time_point now = Clock::now();
    const double elapsed = seconds(now - last_);
    last_ = now;
    if (sim_ == nullptr || paused_) {  // time does not run; the factor's window starts on resuming
      pacer_.clearDue();
      window_start_ = now;
      window_sim_start_ = sim_ != nullptr ? sim_->state().time : 0.0;
      wake_.wait_for(lock, std::chrono::milliseconds(5));
      continue;
    }
    stats_.wall_s += elapsed;
    stepDue(lock, pacer_.due(elapsed, speed_));
    updateRealtime(now);
    stats_.behind_s = pacer_.behindS();
    stats_.cannot_keep_up = stats_.cannot_keep_up || stats_.behind_s > PaceStats::kBehindLimitS;
    sleepUntilDue(lock);
  }
}

// The steps due, each followed by the after-step call. access() gets the lock between two
// steps; if it changed what is stepped (a reset, a pause), the rest is dropped.
void SimThread::stepDue(std::unique_lock<std::mutex>& lock, int due) {
  Simulation* const sim = sim_;
  for (int i = 0; i < due; ++i) {
    if (waiting_.load(std::memory_order_acquire)) {
      lock.unlock();
      while (waiting_.load(std::memory_order_acquire)) std::this_thread::yield();
      lock.lock();
      if (quit_ || sim_ != sim || paused_) return;
    }
    const Clock::time_point t0 = Clock::now();
    sim->step();
    step_times_.add(1e6 * seconds(Clock::now() - t0));
    ++stats_.steps;
    stats_.sim_s += pacer_.dt();
    if (after_step_) after_step_(*sim);
    if (paused_) break;  // the after-step call paused it (e.g. a replay at its end)
  }
  stats_.step_median_us = step_times_.median();
}

void SimThread::updateRealtime(Clock::time_point now) {
  const double window_s = seconds(now - window_start_);
  if (window_s < 1.0 || sim_ == nullptr) return;
  stats_.realtime = (sim_->state().time - window_sim_start_) / window_s;
  window_start_ = now;
  window_sim_start_ = sim_->state().time;
}

void SimThread::sleepUntilDue(std::unique_lock<std::mutex>& lock) {
  const double wait_s = pacer_.untilNextStep() / std::max(speed_, 1e-3);
  if (wait_s <= 0.0 || quit_) return;
  wake_.wait_for(lock, std::chrono::duration<double>(wait_s));
}

}  // namespace hysim::engine
