#pragma once
// A timed script of game-controller inputs, played into a VirtualPad: a trainee's hands for
// demos and for recording sessions driven through the real pad driver (hysim run --device
// virtual-pad:FILE). YAML: a list of events, each `t_s` and the standard-layout inputs that
// change then (sticks -1..1, triggers 0..1, buttons true/false); an input keeps its value
// until an event changes it. Example: scenes/pad/default-course.yaml.
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"
#include "hysim/haptics/virtual_pad.hpp"

namespace hysim::tools {

struct PadEvent {
  double t_s = 0.0;
  struct Input {
    bool is_axis = true;
    int index = 0;
    double value = 0.0;  // axis value, or 0/1 for a button
  };
  std::vector<Input> inputs;
};

class PadScript {
 public:
  // Events in time order; errors name the file, line and key.
  static Result<PadScript> load(const std::string& path);
  // Sets every event up to time t_s (inclusive) not yet played; call with growing times.
  void playUntil(double t_s, haptics::VirtualPad& pad);
  double duration() const { return events_.empty() ? 0.0 : events_.back().t_s; }
  std::size_t size() const { return events_.size(); }

 private:
  std::vector<PadEvent> events_;
  std::size_t next_ = 0;
};

}  // namespace hysim::tools
