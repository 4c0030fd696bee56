#include "controllers/program_writing.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "controllers/text.hpp"

namespace rotacal::ctl {

int probeCount(const nc::Program& p) {
  int probes = 0;
  for (const auto& op : p.ops) probes += op.kind == nc::Op::Kind::Probe;
  if (p.point_count != 0 && p.point_count != probes)
    throw std::invalid_argument(fmt::format("program has {} probing moves but point_count {}", probes, p.point_count));
  return probes;
}

void appendLine(std::string& out, const std::string& s, size_t max_chars) {
  if (s.size() > max_chars) throw std::invalid_argument(fmt::format("line longer than {} characters: {}", max_chars, s));
  out += s;
  out += '\n';
}

int programNumber(const nc::Program& program) {
  // Fanuc and Okuma take O1-O9999; Haas writes the same number in five digits.
  if (program.number < 1 || program.number > 9999)
    throw std::invalid_argument(fmt::format("program '{}' has no program number from 1 to 9999 (got {})", program.name,
                                            program.number));
  return program.number;
}

std::string rotaryLinearWords(const nc::Op& op, nc::Unit unit, const std::string& sep) {
  const int dec = nc::rotaryLinearDecimals(unit);
  std::string s;
  for (char axis : op.axes) {
    if (axis < 'X' || axis > 'Z') throw std::invalid_argument(std::string("rotary-linear move: bad linear axis ") + axis);
    if (!s.empty()) s += sep;
    s += axis + fixed(op.xyz[axis - 'X'], dec);
  }
  for (const auto& [axis, deg] : op.rotary) {
    if (!s.empty()) s += sep;
    s += axis + trimmed(deg, 4);
  }
  if (op.feed > 0) s += sep + "F" + trimmed(op.feed, 4);
  return s;
}

std::string rapidBlock(std::string_view g, const nc::Op& op, int decimals) {
  const Eigen::Vector3d& x = op.xyz;
  if (op.z_only) return fmt::format("{} Z{}", g, fixed(x.z(), decimals));
  return fmt::format("{} X{} Y{} Z{}", g, fixed(x.x(), decimals), fixed(x.y(), decimals), fixed(x.z(), decimals));
}

std::string linearBlock(std::string_view g, const nc::Op& op, int decimals, bool inch) {
  const Eigen::Vector3d& x = op.xyz;
  return fmt::format("{} X{} Y{} Z{} F{}", g, fixed(x.x(), decimals), fixed(x.y(), decimals), fixed(x.z(), decimals),
                     fixed(op.feed, inch ? 3 : 1));
}

void requireRapidIndex(const nc::Op& op, std::string_view dialect) {
  if (op.feed > 0)
    throw std::invalid_argument(fmt::format("the {} program indexes at rapid only; a rotary move at a feed (R-test "
                                            "reciprocation) is written for linuxcnc only",
                                            dialect));
}

std::string inverseTimeRefusal(std::string_view dialect) {
  const Dialect* d = findDialect(dialect);
  if (!d || d->inverseTimeRefusal().empty()) return "";
  std::vector<std::string> writing;
  for (const Dialect* o : dialects())
    if (o->hasPrograms() && o->inverseTimeRefusal().empty()) writing.emplace_back(o->name());
  std::string use;
  for (size_t i = 0; i < writing.size(); ++i)
    use += (i == 0 ? "" : i + 1 == writing.size() ? " or " : ", ") + writing[i];
  return fmt::format("{}: {}, so a program that moves under inverse time is refused for this dialect; use {}", dialect,
                     d->inverseTimeRefusal(), use);
}

void requireInverseTimeAllowed(const nc::Program& program, std::string_view dialect) {
  const std::string why = inverseTimeRefusal(dialect);
  if (why.empty()) return;
  for (const auto& op : program.ops)
    if (op.kind == nc::Op::Kind::Mode && op.inverse_time) throw std::invalid_argument(why);
}

void ModeGuard::apply(const nc::Op& op) {
  switch (op.kind) {
    case nc::Op::Kind::Mode: inverse_time_ = op.inverse_time; break;
    case nc::Op::Kind::Probe:
      if (inverse_time_) throw std::invalid_argument("a probing move under inverse-time feed (G93): switch to G94 first");
      break;
    case nc::Op::Kind::RotaryLinear:
      if (inverse_time_ && !(op.feed > 0))
        throw std::invalid_argument("an inverse-time (G93) move needs its own F word on every block");
      break;
    case nc::Op::Kind::Linear:
      if (inverse_time_) throw std::invalid_argument("a per-minute linear move under inverse-time feed (G93)");
      break;
    case nc::Op::Kind::Comment:
    case nc::Op::Kind::Rapid:
    case nc::Op::Kind::Index:
    case nc::Op::Kind::Pause:
    case nc::Op::Kind::Dwell:
    case nc::Op::Kind::Read:
    case nc::Op::Kind::RepeatBegin:
    case nc::Op::Kind::RepeatEnd: break;
  }
}

void refuseRtestOps(std::string_view dialect) {
  throw std::invalid_argument(fmt::format("the {} program cannot express an R-test dwell, logger trigger or loop "
                                          "in this version: generate this program for linuxcnc",
                                          dialect));
}

void writeOps(const nc::Program& p, const WordAddressMoves& moves, LineWriter& w,
              const std::function<void(const nc::Op&)>& own, const std::function<void()>& before_index) {
  const bool inch = p.unit == nc::Unit::Inch;
  ModeGuard guard;
  for (const auto& op : p.ops) {
    guard.apply(op);
    switch (op.kind) {
      case nc::Op::Kind::Rapid: w.line(rapidBlock(moves.rapid, op, moves.decimals)); break;
      case nc::Op::Kind::Linear: w.line(linearBlock(moves.feed, op, moves.decimals, inch)); break;
      case nc::Op::Kind::Index: {
        requireRapidIndex(op, moves.dialect);
        std::string s(moves.rapid);
        for (const auto& [axis, deg] : op.rotary) s += fmt::format(" {}{}", axis, fixed(deg, moves.decimals));
        if (before_index) before_index();
        w.line(s);
        break;
      }
      case nc::Op::Kind::RotaryLinear: w.line(rotaryLinearWords(op, p.unit, moves.rotary_linear_sep)); break;
      case nc::Op::Kind::Dwell:
      case nc::Op::Kind::Read:
      case nc::Op::Kind::RepeatBegin:
      case nc::Op::Kind::RepeatEnd: refuseRtestOps(moves.dialect);
      case nc::Op::Kind::Comment:
      case nc::Op::Kind::Mode:
      case nc::Op::Kind::Pause:
      case nc::Op::Kind::Probe: own(op); break;
    }
  }
}

std::string isoModeBlock(const nc::Op& op) {
  if (op.inverse_time && op.feed > 0)
    return fmt::format("{} G01 G93 F{}", op.incremental ? "G91" : "G90", trimmed(op.feed, 4));
  return fmt::format("{} {}", op.incremental ? "G91" : "G90", op.inverse_time ? "G93" : "G94");
}

void requireSingleTouch(const nc::Op& op, std::string_view dialect) {
  const int id = op.point_id;
  if (!(op.feed > 0)) throw std::invalid_argument(fmt::format("point {}: probing feed must be > 0", id));
  if (op.retract_mm > 0)
    throw std::invalid_argument(fmt::format(
        "point {}: the {} program records a single touch (rotacal has no double-touch form for this dialect); "
        "set the machine's probe retract_mm to 0 for it",
        id, dialect));
}

}  // namespace rotacal::ctl
