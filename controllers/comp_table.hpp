#pragma once
// Rotary-axis compensation tables in the controller's own form: the angular positioning error of
// a rotary axis (ISO 230-7: E_CC for the C axis, the error of the angle the table actually turns
// to, as a function of the commanded angle) written as the control's axis / pitch compensation
// table. Forms, sources and what is UNVERIFIED: docs/dialects.md "Compensation tables".
//
// Signs. Input angles and errors are in the papers' convention (docs/conventions.md): a positive
// commanded angle turns a table by minus that angle about its axis, and a positive E_CC turns the
// table about +Z (right hand). So the table reaches the papers' angle C - E_CC(C), and in the
// control's counting (theta = s C, s = MachineModel::controllerSign) the axis stands at
//     theta_actual = theta - s E(theta / s):  positioning error e(theta) = -s E(theta / s).
// Every table is written in the control's counting, from e(theta).
#include <string>
#include <vector>

namespace rotacal::ctl {

/// The angular positioning error of one rotary axis, sampled at equally spaced angles over a full
/// turn (the identification's angles). Angles in the papers' convention (deg), errors and their standard
/// uncertainties in mdeg (u may be empty).
struct AngularPositionErrors {
  char axis = 'C';
  std::vector<double> angle_deg;
  std::vector<double> error_mdeg;
  std::vector<double> u_mdeg;
};

/// Trigonometric interpolation through N equally spaced samples over a full turn: the unique
/// trigonometric polynomial of harmonics 0 .. N/2 - 1 (plus cos(N/2 (x - x0)) for even N) through
/// the samples; it reproduces any Fourier series of those harmonics exactly, at every angle.
/// Throws std::invalid_argument for fewer than 3 samples, unequal spacing (more than 1e-6 deg off
/// 360/N after sorting modulo 360) or non-finite values.
class PeriodicInterpolant {
 public:
  PeriodicInterpolant(const std::vector<double>& angle_deg, const std::vector<double>& value);
  double operator()(double angle_deg) const;
  int samples() const { return n_; }

 private:
  int n_ = 0;
  double x0_deg_ = 0.0;
  std::vector<double> a_, b_;  // cos / sin coefficients of harmonics 0 .. n/2
};

struct CompTableRequest {
  AngularPositionErrors errors;
  std::string dialect;          // one of compTableDialects() (the others are refused)
  int controller_sign = 1;      // commanded controller angle = sign * papers' angle
  double step_deg = 0.0;        // table spacing in the control's counting; 0 = the dialect's default
  /// Extent of the LinuxCNC table in the control's counting (deg). Empty range (lo >= hi): one
  /// turn each side of 0, [-360, 360] (a continuous axis). Other dialects cover one turn.
  double range_lo_deg = 0.0, range_hi_deg = 0.0;
  int fanuc_reference_point = 0;  // pitch error compensation point number of the reference position
  double fanuc_detection_unit_deg = 0.001;  // IS-B; 0.0001 for IS-C (the machine's, UNVERIFIED per machine)
  std::string source;           // provenance (the report's path), for the file's comments
  bool force = false;           // accept an error beyond the plausibility limit (100 mdeg)
};

/// One row of a written table, for tests and the summary: the control's angle and the error the
/// table cancels there (deg, control's counting).
struct CompTableRow {
  double controller_deg = 0.0;
  double error_deg = 0.0;
};

struct CompTable {
  std::string text;                 // the file
  std::vector<CompTableRow> rows;   // the grid the file holds
  std::vector<std::string> setup;   // what must be set on the control besides the file (one line each)
  double max_error_mdeg = 0.0;      // largest |e| on the grid
};

/// Positioning error e(theta) (deg, control's counting) of the interpolated papers' error E.
double controllerError_deg(const PeriodicInterpolant& E_mdeg, int controller_sign, double controller_deg);

/// The table in the dialect's form. Throws std::invalid_argument naming the problem: a dialect
/// that has no verified form (heidenhain, okuma, haas), bad samples, a step that does not divide
/// 360 or exceeds the control's point count, or an error beyond the plausibility limit of the
/// offsets writers (kMaxAngleCorrectionMdeg) without force.
CompTable writeCompTable(const CompTableRequest& request);

/// The dialects that write a table, for --help and messages: the controllers' own forms in the
/// registry's order, then the neutral one.
const std::vector<std::string>& compTableDialects();

/// Why `dialect` gets no table ("" when it gets one): the dialect's comp_table_refusal where it
/// has no form in the sources; anything else not in compTableDialects() is unknown.
std::string compTableRefusal(const std::string& dialect);

// ---- What every dialect's table form (DialectIdentity::comp_table) is written with ----

/// The table's points over one turn: 360 / step_deg. Throws std::invalid_argument when the step is
/// not > 0 and <= 90 deg or does not divide 360 deg into whole steps.
int compTableStepsPerTurn(double step_deg);

/// `count` rows from `lo` every `step` deg (control's counting) and the largest |e| among them.
struct CompTableGrid {
  std::vector<CompTableRow> rows;
  double max_abs_mdeg = 0.0;
};
CompTableGrid compTableGrid(const PeriodicInterpolant& E_mdeg, int controller_sign, double lo, double step, int count);

/// Where a table comes from, one line each, for its comments: axis, source, spacing, uncertainty.
std::vector<std::string> compTableProvenance(const CompTableRequest& request, const PeriodicInterpolant& E_mdeg,
                                             double step);

/// Why a table spacing cannot be used ("" when it can): it must be > 0, at most 90 deg and divide
/// 360 deg into whole steps.
std::string stepRefusal(double step_deg);

}  // namespace rotacal::ctl
