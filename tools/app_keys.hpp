#pragma once
// The trainee's keys, decided apart from SDL so that tests can hold them: which keys are held
// (TraineeKeys, filled from SDL's keyboard state in the app) and what the scope does with
// them (a PivotCommand for the PivotScopeDevice).
//   W / S           insert / withdraw the scope
//   arrows          pivot the scope about the cervix (left, right, up, down)
//   A / D           roll the scope (turns the fore-oblique lens' view)
//   Q / E           loop electrode in / out
//   C or Left-Shift cut pedal (hold): the electrode is active while held
#include "hysim/haptics/pivot_device.hpp"

namespace hysim::tools {

struct TraineeKeys {
  bool insert = false, withdraw = false;
  bool pivot_left = false, pivot_right = false, pivot_up = false, pivot_down = false;
  bool roll_left = false, roll_right = false;
  bool loop_in = false, loop_out = false;
  bool pedal_c = false, pedal_shift = false;
};

// Rates of the keyboard scope: slow enough to place the loop to a millimetre by tapping.
struct KeyRates {
  double insert_mm_s = 10.0;
  double pivot_rad_s = 0.3;
  double roll_rad_s = 1.0;
  double loop_mm_s = 5.0;
};

// Either pedal key held: the electrode is active.
bool pedalDown(const TraineeKeys& keys);
haptics::PivotCommand pivotCommand(const TraineeKeys& keys, const KeyRates& rates = {});

}  // namespace hysim::tools
