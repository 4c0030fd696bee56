#include "controllers/offsets.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "controllers/text.hpp"
#include "core/units.hpp"

namespace rotacal::ctl {

void requireNotHeadCb(const OffsetRequest& r) {
  // Its parameters are its model's, not eight location errors; one form of them is verified.
  if (r.identified.kinematics == Kinematics::HeadCB)
    throw std::invalid_argument(
        "a head_cb machine's parameters go into its control's kinematics, and rotacal knows that form only for "
        "LinuxCNC's 5axiskins (--dialect linuxcnc: a .hal file with its pivot length, a .ngc file with the B and C "
        "zeros); here enter REPORT.json's kinematic_parameters by hand");
}

std::string implausibility(Kinematics kinematics, int index, double v) {
  const auto& p = locationParameters(kinematics).at(static_cast<size_t>(index));
  if (!std::isfinite(v)) return fmt::format("{} is not a finite number; nothing written", p.name);
  if (p.kind == ParamKind::Length && std::abs(v) > kMaxLengthCorrectionMm)
    return fmt::format("{} = {:.4f} mm exceeds the plausibility limit of {} mm: check the setup and the results, or "
                       "force it",
                       p.name, v, kMaxLengthCorrectionMm);
  if (p.kind == ParamKind::Angle && std::abs(radToMdeg(v)) > kMaxAngleCorrectionMdeg)
    return fmt::format("{} = {:.1f} mdeg exceeds the plausibility limit of {} mdeg: check the setup and the results, "
                       "or force it",
                       p.name, radToMdeg(v), kMaxAngleCorrectionMdeg);
  return "";
}

namespace {
// The plausibility of one of a head machine's parameters, as implausibility() judges the papers' eight.
std::string implausibility(const ParameterEstimate& p) {
  if (!std::isfinite(p.value)) return fmt::format("{} is not a finite number; nothing written", p.name);
  if (p.kind == ParamKind::Length && std::abs(p.value) > kMaxLengthCorrectionMm)
    return fmt::format("{} = {:.4f} mm exceeds the plausibility limit of {} mm: check the setup and the results, or "
                       "force it",
                       p.name, p.value, kMaxLengthCorrectionMm);
  if (p.kind == ParamKind::Angle && std::abs(radToMdeg(p.value)) > kMaxAngleCorrectionMdeg)
    return fmt::format("{} = {:.1f} mdeg exceeds the plausibility limit of {} mdeg: check the setup and the results, "
                       "or force it",
                       p.name, radToMdeg(p.value), kMaxAngleCorrectionMdeg);
  return "";
}
}  // namespace

const ParameterEstimate* kinematicParameter(const OffsetRequest& r, std::string_view name) {
  for (const auto& p : r.parameters)
    if (p.name == name) return &p;
  return nullptr;
}

std::string headTableOffsetsRefusal(std::string_view dialect) {
  return fmt::format(
      "a head_table machine's kinematic parameters go into the control's kinematics description (Heidenhain's "
      "kinematics table, Siemens' $TC_CARR, Fanuc's TCP parameters), and rotacal knows that form only for LinuxCNC's "
      "maxkins (--dialect linuxcnc: a .hal file for its pivot-length, a .ngc file for the work offset); none is "
      "confirmed for {} in rotacal's sources (docs/dialects.md): enter REPORT.json's kinematic_parameters by hand",
      dialect);
}

void requirePlausible(const OffsetRequest& r) {
  if (!r.plan) throw std::invalid_argument("offset request without a plan");
  requireNotHeadCb(r);
  if (r.identified.kinematics != r.plan->machine.kinematics)
    throw std::invalid_argument("identified errors are for another kinematics than the plan's machine");
  if (r.identified.kinematics == Kinematics::HeadTable) {
    if (r.parameters.empty())
      throw std::invalid_argument("a head_table offset request without its kinematic parameters");
    for (const auto& p : r.parameters) {
      if (p.held || (r.force && std::isfinite(p.value))) continue;
      const std::string why = implausibility(p);
      if (!why.empty()) throw std::invalid_argument(why);
    }
    return;
  }
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const double v = r.identified.values[i];
    if (r.force && std::isfinite(v)) continue;
    const std::string why = implausibility(r.identified.kinematics, i, v);
    if (!why.empty()) throw std::invalid_argument(why);
  }
}

std::vector<std::string> identifiedLines(const OffsetRequest& r) {
  std::vector<std::string> out;
  if (r.identified.kinematics == Kinematics::HeadTable) {
    for (const auto& p : r.parameters) {
      const bool len = p.kind == ParamKind::Length;
      if (p.held) {
        out.push_back(
            fmt::format("{:<6} held at nominal: one sphere cannot separate it (REPORT.json unseparable)", p.name));
        continue;
      }
      const double u = len ? mmToUm(p.u) : radToMdeg(p.u);
      out.push_back(fmt::format("{:<6} {:>10} {:<4} +- {} {}", p.name,
                                fixed(len ? mmToUm(p.value) : radToMdeg(p.value), 3), reportUnit(p.kind),
                                std::isfinite(u) ? fixed(u, 3) : std::string("?"), reportUnit(p.kind)));
    }
    return out;
  }
  const auto& params = locationParameters(r.identified.kinematics);
  for (int i = 0; i < kNumLocationErrors; ++i) {
    const ParamKind k = params[i].kind;
    const double u = k == ParamKind::Length ? mmToUm(r.u[i]) : radToMdeg(r.u[i]);
    out.push_back(fmt::format("{:<6} {:<8} {:>10} {:<4} +- {} {}", params[i].name, params[i].iso,
                              fixed(r.identified.reportValue(i), 3), reportUnit(k),
                              std::isfinite(u) ? fixed(u, 3) : std::string("?"), reportUnit(k)));
  }
  return out;
}

namespace {
// The A/B table's offsets have one verified form, LinuxCNC's xyzab_tdr_kins pins; the other
// controls' forms are written for a tilt axis carrying a C table.
const OffsetRequest& requireTiltAndC(const OffsetRequest& r, std::string_view dialect) {
  if (r.identified.kinematics == Kinematics::HeadTable)
    throw std::invalid_argument(headTableOffsetsRefusal(dialect));
  if (r.identified.kinematics == Kinematics::TableAB)
    throw std::invalid_argument(
        "a table_ab machine's location errors go into its control's kinematics, and rotacal knows that form only for "
        "LinuxCNC's xyzab_tdr_kins (--dialect linuxcnc, a .hal file); here use rotacal compensate (the program "
        "rewritten for all eight) or enter REPORT.json's values by hand");
  return r;
}
}  // namespace

OffsetBasis::OffsetBasis(const OffsetRequest& r, std::string_view dialect)
    : plan((requirePlausible(requireTiltAndC(r, dialect)), *r.plan)),
      machine(plan.machine),
      e(r.identified),
      ac(e.kinematics == Kinematics::TableAC),
      inch(machine.units == LengthUnit::Inch),
      k(inch ? 1.0 / kMmPerInch : 1.0),
      tilt(ac ? 'A' : 'B') {}

Eigen::Vector3d OffsetBasis::pivot() const {
  return ac ? Eigen::Vector3d(e.get("dx_AY"), e.get("dy_AY"), e.get("dz_AY"))
            : Eigen::Vector3d(e.get("dx_BY"), e.get("dy_CB"), e.get("dz_BY"));
}

Eigen::Vector3d OffsetBasis::second() const {
  return ac ? Eigen::Vector3d(0, e.get("dy_CA"), 0) : Eigen::Vector3d(e.get("dx_CB"), 0, 0);
}

double OffsetBasis::zeroDeg(std::string_view dialect) const {
  return (machine.hasRotary(tilt) ? machine.controllerSign(tilt, std::string(dialect)) : 1) *
         radToDeg(e.get(ac ? "a_AY" : "b_BY"));
}

}  // namespace rotacal::ctl
