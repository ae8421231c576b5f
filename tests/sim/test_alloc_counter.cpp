// The allocation counter behind the "allocates nothing" tests must itself count, in plain
// builds (malloc interposed) and under the sanitizers (their allocator hooks): otherwise those
// tests would pass vacuously.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "alloc_counter.hpp"

namespace hysim::testing {
namespace {

TEST(AllocationCounter, CountsNewVectorsAndEigen) {
  long counted = 0;
  {
    AllocationCounter counter;
    auto one = std::make_unique<int>(7);
    std::vector<double> many(100, 1.0);
    Eigen::VectorXd eigen = Eigen::VectorXd::Constant(100, 2.0);
    counted = counter.count();
    EXPECT_EQ(*one + static_cast<int>(many[99] + eigen(99)), 10);
  }
  EXPECT_GE(counted, 3);
}

TEST(AllocationCounter, NothingCountedOutsideItsScope) {
  long counted = -1;
  {
    AllocationCounter counter;
    counted = counter.count();
  }
  auto later = std::make_unique<int>(1);
  EXPECT_EQ(counted, 0);
  EXPECT_EQ(*later, 1);
}

}  // namespace
}  // namespace hysim::testing
