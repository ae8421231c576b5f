#pragma once
// A "latest value" mailbox between exactly one writer thread and one reader thread, without
// locks: triple buffering. The writer fills a private slot and swaps it into the shared
// "middle" index with one atomic exchange (setting the fresh bit); the reader, when the fresh
// bit is set, swaps its own slot for the middle one. Each slot is only ever touched by the
// thread that holds its index, and the exchanges order the copies (release/acquire), so the
// scheme is free of data races (clean under ThreadSanitizer), never blocks and allocates
// nothing beyond T's copy assignment.
#include <array>
#include <atomic>

namespace hysim::haptics {

template <class T>
class LatestValue {
 public:
  // Writer thread only: makes `value` the newest value.
  void publish(const T& value) {
    slots_[back_] = value;
    back_ = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel) & kIndex;
  }

  // Reader thread only: copies the newest completely published value into `out`; returns
  // false (and leaves `out` alone) while nothing was ever published.
  bool read(T& out) {
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      // Only the reader clears the fresh bit, so the exchange still takes a fresh slot.
      front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
      has_value_ = true;
    }
    if (!has_value_) return false;
    out = slots_[front_];
    return true;
  }

 private:
  static constexpr int kIndex = 0x3;
  static constexpr int kFresh = 0x4;

  std::array<T, 3> slots_{};
  int back_ = 0;            // writer's slot
  alignas(64) std::atomic<int> middle_{1};  // handed over; plus the fresh bit
  alignas(64) int front_ = 2;               // reader's slot
  bool has_value_ = false;                  // reader's
};

}  // namespace hysim::haptics
