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
#include "controllers/comp_table.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "controllers/common.hpp"
#include "controllers/dialect.hpp"

namespace rotacal::ctl {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr int kLinuxcncMaxEntries = 256;      // EMCMOT_COMP_SIZE (ini-config: "256 triplets per joint")
constexpr double kDefaultStepDeg = 5.0;
constexpr long kFanucMaxValue = 32767;          // per point, detection units x magnification (UNVERIFIED)
constexpr int kSiemensMaxPoints = 10000;       // sanity bound only: MD38000 sets the real one

double wrap360(double deg) {
  double r = std::fmod(deg, 360.0);
  if (r < 0) r += 360.0;
  return r;
}

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument(what); }

int stepsPerTurn(double step_deg) {
  if (!std::isfinite(step_deg) || step_deg <= 0.0 || step_deg > 90.0)
    bad(fmt::format("table spacing {} deg: must be > 0 and <= 90 deg", step_deg));
  const double n = 360.0 / step_deg;
  const long r = std::lround(n);
  if (std::fabs(n - static_cast<double>(r)) > 1e-9 * n)
    bad(fmt::format("table spacing {} deg does not divide 360 deg into whole steps", step_deg));
  return static_cast<int>(r);
}

std::string axisWord(char axis) { return std::string(1, axis); }

}  // namespace

const std::vector<std::string>& compTableDialects() {
  static const std::vector<std::string> d = {"linuxcnc", "fanuc", "siemens", "csv"};
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

namespace {

struct Grid {
  std::vector<CompTableRow> rows;
  double max_abs_mdeg = 0.0;
};

Grid grid(const PeriodicInterpolant& E, int sign, double lo, double step, int count) {
  Grid g;
  for (int i = 0; i < count; ++i) {
    const double th = lo + i * step;
    const double e = controllerError_deg(E, sign, th);
    g.rows.push_back({th, e});
    g.max_abs_mdeg = std::max(g.max_abs_mdeg, std::fabs(e) * 1e3);
  }
  return g;
}

std::vector<std::string> provenance(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
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

CompTable linuxcnc(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  double lo = r.range_lo_deg, hi = r.range_hi_deg;
  if (!(lo < hi)) lo = -360.0, hi = 360.0;
  lo = std::floor(lo / step + 1e-9) * step;  // a grid point, not beyond the range it covers
  hi = std::ceil(hi / step - 1e-9) * step;
  const long count = std::lround((hi - lo) / step) + 1;
  if (count > kLinuxcncMaxEntries)
    bad(fmt::format("{} table lines from {} to {} deg every {} deg: LinuxCNC takes at most {} per joint (choose a larger "
                    "--step-deg)",
                    count, fixed(lo, 3), fixed(hi, 3), fixed(step, 4), kLinuxcncMaxEntries));
  const Grid g = grid(E, r.controller_sign, lo, step, static_cast<int>(count));
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  for (const auto& row : g.rows) {
    const std::string actual = fixed(row.controller_deg + row.error_deg, 6);
    t.text += fmt::format("{} {} {}\n", fixed(row.controller_deg, 6), actual, actual);
  }
  // After the data: LinuxCNC's loader stops at the first line that is not three numbers.
  for (const auto& l : provenance(r, E, step)) t.text += "# " + l + "\n";
  t.text += "# columns: nominal (commanded) joint position, actual position moving up, actual moving down (deg)\n";
  t.text += "# LinuxCNC commands nominal - actual more; COMP_FILE_TYPE = 0; BACKLASH is then ignored\n";
  t.text += "# after start-up turn the axis through one full revolution: the correction is then followed\n";
  t.setup = {fmt::format("INI, the [JOINT_n] section of axis {}: COMP_FILE = <this file> and COMP_FILE_TYPE = 0 "
                         "(BACKLASH of that joint is then not used)",
                         r.errors.axis),
             "after start-up turn the axis through one full revolution before measuring or cutting: LinuxCNC 2.9 "
             "applies the correction only while the joint moves, and from rest it did not take a step of 3 mdeg "
             "(observed); over a turn the correction passes zero and is followed from there on"};
  return t;
}

CompTable fanuc(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  const int n = stepsPerTurn(step);
  const int ref = r.fanuc_reference_point;
  const double unit = r.fanuc_detection_unit_deg;
  if (!(unit > 0.0 && unit <= 0.01)) bad(fmt::format("detection unit {} deg: expected 0.01 deg or finer", unit));
  if (ref < 0 || ref + n > 9999) bad(fmt::format("reference point number {} with {} points is out of range", ref, n));
  const Grid g = grid(E, r.controller_sign, 0.0, step, n + 1);
  // absolute correction -e in detection units, rounded; the values are its increments, so the sum
  // over the turn is exactly zero (the correction at 360 deg is the one at 0 deg)
  std::vector<long> absolute;
  for (const auto& row : g.rows) absolute.push_back(std::lround(-row.error_deg / unit));
  absolute.back() = absolute.front();
  std::vector<long> value(n + 1, 0);
  for (int k = 1; k <= n; ++k) value[k] = absolute[k] - absolute[k - 1];
  value[0] = value[n];
  long vmax = 0;
  for (long v : value) vmax = std::max(vmax, std::labs(v));
  if (vmax > kFanucMaxValue)
    bad(fmt::format("a pitch error compensation value of {} detection units exceeds {}", vmax, kFanucMaxValue));
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  const std::string ax = axisWord(r.errors.axis);
  std::string& s = t.text;
  s += "ROTACAL PITCH ERROR COMPENSATION FOR FANUC, ROTARY AXIS " + ax + " (ENTRY SHEET, NOT A TAPE)\n";
  for (const auto& l : provenance(r, E, step)) s += l + "\n";
  s += fmt::format("Detection unit assumed: {} deg, magnification 1. Values are increments of the correction\n"
                   "(-error) in detection units; their sum over the turn is 0. The error at the reference position\n"
                   "({} deg) stays: a constant zero shift of the axis, taken by its work offset.\n",
                   fixed(unit, 6), fixed(g.rows.front().controller_deg, 3));
  s += "Parameters of axis " + ax + " (set, then power off and on and return to the reference position):\n";
  s += fmt::format("3605#0 = 0  (one table for both directions)\n");
  s += fmt::format("3620 = {}  (point number of the reference position)\n", ref);
  s += fmt::format("3621 = {}  (most negative point: the reference point on a rotary axis)\n", ref);
  s += fmt::format("3622 = {}  (most positive point: 3620 + 360 / interval)\n", ref + n);
  s += "3623 = 1  (magnification)\n";
  s += fmt::format("3624 = {} deg  (interval; {} in detection units)\n", fixed(step, 3),
                   std::lround(step / unit));
  s += fmt::format("3625 = 360.000 deg  (travel per rotation; {} in detection units)\n",
                   std::lround(360.0 / unit));
  s += fmt::format("Point {} must hold the value of point {}.\n", ref, ref + n);
  s += "POINT  ANGLE_DEG  VALUE\n";
  for (int k = 0; k <= n; ++k)
    s += fmt::format("{:5d}  {:>9}  {:+d}\n", ref + k, fixed(g.rows[k].controller_deg, 3), value[k]);
  s += "END\n";
  t.setup = {fmt::format("parameters 3605#0, 3620-3625 of axis {} as listed, the values on the pitch error "
                         "compensation screen; power off and on, reference return",
                         ax)};
  return t;
}

CompTable siemens(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  const int n = stepsPerTurn(step);
  if (n + 1 > kSiemensMaxPoints) bad(fmt::format("{} interpolation points are too many", n + 1));
  const Grid g = grid(E, r.controller_sign, 0.0, step, n + 1);
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  const std::string ax = axisWord(r.errors.axis) + "1";  // machine axis name as in K3's example X1: UNVERIFIED
  std::string& s = t.text;
  s += "%_N_AX_EEC_INI\n";
  std::string comment;
  for (const auto& l : provenance(r, E, step)) comment += l + ". ";
  comment += fmt::format("Value = positioning error (actual - commanded, deg): a positive value moves the axis in the "
                         "negative direction. Load with MD32700 ENC_COMP_ENABLE = 0, MD38000 MM_ENC_COMP_MAX_POINTS >= {}, "
                         "then MD32700 = 1.",
                         n + 1);
  for (const auto& l : dialectByName("siemens").commentLines(comment)) s += l + "\n";
  s += "CHANDATA(1)\n";
  for (int k = 0; k <= n; ++k) {
    const double v = k == n ? g.rows[0].error_deg : g.rows[k].error_deg;  // modulo: 360 = 0
    s += fmt::format("$AA_ENC_COMP[0,{},{}]={}\n", k, ax, fixed(v, 6));
  }
  s += fmt::format("$AA_ENC_COMP_STEP[0,{}]={}\n", ax, fixed(step, 4));
  s += fmt::format("$AA_ENC_COMP_MIN[0,{}]=0.0\n", ax);
  s += fmt::format("$AA_ENC_COMP_MAX[0,{}]=360.0\n", ax);
  s += fmt::format("$AA_ENC_COMP_IS_MODULO[0,{}]=1\n", ax);
  s += "M17\n";
  t.setup = {fmt::format("MD32700 $MA_ENC_COMP_ENABLE[0] = 0 for axis {0}, MD38000 $MA_MM_ENC_COMP_MAX_POINTS[0] >= {1} "
                         "(memory reorganised at the next start-up), load the file, MD32700 = 1, reference the axis",
                         ax, n + 1)};
  return t;
}

CompTable csv(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  const int n = stepsPerTurn(step);
  const Grid g = grid(E, r.controller_sign, 0.0, step, n);
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  t.text = "controller_angle_deg,error_mdeg\n";
  for (const auto& row : g.rows) t.text += fmt::format("{},{}\n", fixed(row.controller_deg, 6), fixed(row.error_deg * 1e3, 6));
  t.setup = {"error_mdeg = actual - commanded angle in the control's counting; a control cancels it by commanding "
             "-error_mdeg more"};
  return t;
}

}  // namespace

std::string compTableRefusal(const std::string& d) {
  if (d == "heidenhain")
    return "heidenhain: no compensation table form is given by the sources (the TNC's axis-error compensation tables "
           "are machine configuration, OEM-protected: docs/dialects.md); give the table of --dialect csv to the machine "
           "builder";
  if (d == "okuma")
    return "okuma: no source gives the OSP's pitch / rotary compensation table form (docs/dialects.md); give the "
           "table of --dialect csv to the machine builder";
  if (d == "haas")
    return "haas: no source gives a user-loadable rotary compensation table for NGC (docs/dialects.md); give the table "
           "of --dialect csv to Haas service";
  if (std::find(compTableDialects().begin(), compTableDialects().end(), d) == compTableDialects().end())
    return "unknown dialect '" + d + "' (compensation tables: linuxcnc, fanuc, siemens, csv)";
  return "";
}

std::string stepRefusal(double step_deg) {
  try {
    stepsPerTurn(step_deg);
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
  stepsPerTurn(step);
  CompTable t = d == "linuxcnc" ? linuxcnc(r, E, step)
                : d == "fanuc"  ? fanuc(r, E, step)
                : d == "siemens" ? siemens(r, E, step)
                                 : csv(r, E, step);
  if (!std::isfinite(t.max_error_mdeg)) bad("the interpolated error is not finite");
  if (t.max_error_mdeg > kMaxAngleCorrectionMdeg && !r.force)
    bad(fmt::format("angular positioning error of {} up to {} mdeg exceeds the plausibility limit of {} mdeg (a setup "
                    "blunder, not a machine's error; --force to write it anyway)",
                    e.axis, fixed(t.max_error_mdeg, 3), fixed(kMaxAngleCorrectionMdeg, 0)));
  return t;
}

}  // namespace rotacal::ctl
