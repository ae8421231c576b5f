#pragma once
// The cut worker: one named thread ("hysim-cut") that runs whole jobs, one at a time, next to
// the simulation thread. The simulation hands it a shaving pass's cut and collects the
// result at a fixed later step; nothing it computes depends on when it runs.
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace hysim::engine {

class CutWorker {
 public:
  CutWorker();
  ~CutWorker();  // waits for the job in hand
  CutWorker(const CutWorker&) = delete;
  CutWorker& operator=(const CutWorker&) = delete;

  // Starts job on the worker. The previous job must be done (wait() first).
  void start(std::function<void()> job);
  bool done() const;  // no job in hand
  void wait();        // blocks until no job is in hand
  // Testing: called on the worker before each job (e.g. a random sleep), to show that the
  // simulation's results do not depend on the worker's timing.
  void setDelayForTesting(std::function<void()> delay);

 private:
  void loop();
  mutable std::mutex mutex_;
  std::condition_variable wake_, finished_;
  std::function<void()> job_;    // under mutex_
  std::function<void()> delay_;  // under mutex_
  bool busy_ = false;            // under mutex_: a job was started and has not finished
  bool quit_ = false;            // under mutex_
  std::thread thread_;           // last: starts once the members above exist
};

}  // namespace hysim::engine
