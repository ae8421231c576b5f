#pragma once
// A Cut3DOptions::beside for tests: each job on a thread of its own, joined by the waiter it
// returns. The threads stay in `threads` (a deque: they keep their place as it grows), so a
// test can count the jobs and check that every one was waited for.
#include <deque>
#include <functional>
#include <thread>

#include "hysim/cutting/beside.hpp"

namespace hysim::testing {

struct ThreadBeside {
  std::deque<std::thread> threads;
  cutting::Beside lend() {
    return [this](std::function<void()> job) -> std::function<void()> {
      threads.emplace_back(std::move(job));
      std::thread* t = &threads.back();
      return [t] { t->join(); };
    };
  }
  int jobs() const { return static_cast<int>(threads.size()); }
};

}  // namespace hysim::testing
