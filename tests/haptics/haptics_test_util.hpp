#pragma once
// Helpers shared by the haptics tests.
#include <memory>

#include "hysim/haptics/device.hpp"

namespace hysim::haptics::test {

// A scripted device holding its tip still at `tip_mm` (velocity exactly zero).
inline std::unique_ptr<ScriptedDevice> standingDevice(const Eigen::Vector3d& tip_mm = Eigen::Vector3d::Zero()) {
  Keyframe k;
  k.tip = tip_mm;
  return std::make_unique<ScriptedDevice>(Trajectory({k}));
}

inline constexpr std::int64_t kMs = 1'000'000;  // nanoseconds

}  // namespace hysim::haptics::test
