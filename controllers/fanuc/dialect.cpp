// Fanuc 0i/30i with Custom Macro B: G31 skip moves with an explicit no-trigger check (the skip
// ends silently at the end point without a signal), results through POPEN/DPRNT/PCLOS with the
// control's date/time (#3011/#3012) in the header and the ms timer #3001 per point (program,
// results and checker: macro_b.cpp), compensation as an incremental G54 shift
// (../shared/reference/controllers.md Sec. 2).
//
// Results, as the program's DPRNTs print them (rotacal's rendering, see macro_b::dprntNumber):
//   ROTACAL-RESULTS DIALECT FANUC CYCLE TOUCH154 POINTS 154 UNIT MM
//   DATE 20261122 TIME  14119
//   P17 X 123.4560 Y-200.0000 Z 173.0000 T   12345
//   END
// X Y Z = skip position #5061-#5063 in the work coordinates (G54 = rotary-axis intersection),
// program units, [44] = 4 integer + 4 decimal digits; T = ms timer #3001 ([80]), zeroed right
// after DATE/TIME were read; t_s = seconds of DATE TIME since 2000-01-01 + T / 1000.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "controllers/comp_table.hpp"
#include "controllers/macro_b.hpp"
#include "controllers/offsets.hpp"
#include "controllers/program_writing.hpp"
#include "controllers/text.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace ctl {
namespace {

constexpr long kFanucMaxValue = 32767;  // per point, detection units x magnification (UNVERIFIED)

// The rotary compensation table in this control's form (controllers/comp_table.hpp).
CompTable compTable(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  const int n = compTableStepsPerTurn(step);
  const int ref = r.fanuc_reference_point;
  const double unit = r.fanuc_detection_unit_deg;
  if (!(unit > 0.0 && unit <= 0.01)) throw std::invalid_argument(fmt::format("detection unit {} deg: expected 0.01 deg or finer", unit));
  if (ref < 0 || ref + n > 9999) throw std::invalid_argument(fmt::format("reference point number {} with {} points is out of range", ref, n));
  const CompTableGrid g = compTableGrid(E, r.controller_sign, 0.0, step, n + 1);
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
    throw std::invalid_argument(fmt::format("a pitch error compensation value of {} detection units exceeds {}", vmax, kFanucMaxValue));
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  const std::string ax = std::string(1, r.errors.axis);
  std::string& s = t.text;
  s += "ROTACAL PITCH ERROR COMPENSATION FOR FANUC, ROTARY AXIS " + ax + " (ENTRY SHEET, NOT A TAPE)\n";
  for (const auto& l : compTableProvenance(r, E, step)) s += l + "\n";
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

}  // namespace
}  // namespace ctl

namespace {

constexpr const char* kDialect = "fanuc";
using macro_b::comments;

MacroBFlavor fanucFlavor() {
  MacroBFlavor f;
  f.name = kDialect;
  f.tag = "FANUC";
  f.title = "FANUC CUSTOM MACRO B";
  f.program_digits = 4;
  f.store_base = 700;            // retained #700.. (#500-#999 survive power-off)
  f.max_points_per_pose = 70;    // #700 + 4 * 70 - 1 = #979 <= #999
  f.dwell_word = 'X';            // G04 X2. = 2 s (P would be integer ms); G04 is not in controllers.md: UNVERIFIED
  f.notes = {"RESULTS: POPEN AND DPRNT TO THE DEVICE OF PARAMETER 20 - UNVERIFIED PER MACHINE"};
  return f;
}

DialectIdentity fanucIdentity() {
  DialectIdentity d = macro_b::identity();
  d.comp_table = ctl::compTable;
  return d;
}

class FanucDialect final : public MacroBDialect {
 public:
  FanucDialect() : MacroBDialect(fanucFlavor(), fanucIdentity()) {}

  std::string writeOffsets(const OffsetRequest& r) const override {
    const ctl::OffsetBasis b(r, kDialect);
    const auto& [plan, m, e, ac, inch, k, tilt] = b;
    const std::string u = inch ? "INCH" : "MM";
    const Eigen::Vector3d shift = b.pivot();
    const double zero_deg = b.zeroDeg(kDialect);
    const Eigen::Vector3d second = b.second();

    ctl::LineWriter w(comments);
    w.line("%");
    w.comment(fmt::format("ROTACAL G54 CORRECTION, TABLE {}/C, FANUC. RUN IN MDI OR A SETUP PROGRAM.", tilt));
    w.comment(fmt::format("PROVENANCE: {} CYCLE {} MACHINE {}", r.report_file.empty() ? "NO REPORT" : r.report_file,
                          plan.cycle, m.name));
    w.identified(r, "IDENTIFIED, PAPERS CONVENTION, VALUE +- STANDARD UNCERTAINTY K=1:");
    w.comment(fmt::format("SHIFTS G54 BY THE {} PIVOT AND THE {} ZERO ERROR. G10 L2 UNDER G91 ADDS TO THE OFFSET - "
                          "UNVERIFIED: CHECK THE G54 PAGE BEFORE AND AFTER.",
                          tilt, tilt));
    w.line(fmt::format("G91 G10 L2 P1 X{} Y{} Z{} {}{}", ctl::fixed(shift.x() * k, 4), ctl::fixed(shift.y() * k, 4),
                       ctl::fixed(shift.z() * k, 4), tilt, ctl::fixed(zero_deg, 4)));
    w.line("G90");
    w.comment(ac ? "NOT APPLIED BY THE SHIFT, REPORTED ONLY: DY-CA, B-AY, C-AY, B-CA."
                    : "NOT APPLIED BY THE SHIFT, REPORTED ONLY: DX-CB, A-BY, C-BY, A-CB.");
    w.comment(fmt::format(
        "WITH TCP: PARAMETERS 19700-19702 ROTARY TABLE POSITION, ADD X {} Y {} Z {} {} - OLD VALUES NOT KNOWN HERE, "
        "PARAMETER NUMBERS AND UNITS UNVERIFIED.",
        ctl::fixed(shift.x() * k, 4), ctl::fixed(shift.y() * k, 4), ctl::fixed(shift.z() * k, 4), u));
    w.comment(fmt::format("PARAMETERS 19703-19705 OFFSET 1ST TO 2ND TABLE AXIS, ADD X {} Y {} Z {} {} - UNVERIFIED.",
                          ctl::fixed(second.x() * k, 4), ctl::fixed(second.y() * k, 4), ctl::fixed(second.z() * k, 4),
                          u));
    w.line("%");
    return w.text;
  }
};

}  // namespace

const Dialect& fanucDialect() { return singleton<FanucDialect>(); }

}  // namespace rotacal
