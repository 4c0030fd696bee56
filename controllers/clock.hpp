#pragma once
// The controllers' wall clocks as results files print them (a date YYYYMMDD and a time HHMMSS)
// and the seconds since one epoch that every results reader turns them into.
#include <optional>

namespace rotacal::ctl {

/// Epoch of the controllers' wall clocks in results files: 2000-01-01 00:00:00 (control local
/// time, no time zone: every repeat of a calibration runs on the same control). t_s of a point =
/// seconds since this epoch, so repeats share one clock (contract.md "Neutral results").
constexpr int kClockEpochYear = 2000;

/// Seconds since kClockEpochYear-01-01 00:00:00 of a date YYYYMMDD and a time HHMMSS (as Fanuc
/// #3011/#3012 hold them); nullopt when the date or the time is not a valid calendar value.
std::optional<double> clockSeconds(long yyyymmdd, long hhmmss);

struct ClockStamp {
  long yyyymmdd = 0;
  long hhmmss = 0;
};
/// Date and time of floor(seconds) since the epoch (inverse of clockSeconds on whole seconds).
/// Throws std::invalid_argument for a non-finite value or a year outside 1900..9999.
ClockStamp clockStamp(double seconds_since_epoch);

}  // namespace rotacal::ctl
