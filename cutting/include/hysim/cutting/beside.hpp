#pragma once
// Work beside: how a caller lends cut3d, the optimisation and the tissue update a second
// thread (engine::PassWorker::lend() in the simulator), and the guard that waits for a job.
#include <functional>
#include <utility>

namespace hysim::cutting {

// Starts a job on another thread and returns what waits for it. Empty: no thread lent.
using Beside = std::function<std::function<void()>(std::function<void()>)>;

// A job handed to `beside` (run here at once where it is empty), waited for by join() before
// its results are read, and at the latest by the destructor, on every way out: declared after
// everything the job uses, it is waited for before any of that goes.
class LentJob {
 public:
  LentJob(const Beside& beside, const std::function<void()>& job) {
    if (beside) {
      wait_ = beside(job);
    } else {
      job();
    }
  }
  LentJob(const LentJob&) = delete;
  LentJob& operator=(const LentJob&) = delete;
  ~LentJob() { join(); }
  void join() {
    if (wait_) {
      const std::function<void()> wait = std::move(wait_);
      wait_ = nullptr;
      wait();
    }
  }

 private:
  std::function<void()> wait_;
};

}  // namespace hysim::cutting
