#pragma once
// The alarm's sound: a beep pattern generated in code and queued on an SDL audio device. A
// machine without audio (Xvfb, CI) gets one log line and a silent alarm, never a failure.
#include <SDL.h>

#include <string>
#include <vector>

namespace hysim::tools {

class AlarmSound {
 public:
  AlarmSound() = default;
  AlarmSound(const AlarmSound&) = delete;
  AlarmSound& operator=(const AlarmSound&) = delete;
  ~AlarmSound();

  // Opens the default output device. False (said once on stdout) when there is none.
  bool open();
  bool available() const { return device_ != 0; }
  // Queues one beep pattern unless one is still playing: call every frame while the alarm is on.
  void beep();
  // The pattern, mono float samples at `rate_hz`: three 880 Hz beeps with gaps.
  static std::vector<float> pattern(int rate_hz);

 private:
  SDL_AudioDeviceID device_ = 0;
  bool subsystem_ = false;
  std::vector<float> samples_;
};

}  // namespace hysim::tools
