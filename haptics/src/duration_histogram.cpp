#include "hysim/haptics/duration_histogram.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace hysim::haptics {

DurationHistogram::DurationHistogram(std::int64_t bin_ns, std::int64_t range_ns)
    : bin_ns_(std::max<std::int64_t>(bin_ns, 1)),
      num_bins_(std::max<std::int64_t>(range_ns / bin_ns_, 1)),
      bins_(std::make_unique<std::atomic<std::uint32_t>[]>(static_cast<size_t>(num_bins_))) {}

void DurationHistogram::add(std::int64_t duration_ns) {
  const std::int64_t d = std::max<std::int64_t>(duration_ns, 0);
  const std::int64_t bin = std::min(d / bin_ns_, num_bins_ - 1);
  // Single writer: a load and a store suffice, no read-modify-write needed.
  std::atomic<std::uint32_t>& b = bins_[static_cast<size_t>(bin)];
  b.store(b.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  if (d > max_ns_.load(std::memory_order_relaxed)) max_ns_.store(d, std::memory_order_relaxed);
}

namespace {

// Lower edge of the bin holding the q-quantile of `counts` (total > 0).
std::int64_t quantileBin(const std::vector<std::uint32_t>& counts, long total, double q) {
  const long rank = std::max(1L, static_cast<long>(std::ceil(q * static_cast<double>(total))));
  long seen = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    seen += counts[i];
    if (seen >= rank) return static_cast<std::int64_t>(i);
  }
  return static_cast<std::int64_t>(counts.size()) - 1;
}

}  // namespace

DurationSummary DurationHistogram::summary() const {
  // Copy first so the percentiles come from one consistent set of counts.
  std::vector<std::uint32_t> counts(static_cast<size_t>(num_bins_));
  long total = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    counts[i] = bins_[i].load(std::memory_order_relaxed);
    total += counts[i];
  }
  DurationSummary s;
  s.count = total;
  if (total == 0) return s;
  const double max_us = 1e-3 * static_cast<double>(max_ns_.load(std::memory_order_relaxed));
  const double bin_us = 1e-3 * static_cast<double>(bin_ns_);
  s.max_us = max_us;
  s.p50_us = std::min(bin_us * static_cast<double>(quantileBin(counts, total, 0.50)), max_us);
  s.p99_us = std::min(bin_us * static_cast<double>(quantileBin(counts, total, 0.99)), max_us);
  return s;
}

void DurationHistogram::clear() {
  for (std::int64_t i = 0; i < num_bins_; ++i) bins_[static_cast<size_t>(i)].store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
}

}  // namespace hysim::haptics
