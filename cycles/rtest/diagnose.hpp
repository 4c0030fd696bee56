#pragma once
// The thermal_drift cause (issue 6) on R-test series (002): do the position-dependent errors of
// 002 Table 2 change with time across the measuring cycles?
//  - per error and tilt, the slope of the per-cycle estimates over time against its standard
//    uncertainty, widened by the scatter of the cycles about the line (so that slow chatter,
//    e.g. a quantised spindle growth, counts as scatter, not as drift); a Student t test with
//    the cycles' degrees of freedom, Bonferroni over the 6 x (tilts) slopes;
//  - the gain measured on held-out data: leave one cycle out, fit the constant model and the
//    drift model (errors + rates, 002 Eq. (6) over all cycles) to the others, predict the
//    readings of the left-out cycle.
// A drift is reported only when a slope passes the test and the held-out residual drops.
#include <string>
#include <vector>

#include "core/json_io.hpp"
#include "core/probe_plan.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/rtest/analyze.hpp"
#include "core/statistics.hpp"  // studentTwoSided

namespace rotacal {

struct RtestDiagnosisOptions {
  double alpha = 1e-3;             // family-wise false-alarm rate of the slope tests
  double min_holdout_gain = 0.02;  // held-out rms must drop by at least this fraction
  double sensor_sigma_um = 0.2;
  void validate() const;  // throws std::invalid_argument
};

struct RtestDriftTest {
  int param = 0, tilt = 0;
  double rate = 0.0, u = 0.0;  // per second, mm or rad
  double t = 0.0;              // rate / u
  double p_value = 1.0;        // two-sided, Student t with cycles - 2 dof
  bool significant = false;
};

struct RtestDiagnosis {
  RtestAnalysis analysis;
  int cycles = 0;
  double baseline_rms_um = 0.0, baseline_holdout_rms_um = 0.0;
  double drift_rms_um = 0.0, drift_holdout_rms_um = 0.0;
  double gain_pct = 0.0;
  std::vector<RtestDriftTest> tests;
  bool drift_found = false;
  std::string reason;  // why not, when not
};

RtestDiagnosis diagnoseRtest(const ProbePlan& plan, const std::vector<RtestCycle>& cycles,
                             const RtestDiagnosisOptions& options);
Json rtestDiagnosisJson(const ProbePlan& plan, const RtestDiagnosis& d);
std::string rtestDiagnosisText(const ProbePlan& plan, const RtestDiagnosis& d);

}  // namespace rotacal
