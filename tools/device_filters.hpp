#pragma once
// The filters between a hardware device and the simulation, from a small YAML file
// (`hysim run --device udp:PORT --device-filters FILE`; keys in haptics/README.md, "Filters").
#include <string>

#include "hysim/cutting/result.hpp"
#include "hysim/haptics/filters.hpp"

namespace hysim::tools {

struct DeviceFilters {
  haptics::MotionScale scale;
  haptics::PoseTransform transform;
  haptics::MotionLimit limit;
};

// Keys left out keep the defaults (no scaling, no transform, the default limits). Errors
// name the file, line and key.
Result<DeviceFilters> loadDeviceFilters(const std::string& path);

}  // namespace hysim::tools
