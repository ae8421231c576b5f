#include <gtest/gtest.h>

#include "hysim/haptics/duration_histogram.hpp"

namespace hysim::haptics {
namespace {

TEST(DurationHistogram, EmptyIsAllZero) {
  const DurationSummary s = DurationHistogram().summary();
  EXPECT_EQ(s.count, 0);
  EXPECT_EQ(s.p50_us, 0.0);
  EXPECT_EQ(s.max_us, 0.0);
}

TEST(DurationHistogram, ExactPeriods) {
  DurationHistogram h;
  for (int i = 0; i < 100; ++i) h.add(1'000'000);
  const DurationSummary s = h.summary();
  EXPECT_EQ(s.count, 100);
  EXPECT_EQ(s.p50_us, 1000.0);
  EXPECT_EQ(s.p99_us, 1000.0);
  EXPECT_EQ(s.max_us, 1000.0);
}

TEST(DurationHistogram, PercentilesAndExactMax) {
  DurationHistogram h;
  for (int i = 0; i < 98; ++i) h.add(1'000'400);  // rounds down to its 1 µs bin
  h.add(5'000'000);
  h.add(5'000'123);
  const DurationSummary s = h.summary();
  EXPECT_EQ(s.p50_us, 1000.0);
  EXPECT_EQ(s.p99_us, 5000.0);  // rank 99 of 100
  EXPECT_DOUBLE_EQ(s.max_us, 5000.123);
}

TEST(DurationHistogram, OutOfRangeAndNegative) {
  DurationHistogram h;
  h.add(-5);
  EXPECT_EQ(h.summary().max_us, 0.0);
  h.clear();
  h.add(30'000'000);  // beyond the 20 ms range: last bin, exact max
  const DurationSummary s = h.summary();
  EXPECT_EQ(s.count, 1);
  EXPECT_EQ(s.max_us, 30000.0);
  EXPECT_GE(s.p50_us, 19999.0);
  EXPECT_LE(s.p50_us, s.max_us);
}

}  // namespace
}  // namespace hysim::haptics
