#pragma once
// Checks every controller dialect must pass, with values computed another way than the
// dialect's own code: the round trip of writeResults -> parseResults within the printed digits,
// the recovery of injected location errors through plan -> simulate -> writeResults ->
// parseResults -> identify, the checker on generated programs (mm and inch; touch154 exists for A/C only), and the
// plausibility limit of the offset writer.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <regex>
#include <stdexcept>
#include <string>
#include <utility>

#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/simulation.hpp"
#include "core/units.hpp"
#include "ctl_test_util.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal::test {

/// 000 Table 4 mean (um / mdeg), order of locationParameters(TableAC).
inline const double kTable4[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};

inline LocationErrors table4() {
  LocationErrors e;
  e.kinematics = Kinematics::TableAC;
  for (int i = 0; i < 8; ++i) e.setReportValue(i, kTable4[i]);
  return e;
}

/// Time handling of a dialect's results.
enum class Clock { None, Milliseconds, Seconds };

/// `back` is `run` read back from a results text: the same ids in the same order, positions within
/// `tol_mm`, times as the clock prints them (ms: within `ms_tol_s`).
inline void expectReadBack(const MeasurementRun& back, const MeasurementRun& run, double tol_mm, Clock clock,
                           double ms_tol_s = 0.5e-3 + 1e-6) {
  ASSERT_EQ(back.points.size(), run.points.size());
  for (size_t i = 0; i < back.points.size(); ++i) {
    EXPECT_EQ(back.points[i].point_id, run.points[i].point_id);
    EXPECT_LE((back.points[i].position_m_mm - run.points[i].position_m_mm).cwiseAbs().maxCoeff(), tol_mm)
        << "point " << run.points[i].point_id;
    switch (clock) {
      case Clock::None: EXPECT_TRUE(std::isnan(back.points[i].t_s)); break;
      case Clock::Milliseconds: EXPECT_NEAR(back.points[i].t_s, run.points[i].t_s, ms_tol_s); break;
      // the control prints the current second: the floor of the true time.
      case Clock::Seconds: EXPECT_EQ(back.points[i].t_s, std::floor(run.points[i].t_s)); break;
    }
  }
}

/// writeResults -> parseResults: same ids in the same order, positions within half a unit of
/// the printed `decimals` (in the printed unit), times as the clock prints them (ms printed as
/// integers: within 0.5 ms, 1e-6 s more for the double sum near 7.5e8 s).
inline void expectRoundTrip(const Dialect& d, const ProbePlan& plan, double printed_unit_mm, int decimals, Clock clock) {
  MeasurementRun run = displacedRun(plan);
  for (auto& p : run.points) p.t_s += 7.5e8;  // 2023-10-07: a real date on the common epoch
  const std::string text = d.writeResults(plan, run);
  const MeasurementRun back = d.parseResults(text, "res.txt", plan);
  expectReadBack(back, run, 0.5 * std::pow(10.0, -decimals) * printed_unit_mm + 1e-12, clock);
}

/// plan -> simulate (000 Table 4 errors, setup error, no noise) -> writeResults -> parseResults
/// -> identify. The only perturbation is the printed rounding, at most half a unit of the 4th
/// decimal per coordinate (uniform, sigma = 0.5e-4 mm / sqrt(3) = 0.029 um): the least squares
/// estimate then differs from the truth by a few standard uncertainties computed from that
/// residual. Bound: 5 u (the rounding is bounded, so a 5-sigma excursion over 8 parameters does
/// not happen), plus 1e-6 um for the solver's own tolerance.
inline void expectRecovery(const Dialect& d, const ProbePlan& plan) {
  Truth truth;
  truth.errors = table4();
  truth.artefact.setup.translation_mm = Eigen::Vector3d(0.5, -0.3, 0.2);
  truth.start_time_s = 7.5e8;
  const MeasurementRun sim = simulate(plan, truth, {1});
  const MeasurementRun run = d.parseResults(d.writeResults(plan, sim), "sim.txt", plan);
  const IdentificationResult r = identify(plan, {run}, IdentificationOptions{});
  ASSERT_EQ(r.summary.termination, Termination::Converged) << r.summary.message;
  const auto& params = locationParameters(Kinematics::TableAC);
  for (int i = 0; i < 8; ++i) {
    const bool length = params[static_cast<size_t>(i)].kind == ParamKind::Length;
    const double u = length ? mmToUm(r.u[i]) : radToMdeg(r.u[i]);
    EXPECT_GT(u, 0.0);
    EXPECT_NEAR(r.estimate.reportValue(i), kTable4[i], 5 * u + 1e-6) << params[static_cast<size_t>(i)].name;
    // And the rounding alone cannot move an estimate by more than a few tenths of a um / mdeg.
    EXPECT_NEAR(r.estimate.reportValue(i), kTable4[i], 0.1) << params[static_cast<size_t>(i)].name;
  }
}

/// A dialect's touch154 program for the A/C plan: its text, its lines and `g`, the first line
/// that matches `probing_move` (a regex; "" for line 0). What each dialect's program tests read,
/// what `PlantedFaults` edits and what `expectCleanPrograms` checks.
struct WrittenProgram {
  WrittenProgram(const std::string& dialect, const std::string& probing_move = "",
                 LengthUnit units = LengthUnit::Millimetre)
      : plan(acPlan(units)),
        text(dialectByName(dialect).writeProgram(cycleProgram(plan, dialect))),
        ls(lines(text)),
        g(firstMatch(ls, std::regex(probing_move))) {}
  static size_t firstMatch(const std::vector<std::string>& ls, const std::regex& re) {
    for (size_t i = 0; i < ls.size(); ++i)
      if (std::regex_search(ls[i], re)) return i;
    throw std::runtime_error("no line of the program matches");
  }

  ProbePlan plan;
  std::string text;
  std::vector<std::string> ls;
  size_t g;
};

inline void expectCleanPrograms(const Dialect& d) {
  for (LengthUnit u : {LengthUnit::Millimetre, LengthUnit::Inch}) {
    const WrittenProgram p(std::string(d.name()), "", u);
    EXPECT_EQ(d.check(p.text, p.plan, test::shapeOf(p.plan, std::string(d.name()))), std::vector<std::string>{}) << d.name();
    EXPECT_EQ(p.text.find("-0.0000"), std::string::npos);
  }
}

inline OffsetRequest table4Request(const ProbePlan& plan) {
  OffsetRequest r;
  r.plan = &plan;
  r.identified = table4();
  r.u.setConstant(1e-6);
  r.report_file = "out/report.json";
  return r;
}

/// The offset writer refuses dx_AY = 0.7 mm (limit 0.5 mm) unless forced, and then writes it.
inline void expectPlausibilityLimit(const Dialect& d, const ProbePlan& plan, const std::string& forced_text) {
  OffsetRequest r = table4Request(plan);
  r.identified.set("dx_AY", 0.7);
  const std::string e = messageOf<std::invalid_argument>([&] { d.writeOffsets(r); });
  EXPECT_NE(e.find("exceeds the plausibility limit"), std::string::npos) << e;
  r.force = true;
  EXPECT_NE(d.writeOffsets(r).find(forced_text), std::string::npos) << d.writeOffsets(r);
}

/// The parser's InputError for `text`, "" when it accepts it.
inline std::string parseError(const Dialect& d, const std::string& text, const ProbePlan& plan) {
  return messageOf<InputError>([&] { d.parseResults(text, "res.txt", plan); });
}

inline bool hasProblem(const std::vector<std::string>& ps, const std::string& what) {
  for (const auto& p : ps)
    if (p.find(what) != std::string::npos) return true;
  return false;
}

/// A dialect's results of the A/C plan (the displaced run) as lines, and what its parser says of
/// a copy in which `edit` has planted a fault: the fault must be named at "res.txt:LINE: what".
/// `eol` joins the edited lines (CR LF, as a Fanuc punch writes them, or LF).
class WrittenResults : public ::testing::Test {
 protected:
  explicit WrittenResults(const std::string& dialect, std::string eol = "\n")
      : d(dialectByName(dialect)), eol_(std::move(eol)) {}
  /// `line` for "the edited copy's last line" (a missing point or END is reported there).
  static constexpr size_t kLastLine = 0;
  void expectAt(const std::function<void(std::vector<std::string>&)>& edit, size_t line, const std::string& what) const {
    auto v = ls;
    edit(v);
    if (line == kLastLine) line = v.size();
    const std::string e = parseError(d, join(v, eol_), plan);
    EXPECT_NE(e.find(fmt::format("res.txt:{}: {}", line, what)), std::string::npos) << e;
  }

  const Dialect& d;
  ProbePlan plan = acPlan();
  std::vector<std::string> ls = lines(d.writeResults(plan, displacedRun(plan)));

 private:
  std::string eol_;
};

/// What the dialect's checker finds once `edit` has planted a fault in a copy of the program's
/// lines.
class PlantedFaults : public ::testing::Test {
 protected:
  PlantedFaults(const std::string& dialect, const std::string& probing_move)
      : dialect_(dialect), p(dialect, probing_move), plan(p.plan), ls(p.ls), g(p.g) {}
  std::vector<std::string> with(const std::function<void(std::vector<std::string>&)>& edit) const {
    auto v = ls;
    edit(v);
    return dialectByName(dialect_).check(join(v), plan, shapeOf(plan, dialect_));
  }

 private:
  std::string dialect_;
  WrittenProgram p;

 protected:
  const ProbePlan& plan;
  const std::vector<std::string>& ls;
  size_t g;
};

}  // namespace rotacal::test
