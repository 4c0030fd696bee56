#pragma once
// Terminal manners for long runs (Monte Carlo, plan design, diagnosis search): a one-line
// progress indicator on stderr when stderr is a terminal and --quiet was not given; nothing
// otherwise, so that logs and pipelines stay clean.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>

#include "cli/command.hpp"

namespace rotacal {

/// "\rWHAT: 640/1000 UNIT (64 %)" at most every 0.1 s; the line is cleared when done. Empty
/// function (no cost) when quiet or not on a terminal.
inline std::function<void(int, int)> progressIndicator(const Common& c, const std::string& what,
                                                       const std::string& unit = "runs") {
  if (c.quiet || !isatty(fileno(stderr))) return {};
  auto last = std::make_shared<std::chrono::steady_clock::time_point>();
  return [last, what, unit](int done, int total) {
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - *last < std::chrono::milliseconds(100)) return;
    *last = now;
    std::fprintf(stderr, "\r%s: %d/%d %s (%3.0f %%)%s", what.c_str(), done, total, unit.c_str(),
                 total > 0 ? 100.0 * done / total : 100.0, done >= total ? "\n" : "");
    std::fflush(stderr);
  };
}

}  // namespace rotacal
