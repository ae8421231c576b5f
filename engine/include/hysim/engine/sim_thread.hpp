#pragma once
// The simulation thread ("hysim-sim"): steps a Simulation paced to real time, so that drawing
// a frame (slow on a software GL) never slows the simulation down. Everything else that reads
// or changes the simulation (input, snapshots, the panel) does so inside access(), which runs
// between two steps under the thread's lock.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

#include "hysim/engine/pacer.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/engine/step_times.hpp"

namespace hysim::engine {

// How the pacing went since the simulation was attached (read inside access()).
struct PaceStats {
  long long steps = 0;          // steps done
  double sim_s = 0.0;           // simulated time stepped
  double wall_s = 0.0;          // wall time running (not paused)
  double realtime = 0.0;        // simulated seconds per wall second over the last second
  double behind_s = 0.0;        // simulated time given up because the machine could not keep up
  double step_median_us = 0.0;  // over the last StepTimes::kWindow steps
  // The machine did not keep up: more than kBehindLimitS was given up. Stays set.
  bool cannot_keep_up = false;
  static constexpr double kBehindLimitS = 0.25;
};

class SimThread {
 public:
  using AfterStep = std::function<void(Simulation&)>;
  SimThread();
  ~SimThread();  // stops the thread (between steps)
  SimThread(const SimThread&) = delete;
  SimThread& operator=(const SimThread&) = delete;

  // What to step from now on (null: nothing) and what to call after each step; the pacing and
  // its statistics start anew. Not from inside access().
  void attach(Simulation* sim, AfterStep after_step = {});
  // Runs f() between two steps, with the simulation left alone until it returns.
  template <class F>
  decltype(auto) access(F&& f) {
    waiting_.store(true, std::memory_order_release);
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_.store(false, std::memory_order_release);
    return std::forward<F>(f)();
  }
  // Inside access() or the after-step call: pause (time does not run; from the after-step call
  // no further step is taken) and speed (simulated seconds per wall second).
  void setPaused(bool paused) { paused_ = paused; }
  void setSpeed(double speed) { speed_ = speed; }
  const PaceStats& stats() const { return stats_; }  // inside access()

 private:
  using Clock = std::chrono::steady_clock;
  void loop();
  void stepDue(std::unique_lock<std::mutex>& lock, int due);
  void updateRealtime(Clock::time_point now);
  void sleepUntilDue(std::unique_lock<std::mutex>& lock);

  std::mutex mutex_;  // guards everything below and the attached simulation
  std::condition_variable wake_;
  std::atomic<bool> waiting_{false};  // access() wants the lock: the stepping yields it
  Simulation* sim_ = nullptr;
  AfterStep after_step_;
  Pacer pacer_;
  StepTimes step_times_;
  PaceStats stats_;
  bool paused_ = false;
  double speed_ = 1.0;
  bool quit_ = false;
  Clock::time_point last_;                     // the pacing's last look at the clock
  Clock::time_point window_start_;             // the real-time factor's window
  double window_sim_start_ = 0.0;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace hysim::engine
