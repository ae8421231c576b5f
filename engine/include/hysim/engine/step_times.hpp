#pragma once
// The median of the last kWindow step times, without allocating per step.
#include <algorithm>
#include <array>

namespace hysim::engine {

class StepTimes {
 public:
  static constexpr int kWindow = 100;
  void add(double us) {
    ring_[next_] = us;
    next_ = (next_ + 1) % kWindow;
    count_ = std::min(count_ + 1, kWindow);
  }
  double median() const {
    if (count_ == 0) return 0.0;
    std::array<double, kWindow> scratch;
    std::copy(ring_.begin(), ring_.begin() + count_, scratch.begin());
    auto mid = scratch.begin() + count_ / 2;
    std::nth_element(scratch.begin(), mid, scratch.begin() + count_);
    return *mid;
  }
  void clear() { count_ = next_ = 0; }

 private:
  std::array<double, kWindow> ring_{};
  int count_ = 0;
  int next_ = 0;
};

}  // namespace hysim::engine
