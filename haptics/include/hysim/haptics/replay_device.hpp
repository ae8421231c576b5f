#pragma once
// Plays a recording back: each read() returns the next recorded state, whatever time it is
// asked for, because a recording holds exactly one state per read the simulation made (the
// attach read, then one per step). Several ReplayDevice objects may share one source: a
// recorded device change (RecordedState::attached) is replayed by attaching a fresh
// ReplayDevice on the same source, which goes on where the last one stopped.
#include <cstddef>
#include <memory>

#include "hysim/haptics/device.hpp"
#include "hysim/haptics/recording.hpp"

namespace hysim::haptics {

class ReplaySource {
 public:
  explicit ReplaySource(std::shared_ptr<const Recording> recording) : recording_(std::move(recording)) {}
  const Recording& recording() const { return *recording_; }
  std::size_t position() const { return next_; }
  std::size_t size() const { return recording_->states.size(); }
  // Whether the next state was taken by a newly attached device.
  bool nextIsAttach() const { return next_ < size() && recording_->states[next_].attached; }
  // The next state; past the end the last one again, counted (a replay asked for more steps
  // than were recorded).
  const DeviceState& next();
  long readsPastEnd() const { return past_end_; }

 private:
  std::shared_ptr<const Recording> recording_;
  std::size_t next_ = 0;
  long past_end_ = 0;
  DeviceState rest_;  // before anything was recorded: at rest at the origin
};

class ReplayDevice final : public Device {
 public:
  explicit ReplayDevice(std::shared_ptr<ReplaySource> source);
  const DeviceInfo& info() const override { return info_; }
  DeviceState read(double time_s) override;
  void commandForce(const Eigen::Vector3d& force_n) override { last_force_ = safeForce(force_n, info_.max_force_n); }
  const Eigen::Vector3d& lastForce() const override { return last_force_; }

 private:
  std::shared_ptr<ReplaySource> source_;
  DeviceInfo info_;
  Eigen::Vector3d last_force_{0, 0, 0};
};

}  // namespace hysim::haptics
