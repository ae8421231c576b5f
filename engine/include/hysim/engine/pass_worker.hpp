#pragma once
// A second thread for short bursts of work (the simulator's passes; the 3D cut benchmark).
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

#include "hysim/cutting/beside.hpp"

namespace hysim::engine {

// The second thread of the passes. It sleeps between passes; begin() wakes it as a pass
// starts and it spins until end(), so that it is running when the pass's jobs come (a thread
// started or woken at that moment takes 0.2-0.3 ms to run on this kind of machine, the jobs
// it takes over 0.3-0.8 ms; starting one costs the poster ~0.1 ms). Jobs run in the order
// posted; the poster waits for one by spinning too. Every posted job must be waited for
// before what it uses goes out of scope, and before end().
class PassWorker {
 public:
  PassWorker() : thread_([this] { loop(); }) {}
  PassWorker(const PassWorker&) = delete;
  PassWorker& operator=(const PassWorker&) = delete;
  ~PassWorker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    wake_.notify_one();
    thread_.join();
  }
  void begin() {
    lent_.clear();  // (every job lent before was waited for)
    {
      std::lock_guard<std::mutex> lock(mutex_);
      awake_.store(true, std::memory_order_release);
    }
    wake_.notify_one();
  }
  void end() { awake_.store(false, std::memory_order_release); }
  // A Cut3DOptions::beside that runs each job on the worker (kept here until the next
  // begin(); the caller waits for each, as cut3d does, before end()).
  cutting::Beside lend() {
    return [this](std::function<void()> job) -> std::function<void()> {
      lent_.push_back(std::move(job));
      const std::int64_t ticket = post(lent_.back());
      return [this, ticket] { wait(ticket); };
    };
  }
  // Runs job() on the worker; returns the ticket to wait for.
  template <class F>
  std::int64_t post(F& job) {
    const std::int64_t ticket = posted_.load(std::memory_order_relaxed);
    if (ticket - done_.load(std::memory_order_acquire) >= kMaxJobs) {  // not reached (a pass has at most two outstanding)
      job();
      return -1;
    }
    jobs_[ticket % kMaxJobs] = {[](void* f) { (*static_cast<F*>(f))(); }, &job};
    posted_.store(ticket + 1, std::memory_order_release);
    return ticket;
  }
  void wait(std::int64_t ticket) const {
    for (unsigned spins = 0; done_.load(std::memory_order_acquire) <= ticket;) pause(++spins);
  }

 private:
  // A spin-wait step; every 64th gives the core to any other thread that wants it, so that a
  // spinning thread slows nobody down much on a busy machine.
  static void pause(unsigned spins) {
    if (spins % 64 == 0) {
      std::this_thread::yield();
      return;
    }
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }
  void loop() {
    std::int64_t next = 0;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [this] { return quit_ || awake_.load(std::memory_order_acquire); });
        if (quit_) return;
      }
      for (unsigned spins = 0;;) {  // awake: run jobs as they come, until end() with none left
        if (posted_.load(std::memory_order_acquire) > next) {
          const Job& job = jobs_[next % kMaxJobs];
          job.run(job.job);
          done_.store(++next, std::memory_order_release);
        } else if (!awake_.load(std::memory_order_acquire)) {
          break;
        } else {
          pause(++spins);
        }
      }
    }
  }
  static constexpr int kMaxJobs = 4;
  struct Job {
    void (*run)(void*) = nullptr;
    void* job = nullptr;
  };
  std::array<Job, kMaxJobs> jobs_{};
  std::atomic<std::int64_t> posted_{0}, done_{0};
  std::atomic<bool> awake_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool quit_ = false;   // under mutex_
  std::deque<std::function<void()>> lent_;  // lend()'s jobs (a deque: they stay where they are)
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace hysim::engine
