#pragma once
// The perforation alarm: raised at the step where the engine opens a perforation event (the
// active loop within the scene's margin of the serosa, or beyond it), and kept on while the
// event lasts and kHoldS after it, so a brief touch is still seen and heard.
namespace hysim::tools {

class PerforationAlarm {
 public:
  static constexpr double kHoldS = 2.0;

  // After every step, with the engine's event count and whether an event is open now.
  // True when this step opened a new event: the alarm is raised.
  bool observe(int perforation_count, bool perforating, double time_s);
  bool active(double time_s) const { return raised_ > 0 && (perforating_ || time_s - last_open_s_ <= kHoldS); }
  int raised() const { return raised_; }                 // events that raised it
  double raisedAtS() const { return raised_at_s_; }      // simulated time of the last raise

 private:
  int seen_ = 0;
  int raised_ = 0;
  bool perforating_ = false;
  double raised_at_s_ = -1.0;
  double last_open_s_ = -1.0;
};

}  // namespace hysim::tools
