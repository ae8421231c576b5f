#include <gtest/gtest.h>

#include "haptics_test_util.hpp"
#include "hysim/haptics/model_watchdog.hpp"

namespace hysim::haptics {
namespace {

using test::kMs;

TEST(ModelWatchdog, FullScaleWhileModelsArrive) {
  ModelWatchdog w;
  for (int i = 0; i < 200; ++i) EXPECT_EQ(w.update(true, i * kMs), 1.0);
}

TEST(ModelWatchdog, FadesWithinFadeTimeAfterSilenceAndRecovers) {
  ModelWatchdog w(0.05, 0.01);
  w.update(true, 0);
  for (int i = 1; i <= 50; ++i) EXPECT_EQ(w.update(false, i * kMs), 1.0) << i;
  EXPECT_NEAR(w.update(false, 51 * kMs), 0.9, 1e-12);
  for (int i = 52; i <= 55; ++i) w.update(false, i * kMs);
  EXPECT_NEAR(w.scale(), 0.5, 1e-12);
  for (int i = 56; i <= 60; ++i) w.update(false, i * kMs);
  EXPECT_NEAR(w.scale(), 0.0, 1e-12);
  EXPECT_EQ(w.update(false, 80 * kMs), 0.0);
  // A new model: back to full scale at the same rate.
  EXPECT_NEAR(w.update(true, 81 * kMs), 0.1, 1e-12);
  for (int i = 82; i <= 90; ++i) w.update(false, i * kMs);
  EXPECT_NEAR(w.scale(), 1.0, 1e-12);
}

TEST(ModelWatchdog, OnlyThePartPastTheWatchdogTimeFades) {
  ModelWatchdog w(0.05, 0.01);
  w.update(true, 0);
  EXPECT_NEAR(w.update(false, 53 * kMs), 0.7, 1e-12);  // one late tick spanning the limit
}

TEST(ModelWatchdog, TripsWhenNothingWasEverPublished) {
  ModelWatchdog w(0.05, 0.01);
  for (int i = 0; i <= 60; ++i) w.update(false, 1000 * kMs + i * kMs);
  EXPECT_EQ(w.scale(), 0.0);
}

}  // namespace
}  // namespace hysim::haptics
