#include "hysim/engine/cut_worker.hpp"

#include <pthread.h>

#include <utility>

namespace hysim::engine {

CutWorker::CutWorker() : thread_([this] { loop(); }) { pthread_setname_np(thread_.native_handle(), "hysim-cut"); }

CutWorker::~CutWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void CutWorker::start(std::function<void()> job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = std::move(job);
    busy_ = true;
  }
  wake_.notify_one();
}

bool CutWorker::done() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return !busy_;
}

void CutWorker::wait() {
  std::unique_lock<std::mutex> lock(mutex_);
  finished_.wait(lock, [this] { return !busy_; });
}

void CutWorker::setDelayForTesting(std::function<void()> delay) {
  std::lock_guard<std::mutex> lock(mutex_);
  delay_ = std::move(delay);
}

void CutWorker::loop() {
  for (;;) {
    std::function<void()> job, delay;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return quit_ || job_; });
      if (!job_) return;  // quit with nothing in hand
      job = std::move(job_);
      job_ = nullptr;
      delay = delay_;
    }
    if (delay) delay();
    job();
    job = nullptr;  // what it captured goes here, not on the simulation thread
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    finished_.notify_all();
  }
}

}  // namespace hysim::engine
