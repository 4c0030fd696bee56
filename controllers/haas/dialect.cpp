// Haas NGC: the Macro B program of macro_b.cpp with Haas's rules (../shared/reference/
// controllers.md Sec. 3): O + 5 digits, retained globals #10700.., G103 P1 so that DPRNT (which
// runs at look-ahead time) prints values that exist, DPRNT fields with a + b <= 8 for older
// controls, the same clock (#3011 date, #3012 time, #3001 ms timer). G31 without a signal
// completes silently, so the explicit no-trigger check with #3000 stays (M79 would alarm too,
// but the distance check is the same on every Macro B control).
//
// Results:
//   ROTACAL-RESULTS DIALECT HAAS CYCLE TOUCH154 POINTS 154 UNIT MM
//   DATE 20261122 TIME  14119
//   P17 X 123.4560 Y-200.0000 Z 173.0000 T   12345
//   END
// X Y Z = #5061-#5063 in work coordinates; #5063 includes the tool length compensation [HaasMan],
// so with G43 H<probe> it is the ball centre when the probe's length is to the ball centre.
//
// Offsets: MRZP = Settings 255/256/257 cannot be set from a macro [HaasMan 6.13.3]. The offsets
// file is a program that computes the new values from the current ones (#20255-#20257) into
// #10121-#10123 (where Haas's own VPS MRZP routine leaves them for manual entry), stops with a
// message, and shifts the G54 zero of the tilting axis.
#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "controllers/haas/mrzp.hpp"
#include "controllers/macro_b.hpp"
#include "controllers/offsets.hpp"
#include "controllers/program_writing.hpp"
#include "controllers/text.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

constexpr const char* kDialect = "haas";
using macro_b::comments;

MacroBFlavor haasFlavor() {
  MacroBFlavor f;
  f.name = kDialect;
  f.tag = "HAAS";
  f.title = "HAAS NGC MACRO";
  f.program_digits = 5;          // O + 5 digits [HaasMan]
  f.store_base = 10700;          // retained globals #10000-#10999 [HaasMan]
  f.max_points_per_pose = 70;    // #10700 + 4 * 70 - 1 = #10979 <= #10999
  f.lookahead_g103 = true;       // DPRNT runs at look-ahead time [HaasMan]
  f.dwell_word = 'P';            // G04 P2. = 2 s [HaasMan]
  f.notes = {"RESULTS: DPRNT TO THE DESTINATION OF SETTINGS 261-263 (FILE OR TCP PORT); POPEN AND PCLOS "
             "ARE KEPT FOR OLDER CONTROLS - THEIR EFFECT ON NGC IS UNVERIFIED",
             "SETTING 162 MAY BE OFF: EVERY AXIS AND FEED WORD HAS A DECIMAL POINT"};
  return f;
}

DialectIdentity haasIdentity() {
  DialectIdentity d = macro_b::identity();
  d.comp_table_refusal = "no source gives a user-loadable rotary compensation table for NGC (docs/dialects.md); give "
                         "the table of --dialect csv to Haas service";
  return d;
}

class HaasDialect final : public MacroBDialect {
 public:
  HaasDialect() : MacroBDialect(haasFlavor(), haasIdentity()) {}

  std::string writeOffsets(const OffsetRequest& r) const override {
    const ctl::OffsetBasis b(r, kDialect);
    const auto& [plan, m, e, ac, inch, k, tilt] = b;
    const auto changes = haasMrzpChanges(e);
    const double zero_deg = b.zeroDeg(kDialect);
    ctl::LineWriter w(comments);
    w.line("%");
    w.line("O09001(ROTACAL MRZP)");
    w.comment(fmt::format("ROTACAL MRZP CORRECTION, TABLE {}/C, HAAS NGC. PROVENANCE: {} CYCLE {} MACHINE {}", tilt,
                          r.report_file.empty() ? "NO REPORT" : r.report_file, plan.cycle, m.name));
    w.identified(r, "IDENTIFIED, PAPERS CONVENTION, VALUE +- STANDARD UNCERTAINTY K=1:");
    w.comment("WHAT IT CHANGES: MRZP SETTINGS 255 256 257 (MACHINE HOME TO THE ROTARY CENTRE, MACHINE UNITS) "
              "AND THE G54 ZERO OF THE TILTING AXIS.");
    w.comment("SETTINGS CANNOT BE SET FROM A MACRO: THIS PROGRAM PUTS THE NEW VALUES IN 10121 10122 10123 AND "
              "STOPS. ENTER THEM BY HAND ON THE SETTINGS PAGE, THEN CYCLE START.");
    w.comment(fmt::format("MAPPING UNVERIFIED ON A MACHINE: NEW = OLD + CHANGE, {}; OLD VALUES ARE READ ON THE "
                          "CONTROL FROM 20255-20257, NOT KNOWN HERE.",
                          inch ? "INCH" : "MM"));
    for (size_t i = 0; i < changes.size(); ++i)
      w.comment(fmt::format("SETTING {} {}: CHANGE {} {}", 255 + i, changes[i].first, ctl::fixed(changes[i].second * k, 4),
                            inch ? "IN" : "MM"));
    for (size_t i = 0; i < changes.size(); ++i) {
      const double d = changes[i].second * k;
      w.line(fmt::format("#{}=#{}{}{}", 10121 + i, 20255 + i, d < 0 ? "-" : "+", ctl::fixed(std::abs(d), 4)));
    }
    w.line("#3006=1(ENTER 10121-10123 IN SETTINGS 255-257)");
    w.comment(fmt::format("G54 {} ZERO: ADDS {} DEG (G10 L2 UNDER G91 ADDS TO THE OFFSET - CHECK THE G54 PAGE)", tilt,
                          ctl::fixed(zero_deg, 4)));
    w.line(fmt::format("G91 G10 L2 P1 {}{}", tilt, ctl::fixed(zero_deg, 4)));
    w.line("G90");
    w.comment(ac ? "REPORTED ONLY (NO SETTING TAKES THEM): DY-CA, B-AY, C-AY, B-CA."
                    : "REPORTED ONLY (NO SETTING TAKES THEM): DX-CB, A-BY, C-BY, A-CB.");
    w.line("M30");
    w.line("%");
    return w.text;
  }
};

}  // namespace

std::vector<std::pair<std::string, double>> haasMrzpChanges(const LocationErrors& e) {
  if (e.kinematics == Kinematics::TableAC)
    return {{"MRZP X", e.get("dx_AY")}, {"MRZP Y", e.get("dy_AY")}, {"MRZP Z", e.get("dz_AY")}};
  return {{"MRZP X", e.get("dx_BY")}, {"MRZP Y", e.get("dy_CB")}, {"MRZP Z", e.get("dz_BY")}};
}

const Dialect& haasDialect() { return singleton<HaasDialect>(); }

}  // namespace rotacal
