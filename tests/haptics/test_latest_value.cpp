#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

#include "hysim/haptics/latest_value.hpp"

namespace hysim::haptics {
namespace {

TEST(LatestValue, EmptyUntilPublishedThenNewest) {
  LatestValue<int> box;
  int out = -7;
  EXPECT_FALSE(box.read(out));
  EXPECT_EQ(out, -7);
  box.publish(1);
  box.publish(2);
  box.publish(3);
  ASSERT_TRUE(box.read(out));
  EXPECT_EQ(out, 3);
  out = 0;
  ASSERT_TRUE(box.read(out));  // nothing new: the same value again
  EXPECT_EQ(out, 3);
  box.publish(4);
  ASSERT_TRUE(box.read(out));
  EXPECT_EQ(out, 4);
}

// Wide enough that a torn copy would show as unequal fields.
struct Stamp {
  std::array<std::int64_t, 16> fields{};
};

TEST(LatestValue, TwoThreadsSeeWholeValuesInOrder) {
  constexpr std::int64_t kCount = 200000;
  LatestValue<Stamp> box;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    Stamp s;
    for (std::int64_t i = 1; i <= kCount; ++i) {
      s.fields.fill(i);
      box.publish(s);
    }
    done.store(true);
  });
  std::int64_t last = 0, reads = 0, torn = 0, backwards = 0;
  Stamp s;
  auto check = [&] {
    if (!box.read(s)) return;
    ++reads;
    for (std::int64_t f : s.fields) torn += f != s.fields[0];
    backwards += s.fields[0] < last;
    last = s.fields[0];
  };
  while (!done.load()) check();
  writer.join();
  check();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(backwards, 0);
  EXPECT_EQ(last, kCount);  // the final read sees the final value
  EXPECT_GT(reads, 0);
}

}  // namespace
}  // namespace hysim::haptics
