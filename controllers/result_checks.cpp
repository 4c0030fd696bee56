#include "controllers/result_checks.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/errors.hpp"

namespace rotacal::ctl {

void requireText(std::string_view text, const std::string& file) {
  int line = 1;
  size_t line_start = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      ++line;
      line_start = i + 1;
      continue;
    }
    if (c == '\t' || (c >= 0x20 && c <= 0x7e)) continue;
    throw InputError(file, line,
                     fmt::format("byte 0x{:02X} at column {}: a results file is plain ASCII text (a damaged transfer, "
                                 "a binary file or a file saved in another encoding?)",
                                 static_cast<unsigned>(c), i - line_start + 1));
  }
}

void requireOnProbingMove(const ProbePlan& plan, const ProbePoint& point, const Eigen::Vector3d& position_m_mm,
                          const std::string& file, int line) {
  // s: position along the move measured from the nominal trigger; lateral: distance from the
  // move's line. Both exact, no linearisation: the move is a straight segment.
  const Eigen::Vector3d u = point.approach_m.normalized();
  const Eigen::Vector3d d = position_m_mm - point.trigger_m_mm;
  const double s = d.dot(u);
  const double lateral = (d - s * u).norm();
  const double lo = -plan.machine.approach_mm, hi = plan.machine.overtravel_mm;
  const double beyond = s < lo ? lo - s : (s > hi ? s - hi : 0.0);
  const std::string where = fmt::format("point {} at ({:.4f}, {:.4f}, {:.4f}) mm", point.id, position_m_mm.x(),
                                        position_m_mm.y(), position_m_mm.z());
  if (!(lateral <= kTriggerOffMoveTolMm))
    throw InputError(file, line,
                     fmt::format("{} is {:.3f} mm off the line of its probing move through the nominal trigger "
                                 "({:.4f}, {:.4f}, {:.4f}) mm (tolerance {} mm): a value of another point or plan?",
                                 where, lateral, point.trigger_m_mm.x(), point.trigger_m_mm.y(), point.trigger_m_mm.z(),
                                 kTriggerOffMoveTolMm));
  if (!(beyond <= kTriggerOffMoveTolMm))
    throw InputError(file, line,
                     fmt::format("{} is {:.3f} mm along its probing move from the nominal trigger, outside the move "
                                 "[{:.3f}, +{:.3f}] mm (tolerance {} mm): a value of another point or plan, or a "
                                 "wrong unit?",
                                 where, s, lo, hi, kTriggerOffMoveTolMm));
}

}  // namespace rotacal::ctl
