// Rotary-axis compensation tables per dialect (comp_table.hpp). Sources and UNVERIFIED forms:
// docs/dialects.md "Compensation tables". In short:
//   linuxcnc  joint COMP_FILE, COMP_FILE_TYPE = 0: "nominal actual-forward actual-reverse" per
//             line, strictly increasing nominal, at most 256 lines; motion adds nominal - actual to
//             the motor command (LinuxCNC src/emc/motion/usrmotintf.cc usrmotLoadComp, control.c
//             compute_screw_comp). The loader stops at the first line that is not three numbers, so
//             rotacal's comments come after the data.
//   fanuc     stored pitch error compensation of a rotary axis (parameters 3620-3625), incremental
//             values per point in detection units, their sum over one turn zero (Fanuc 0i-PB
//             parameter manual B-63980EN, parameters 3620-3625). An entry sheet, not a tape:
//             the tape format of pitch data is UNVERIFIED.
//   siemens   interpolatory compensation $AA_ENC_COMP (LEC / measuring-system error compensation) as
//             %_N_AX_EEC_INI with modulo 0..360 (840D sl Function Manual K3 "Interpolatory
//             compensation"; 808D: "a positive compensation value causes the machine axis to move in
//             the negative direction": the value is the error).
//   csv       the neutral table.
//   heidenhain, okuma, haas: refused (no source gives a form the user loads).
// Each form is written in its dialect's folder (DialectIdentity::comp_table); this file holds
// what they share.
#include "controllers/comp_table.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "controllers/dialect.hpp"
#include "controllers/offsets.hpp"
#include "controllers/text.hpp"

namespace rotacal::ctl {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kDefaultStepDeg = 5.0;

double wrap360(double deg) {
  double r = std::fmod(deg, 360.0);
  if (r < 0) r += 360.0;
  return r;
}

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument(what); }

}  // namespace

int compTableStepsPerTurn(double step_deg) {
  if (!std::isfinite(step_deg) || step_deg <= 0.0 || step_deg > 90.0)
    bad(fmt::format("table spacing {} deg: must be > 0 and <= 90 deg", step_deg));
  const double n = 360.0 / step_deg;
  const long r = std::lround(n);
  if (std::fabs(n - static_cast<double>(r)) > 1e-9 * n)
    bad(fmt::format("table spacing {} deg does not divide 360 deg into whole steps", step_deg));
  return static_cast<int>(r);
}

const std::vector<std::string>& compTableDialects() {
  // The controllers' own forms first, the neutral table last.
  static const std::vector<std::string> d = [] {
    std::vector<std::string> own, neutral;
    for (const Dialect* x : dialects())
      if (x->hasCompTable()) (x->hasPrograms() ? own : neutral).emplace_back(x->name());
    own.insert(own.end(), neutral.begin(), neutral.end());
    return own;
  }();
  return d;
}

PeriodicInterpolant::PeriodicInterpolant(const std::vector<double>& angle_deg, const std::vector<double>& value) {
  if (angle_deg.size() != value.size())
    bad(fmt::format("{} angles but {} values", angle_deg.size(), value.size()));
  n_ = static_cast<int>(angle_deg.size());
  if (n_ < 3) bad(fmt::format("{} samples: periodic interpolation needs at least 3 over the turn", n_));
  for (int j = 0; j < n_; ++j)
    if (!std::isfinite(angle_deg[j]) || !std::isfinite(value[j]))
      bad(fmt::format("sample {} (angle {}, value {}) is not finite", j + 1, angle_deg[j], value[j]));
  x0_deg_ = angle_deg[0];
  // order the samples by their angle from the first one, modulo a turn
  std::vector<std::pair<double, double>> s;
  for (int j = 0; j < n_; ++j) s.emplace_back(wrap360(angle_deg[j] - x0_deg_), value[j]);
  std::sort(s.begin(), s.end());
  const double h = 360.0 / n_;
  for (int j = 0; j < n_; ++j) {
    double off = s[j].first - j * h;
    if (j == 0 && off > 180.0) off -= 360.0;
    if (std::fabs(off) > 1e-6)
      bad(fmt::format("the angles are not equally spaced over a full turn: {} samples need a spacing of {} deg, "
                      "the {}th lies {} deg from the first",
                      n_, h, j + 1, s[j].first));
  }
  const int m = n_ / 2;
  a_.assign(m + 1, 0.0);
  b_.assign(m + 1, 0.0);
  for (int k = 0; k <= m; ++k) {
    double ak = 0.0, bk = 0.0;
    for (int j = 0; j < n_; ++j) {
      const double t = 2.0 * kPi * j * k / n_;
      ak += s[j].second * std::cos(t);
      bk += s[j].second * std::sin(t);
    }
    a_[k] = 2.0 * ak / n_;
    b_[k] = 2.0 * bk / n_;
  }
  a_[0] /= 2.0;
  if (n_ % 2 == 0) {  // the Nyquist term: cos only, half weight
    a_[m] /= 2.0;
    b_[m] = 0.0;
  }
}

double PeriodicInterpolant::operator()(double angle_deg) const {
  const double t = (angle_deg - x0_deg_) * kDegToRad;
  double f = a_[0];
  for (size_t k = 1; k < a_.size(); ++k) f += a_[k] * std::cos(k * t) + b_[k] * std::sin(k * t);
  return f;
}

double controllerError_deg(const PeriodicInterpolant& E_mdeg, int controller_sign, double controller_deg) {
  if (controller_sign != 1 && controller_sign != -1) bad("controller sign must be +1 or -1");
  const double paper_deg = controller_sign * controller_deg;  // s = +-1: theta / s = s theta
  return -controller_sign * E_mdeg(paper_deg) * 1e-3;
}

CompTableGrid compTableGrid(const PeriodicInterpolant& E, int sign, double lo, double step, int count) {
  CompTableGrid g;
  for (int i = 0; i < count; ++i) {
    const double th = lo + i * step;
    const double e = controllerError_deg(E, sign, th);
    g.rows.push_back({th, e});
    g.max_abs_mdeg = std::max(g.max_abs_mdeg, std::fabs(e) * 1e3);
  }
  return g;
}

std::vector<std::string> compTableProvenance(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  double umax = 0.0;
  for (double u : r.errors.u_mdeg) umax = std::max(umax, u);
  std::vector<std::string> out;
  out.push_back(fmt::format("rotacal comp-table: angular positioning error of axis {} (ISO 230-7 E{}{})", r.errors.axis,
                            r.errors.axis, r.errors.axis));
  if (!r.source.empty()) out.push_back("from " + printableLine(r.source));
  out.push_back(fmt::format("{} identified angles, periodic interpolation; table every {} deg in the control's counting "
                            "(controller sign {:+d})",
                            E.samples(), fixed(step, 4), r.controller_sign));
  if (!r.errors.u_mdeg.empty())
    out.push_back(fmt::format("standard uncertainty of the identified error up to {} mdeg (k = 1)", fixed(umax, 4)));
  return out;
}

std::string compTableRefusal(const std::string& d) {
  const Dialect* dialect = findDialect(d);
  if (dialect && !dialect->hasCompTable() && !dialect->identity().comp_table_refusal.empty())
    return d + ": " + std::string(dialect->identity().comp_table_refusal);
  if (!dialect || !dialect->hasCompTable()) {
    std::string known;
    for (const auto& n : compTableDialects()) known += (known.empty() ? "" : ", ") + n;
    return "unknown dialect '" + d + "' (compensation tables: " + known + ")";
  }
  return "";
}

std::string stepRefusal(double step_deg) {
  try {
    compTableStepsPerTurn(step_deg);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

CompTable writeCompTable(const CompTableRequest& r) {
  const std::string& d = r.dialect;
  if (const std::string why = compTableRefusal(d); !why.empty()) bad(why);
  const auto& e = r.errors;
  if (!e.u_mdeg.empty() && e.u_mdeg.size() != e.angle_deg.size())
    bad(fmt::format("{} angles but {} uncertainties", e.angle_deg.size(), e.u_mdeg.size()));
  const PeriodicInterpolant E(e.angle_deg, e.error_mdeg);
  const double step = r.step_deg > 0.0 ? r.step_deg : kDefaultStepDeg;
  compTableStepsPerTurn(step);
  CompTable t = dialectByName(d).identity().comp_table(r, E, step);
  if (!std::isfinite(t.max_error_mdeg)) bad("the interpolated error is not finite");
  if (t.max_error_mdeg > kMaxAngleCorrectionMdeg && !r.force)
    bad(fmt::format("angular positioning error of {} up to {} mdeg exceeds the plausibility limit of {} mdeg (a setup "
                    "blunder, not a machine's error; --force to write it anyway)",
                    e.axis, fixed(t.max_error_mdeg, 3), fixed(kMaxAngleCorrectionMdeg, 0)));
  return t;
}

}  // namespace rotacal::ctl
