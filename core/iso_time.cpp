// ISO 8601 UTC times (core/iso_time.hpp).
#include "core/iso_time.hpp"

#include <cctype>
#include <cmath>
#include <ctime>
#include <stdexcept>

namespace rotacal {

double parseIsoTime(const std::string& text) {
  const std::string bad = "time '" + text + "' is not YYYY-MM-DD or YYYY-MM-DDThh:mm:ssZ (UTC)";
  // Character by character: sscanf would take signs, spaces and short fields.
  const std::string date_form = "dddd-dd-dd", full_form = "dddd-dd-ddTdd:dd:ddZ";
  const std::string& form = text.size() == date_form.size() ? date_form : full_form;
  if (text.size() != form.size()) throw std::invalid_argument(bad);
  for (size_t i = 0; i < form.size(); ++i)
    if (form[i] == 'd' ? !std::isdigit(static_cast<unsigned char>(text[i])) : text[i] != form[i])
      throw std::invalid_argument(bad);
  auto field = [&](size_t at, size_t n) { return std::stoi(text.substr(at, n)); };
  const int Y = field(0, 4), M = field(5, 2), D = field(8, 2);
  const bool full = text.size() == full_form.size();
  const int h = full ? field(11, 2) : 0, m = full ? field(14, 2) : 0, s = full ? field(17, 2) : 0;
  static const int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (Y % 4 == 0 && Y % 100 != 0) || Y % 400 == 0;
  // timegm would roll 2024-02-31 over into March: a date that does not exist is refused.
  if (Y < 1970 || M < 1 || M > 12 || D < 1 || D > kDays[M - 1] + (M == 2 && leap ? 1 : 0) || h > 23 || m > 59 ||
      s > 59)
    throw std::invalid_argument("time '" + text + "' is not a valid date and time (UTC, years 1970-9999)");
  std::tm tm{};
  tm.tm_year = Y - 1900;
  tm.tm_mon = M - 1;
  tm.tm_mday = D;
  tm.tm_hour = h;
  tm.tm_min = m;
  tm.tm_sec = s;
  return static_cast<double>(timegm(&tm));
}

std::string isoTime(double unix_s) {
  const std::time_t t = static_cast<std::time_t>(std::floor(unix_s));
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace rotacal
