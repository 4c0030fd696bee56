#include "controllers/clock.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace rotacal::ctl {

namespace {
// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil).
long long daysFromCivil(long long y, unsigned m, unsigned d) {
  y -= m <= 2;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long long>(doe) - 719468;
}
void civilFromDays(long long z, long long& y, unsigned& m, unsigned& d) {
  z += 719468;
  const long long era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  y = static_cast<long long>(yoe) + era * 400;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y += m <= 2;
}
const long long kEpochDays = daysFromCivil(kClockEpochYear, 1, 1);
}  // namespace

std::optional<double> clockSeconds(long yyyymmdd, long hhmmss) {
  const long y = yyyymmdd / 10000, mo = yyyymmdd / 100 % 100, d = yyyymmdd % 100;
  const long h = hhmmss / 10000, mi = hhmmss / 100 % 100, s = hhmmss % 100;
  if (yyyymmdd < 0 || hhmmss < 0 || y < 1900 || y > 9999 || mo < 1 || mo > 12 || d < 1 || h > 23 || mi > 59 || s > 59)
    return std::nullopt;
  static const int kDays[] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  if (d > kDays[mo - 1] || (mo == 2 && d == 29 && !leap)) return std::nullopt;
  const long long days = daysFromCivil(y, static_cast<unsigned>(mo), static_cast<unsigned>(d)) - kEpochDays;
  return static_cast<double>(days * 86400 + h * 3600 + mi * 60 + s);
}

ClockStamp clockStamp(double seconds) {
  if (!std::isfinite(seconds)) throw std::invalid_argument("a time stamp must be a finite number of seconds");
  // Years 1900..9999 lie within +-2.6e11 s of the epoch: refuse anything beyond before the cast
  // to an integer (1e300 s does not fit one) and the day arithmetic (which would overflow).
  if (std::abs(seconds) > 4e11)
    throw std::invalid_argument(fmt::format("time stamp {:g} s is outside the years 1900-9999", seconds));
  const long long s = static_cast<long long>(std::floor(seconds));
  const long long day = (s >= 0 ? s / 86400 : -((-s + 86399) / 86400));
  const long long sod = s - day * 86400;
  long long y = 0;
  unsigned m = 0, d = 0;
  civilFromDays(day + kEpochDays, y, m, d);
  if (y < 1900 || y > 9999) throw std::invalid_argument(fmt::format("time stamp {} s is outside the years 1900-9999", seconds));
  return {static_cast<long>(y * 10000 + m * 100 + d), static_cast<long>(sod / 3600 * 10000 + sod / 60 % 60 * 100 + sod % 60)};
}

}  // namespace rotacal::ctl
