#include "hysim/haptics/replay_device.hpp"

namespace hysim::haptics {

const DeviceState& ReplaySource::next() {
  const auto& states = recording_->states;
  if (states.empty()) return rest_;
  if (next_ >= states.size()) {
    ++past_end_;
    return states.back().state;
  }
  return states[next_++].state;
}

ReplayDevice::ReplayDevice(std::shared_ptr<ReplaySource> source) : source_(std::move(source)) {
  info_.name = "replay of " + (source_->recording().header.device_name.empty()
                                   ? std::string("a recording")
                                   : source_->recording().header.device_name);
}

DeviceState ReplayDevice::read(double) { return source_->next(); }

}  // namespace hysim::haptics
