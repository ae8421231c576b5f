#include "app_beep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hysim::tools {

AlarmSound::~AlarmSound() {
  if (device_ != 0) SDL_CloseAudioDevice(device_);
  if (subsystem_) SDL_QuitSubSystem(SDL_INIT_AUDIO);
}

std::vector<float> AlarmSound::pattern(int rate_hz) {
  constexpr double kTone = 880.0, kOnS = 0.12, kGapS = 0.08, kPauseS = 0.4, kRampS = 0.005;
  constexpr double kTwoPi = 6.283185307179586;
  std::vector<float> out;
  for (int b = 0; b < 3; ++b) {
    const int on = static_cast<int>(kOnS * rate_hz);
    for (int i = 0; i < on; ++i) {
      const double t = static_cast<double>(i) / rate_hz;
      // Short ramps at both ends: a hard edge clicks.
      const double ramp = std::min({1.0, t / kRampS, (kOnS - t) / kRampS});
      out.push_back(static_cast<float>(0.3 * ramp * std::sin(kTwoPi * kTone * t)));
    }
    out.insert(out.end(), static_cast<size_t>(kGapS * rate_hz), 0.0f);
  }
  out.insert(out.end(), static_cast<size_t>(kPauseS * rate_hz), 0.0f);
  return out;
}

bool AlarmSound::open() {
  if (SDL_InitSubSystem(SDL_INIT_AUDIO) != 0) {
    std::printf("hysim-app: no audio (%s): the alarm is silent\n", SDL_GetError());
    return false;
  }
  subsystem_ = true;
  SDL_AudioSpec want{}, have{};
  want.freq = 44100;
  want.format = AUDIO_F32SYS;
  want.channels = 1;
  want.samples = 1024;
  device_ = SDL_OpenAudioDevice(nullptr, 0, &want, &have, 0);
  if (device_ == 0) {
    std::printf("hysim-app: no audio device (%s): the alarm is silent\n", SDL_GetError());
    return false;
  }
  samples_ = pattern(have.freq);
  SDL_PauseAudioDevice(device_, 0);
  return true;
}

void AlarmSound::beep() {
  if (device_ == 0 || SDL_GetQueuedAudioSize(device_) > 0) return;
  SDL_QueueAudio(device_, samples_.data(), static_cast<Uint32>(samples_.size() * sizeof(float)));
}

}  // namespace hysim::tools
