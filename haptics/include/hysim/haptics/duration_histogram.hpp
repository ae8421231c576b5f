#pragma once
// A fixed-size histogram of durations (1 µs bins up to 20 ms by default, plus the exact
// maximum) that one thread fills without allocating or locking while any other thread reads
// percentiles from it. Bins are relaxed atomics: a reader may see a sample or two in flight,
// never a torn value.
#include <atomic>
#include <cstdint>
#include <memory>

namespace hysim::haptics {

struct DurationSummary {
  long count = 0;
  double p50_us = 0.0;  // bin lower edges: resolution one bin, rounded down
  double p99_us = 0.0;
  double max_us = 0.0;  // exact
};

class DurationHistogram {
 public:
  explicit DurationHistogram(std::int64_t bin_ns = 1000, std::int64_t range_ns = 20'000'000);

  // Writer thread only. Negative durations count as zero; longer ones than the range go to
  // the last bin (the percentiles then report at most the exact maximum).
  void add(std::int64_t duration_ns);
  // Any thread; allocates a copy of the bins (not for the writer's loop).
  DurationSummary summary() const;
  // Only while no thread adds.
  void clear();

 private:
  std::int64_t bin_ns_;
  std::int64_t num_bins_;
  std::unique_ptr<std::atomic<std::uint32_t>[]> bins_;
  std::atomic<std::int64_t> max_ns_{0};
};

}  // namespace hysim::haptics
