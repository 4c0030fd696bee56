#include "postproc/report_errors.hpp"

#include <cmath>
#include <map>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "controllers/offsets.hpp"
#include "core/errors.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace {

constexpr std::array<const char*, 4> kAxisLocationIso = {"X0C", "Y0C", "A0C", "B0C"};

// The kinematics' location error that carries each of X0C Y0C A0C B0C at the tilt axis's zero
// (000 Eq. (1), 002 Eq. (2)-(3); 001 Table 1): the C axis's own terms where the chain has
// them, the tilt axis's where the C axis's would be redundant.
std::array<const char*, 4> axisLocationTargets(Kinematics k) {
  if (k == Kinematics::TableAC) return {"dx_AY", "dy_CA", "a_AY", "b_CA"};
  return {"dx_CB", "dy_CB", "a_CB", "b_BY"};
}


// A value of a report entry {"value", "unit"} in mm or rad.
double valueIn(const JsonDoc& doc, const Json& entry, const std::string& name, ParamKind kind, const char* key = "value") {
  const double v = requireNumber(doc, entry, key);
  const std::string unit = requireString(doc, entry, "unit");
  if (kind == ParamKind::Length) {
    if (unit == "um") return umToMm(v);
    if (unit == "mm") return v;
    doc.fail(entry, "unit", "unit of '" + name + "' must be um or mm");
  }
  if (unit == "mdeg") return mdegToRad(v);
  if (unit == "urad") return v * 1e-6;
  if (unit == "rad") return v;
  doc.fail(entry, "unit", "unit of '" + name + "' must be mdeg, urad or rad");
}

double toReport(double v, ParamKind kind) { return kind == ParamKind::Length ? mmToUm(v) : radToMdeg(v); }

void checkFormat(const JsonDoc& doc) {
  const Json& j = doc.value;
  if (!j.is_object() || !j.contains("format") || j["format"] != "rotacal-report/1")
    doc.fail(j, "format", "not a rotacal report (expected \"format\": \"rotacal-report/1\")");
}

// The location errors of a full report, with their covariance when the report's uncertainty
// block gives it in the same order.
struct FullLocation {
  LocationErrors values;
  std::optional<Eigen::Matrix<double, kNumLocationErrors, kNumLocationErrors>> covariance;
  ErrorVector u = ErrorVector::Zero();  // report's u (k = 1), mm / rad; 0 when absent
};

FullLocation readFullLocation(const JsonDoc& doc, Kinematics k, bool force) {
  const Json& errs = doc.value["location_errors"];
  FullLocation out;
  out.values.kinematics = k;
  for (const auto& [name, entry] : errs.items()) {
    const int i = parameterIndex(k, name);
    if (i < 0) doc.fail(errs, name, "'" + name + "' is not a location error of this machine's kinematics");
    if (!entry.is_object()) doc.fail(errs, name, "'" + name + "' needs {\"value\": number, \"unit\": ...}");
    const ParamKind kind = locationParameters(k)[i].kind;
    out.values.values[i] = valueIn(doc, entry, name, kind);
    if (entry.contains("u")) out.u[i] = valueIn(doc, entry, name, kind, "u");
    const std::string why = ctl::implausibility(k, i, out.values.values[i]);
    if (!why.empty() && !force) doc.fail(errs, name, why + " (--force)");
  }
  const Json& j = doc.value;
  if (j.contains("uncertainty") && j["uncertainty"].is_object() && j["uncertainty"].contains("covariance")) {
    const Json& ub = j["uncertainty"];
    const Json& order = requireArray(doc, ub, "order");
    const Json& units = requireArray(doc, ub, "units");
    const Json& cov = requireArray(doc, ub, "covariance");
    if (units.size() != order.size() || cov.size() != order.size())
      doc.fail(ub, "covariance", "the covariance must be n x n in the order of 'order', with a unit per name");
    // A covariance may be of a larger fit (one sphere's fits the sphere's set-up and the linear
    // axes' squareness beside the location errors, under their ISO 230-7 names): each location
    // error is found under its own name or the fit's name its entry gives ('parameter'), and
    // its block is their covariance (the marginal of a normal is its sub-block).
    std::map<std::string, int> name_to_error;
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const std::string name(locationParameters(k)[static_cast<size_t>(i)].name);
      name_to_error[name] = i;
      const Json& entry = errs[name];
      if (entry.contains("parameter") && entry["parameter"].is_string())
        name_to_error[entry["parameter"].get<std::string>()] = i;
    }
    std::vector<int> index(order.size(), -1);
    std::vector<double> scale(order.size(), 0.0);  // report unit -> mm or rad
    std::array<bool, kNumLocationErrors> found{};
    for (size_t a = 0; a < order.size(); ++a) {
      if (!order[a].is_string()) doc.fail(ub, "order", "'order' must list parameter names");
      const auto it = name_to_error.find(order[a].get<std::string>());
      if (it == name_to_error.end()) continue;
      index[a] = it->second;
      found[static_cast<size_t>(it->second)] = true;
      const std::string u = units[a].is_string() ? units[a].get<std::string>() : "";
      scale[a] = u == "um" ? 1e-3 : u == "mdeg" ? mdegToRad(1.0) : 0.0;
      if (scale[a] == 0.0) doc.fail(ub, "units", "covariance units must be um or mdeg");
    }
    for (int i = 0; i < kNumLocationErrors; ++i)
      if (!found[static_cast<size_t>(i)])
        doc.fail(ub, "order", fmt::format("the covariance has no row for {} (under its name or its entry's 'parameter')",
                                          locationParameters(k)[static_cast<size_t>(i)].name));
    Eigen::Matrix<double, kNumLocationErrors, kNumLocationErrors> c;
    for (size_t a = 0; a < order.size(); ++a) {
      if (!cov[a].is_array() || cov[a].size() != order.size())
        doc.fail(ub, "covariance", fmt::format("row {} of the covariance must have {} numbers", a + 1, order.size()));
      for (size_t b = 0; b < order.size(); ++b) {
        if (!cov[a][b].is_number()) doc.fail(ub, "covariance", "the covariance must hold numbers");
        if (index[a] >= 0 && index[b] >= 0) c(index[a], index[b]) = cov[a][b].get<double>() * scale[a] * scale[b];
      }
    }
    if (!c.allFinite() || (c - c.transpose()).cwiseAbs().maxCoeff() > 1e-9 * (c.cwiseAbs().maxCoeff() + 1e-300))
      doc.fail(ub, "covariance", "the covariance must be finite and symmetric");
    out.covariance = c;
  }
  return out;
}

struct AxisLocation {
  Eigen::Vector4d values = Eigen::Vector4d::Zero();  // X0C Y0C (mm), A0C B0C (rad)
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
};

AxisLocation readAxisLocation(const JsonDoc& doc, bool force) {
  const Json& errs = doc.value["location_errors"];
  AxisLocation out;
  std::array<bool, 4> seen{};
  for (const auto& [name, entry] : errs.items()) {
    if (!entry.is_object() || !entry.contains("iso") || !entry["iso"].is_string())
      doc.fail(errs, name, "'" + name + "' names no ISO 230-7 location ('iso')");
    const std::string iso = entry["iso"].get<std::string>();
    int i = -1;
    for (int a = 0; a < 4; ++a)
      if (iso == kAxisLocationIso[static_cast<size_t>(a)]) i = a;
    if (i < 0) doc.fail(entry, "iso", "'" + iso + "' is not a location of the C axis at the tilt axis's zero (X0C Y0C A0C B0C)");
    const ParamKind kind = i < 2 ? ParamKind::Length : ParamKind::Angle;
    out.values[i] = valueIn(doc, entry, name, kind);
    if (entry.contains("u")) out.u[i] = valueIn(doc, entry, name, kind, "u");
    seen[static_cast<size_t>(i)] = true;
    const double limit = kind == ParamKind::Length ? ctl::kMaxLengthCorrectionMm : mdegToRad(ctl::kMaxAngleCorrectionMdeg);
    if (!(std::abs(out.values[i]) <= limit) && !force)
      doc.fail(errs, name, fmt::format("{} = {:.1f} {} is beyond the plausibility limit of a correction ({} {}) (--force)",
                                       iso, toReport(out.values[i], kind), reportUnit(kind),
                                       kind == ParamKind::Length ? mmToUm(ctl::kMaxLengthCorrectionMm)
                                                                 : ctl::kMaxAngleCorrectionMdeg,
                                       reportUnit(kind)));
  }
  for (int a = 0; a < 4; ++a)
    if (!seen[static_cast<size_t>(a)])
      doc.fail(errs, "", fmt::format("'location_errors' lacks {}: the C axis's location needs X0C Y0C A0C B0C",
                                     kAxisLocationIso[static_cast<size_t>(a)]));
  return out;
}

ComponentErrors readComponents(const JsonDoc& doc, bool force) {
  const Json& ce = requireObject(doc, doc.value, "component_errors");
  ComponentErrors out;
  std::optional<char> axis;
  std::array<bool, kNumComponentErrors> seen{};
  for (const auto& [name, entry] : ce.items()) {
    if (name.size() != 3 || name[0] != 'E' || std::string("XYZABC").find(name[1]) == std::string::npos ||
        std::string("ABC").find(name[2]) == std::string::npos)
      doc.fail(ce, name, "'" + name + "' is not an ISO 230-7 component error of a rotary axis (EXC ... ECC)");
    if (axis && *axis != name[2]) doc.fail(ce, name, "component errors of two axes in one report");
    axis = name[2];
    const int c = static_cast<int>(std::string("XYZABC").find(name[1]));
    const ParamKind kind = c < 3 ? ParamKind::Length : ParamKind::Angle;
    if (!entry.is_object()) doc.fail(ce, name, "'" + name + "' needs {\"c_deg\": [...], \"values\": [...], \"unit\": ...}");
    const std::string unit = requireString(doc, entry, "unit");
    if (unit != reportUnit(kind)) doc.fail(entry, "unit", fmt::format("unit of '{}' must be {}", name, reportUnit(kind)));
    const double f = kind == ParamKind::Length ? umToMm(1.0) : mdegToRad(1.0);
    const Json& angles = requireArray(doc, entry, "c_deg");
    const Json& values = requireArray(doc, entry, "values");
    if (values.size() != angles.size()) doc.fail(entry, "values", "'values' and 'c_deg' differ in length");
    if (out.angle_deg.empty()) {
      for (const auto& a : angles) {
        if (!a.is_number()) doc.fail(entry, "c_deg", "'c_deg' must hold numbers");
        out.angle_deg.push_back(a.get<double>());
      }
      out.values.assign(angles.size(), ComponentVector::Zero());
      out.u.assign(angles.size(), ComponentVector::Zero());
    } else {
      if (angles.size() != out.angle_deg.size()) doc.fail(entry, "c_deg", "every component error needs the same angles");
      for (size_t i = 0; i < angles.size(); ++i)
        if (!angles[i].is_number() || std::abs(angles[i].get<double>() - out.angle_deg[i]) > 1e-9)
          doc.fail(entry, "c_deg", "every component error needs the same angles");
    }
    const Json* us = entry.contains("u") ? &requireArray(doc, entry, "u") : nullptr;
    if (us && us->size() != angles.size()) doc.fail(entry, "u", "'u' and 'c_deg' differ in length");
    const double limit = kind == ParamKind::Length ? ctl::kMaxLengthCorrectionMm : mdegToRad(ctl::kMaxAngleCorrectionMdeg);
    for (size_t i = 0; i < values.size(); ++i) {
      if (!values[i].is_number()) doc.fail(entry, "values", "'values' must hold numbers");
      const double v = values[i].get<double>() * f;
      if (!(std::abs(v) <= limit) && !force)
        doc.fail(entry, "values", fmt::format("{} at {} deg = {:.1f} {} is beyond the plausibility limit of a correction "
                                              "(--force)",
                                              name, out.angle_deg[i], values[i].get<double>(), unit));
      out.values[i][c] = v;
      if (us) {
        if (!(*us)[i].is_number()) doc.fail(entry, "u", "'u' must hold numbers");
        out.u[i][c] = (*us)[i].get<double>() * f;
      }
    }
    seen[static_cast<size_t>(c)] = true;
  }
  if (!axis) doc.fail(ce, "", "'component_errors' is empty");
  for (int c = 0; c < kNumComponentErrors; ++c)
    if (!seen[static_cast<size_t>(c)])
      doc.fail(ce, "", fmt::format("'component_errors' lacks {}: a missing one is not zero",
                                   componentErrorNames(*axis)[static_cast<size_t>(c)]));
  out.axis = *axis;
  if (std::string why; !out.validate(&why)) doc.fail(ce, "", why);
  return out;
}

bool namesAxisLocation(const Json& errs) {
  for (const auto& [name, entry] : errs.items()) {
    if (!entry.is_object() || !entry.contains("iso") || !entry["iso"].is_string()) return false;
    bool ok = false;
    for (const char* iso : kAxisLocationIso) ok = ok || entry["iso"] == iso;
    if (!ok) return false;
  }
  return !errs.empty();
}

}  // namespace

ReportErrors errorsFromReports(const std::vector<JsonDoc>& reports, Kinematics k, bool force,
                               const std::vector<std::string>& held_by_controller) {
  if (reports.empty()) throw std::invalid_argument("errorsFromReports: no report");
  ReportErrors out;
  std::optional<FullLocation> full;
  std::optional<AxisLocation> axis_location;
  std::string full_file, axis_file, component_file;
  for (const JsonDoc& doc : reports) {
    guardJson(doc, [&] {
      checkFormat(doc);
      const Json& j = doc.value;
      // A report of a compensated program's results holds what that compensation left, not the
      // machine's errors: applied to a program it would cancel the residual and lose the first
      // correction, and a compensated program is not compensated again.
      if (j.contains("compensated_with")) {
        std::string with;
        if (j["compensated_with"].is_array())
          for (const auto& f : j["compensated_with"])
            if (f.is_string()) with += (with.empty() ? "" : ", ") + f.get<std::string>();
        doc.fail(j, "compensated_with",
                 fmt::format("a residual report: its results were measured with a program compensated for {}, so its "
                             "values are what that compensation left, not the machine's errors; compensate the original "
                             "program for {} (this report verifies that compensation)",
                             with.empty() ? "another report" : with, with.empty() ? "that report" : with));
      }
      if (!hasPapersLocationErrors(k))
        doc.fail(j, j.contains("machine_model") ? "machine_model" : "location_errors",
                 fmt::format("a spindle-head machine ({}) has no table location errors to compensate: compensate "
                             "rewrites programs of table machines (table_ac, table_bc, table_ab)",
                             kinematicsName(k)));
      if (!j.contains("location_errors") || !j["location_errors"].is_object())
        doc.fail(j, "location_errors", "the report has no 'location_errors'");
      const Json& errs = j["location_errors"];
      std::vector<std::string> took;
      if (namesAxisLocation(errs)) {
        if (k == Kinematics::TableAB)
          doc.fail(j, "location_errors", "a C axis's location (X0C Y0C A0C B0C) on a table_ab machine, which has no C axis");
        if (axis_location)
          doc.fail(j, "location_errors", fmt::format("the C axis's location is given twice (also by {}): give one report "
                                                     "per kind of error",
                                                     axis_file));
        axis_location = readAxisLocation(doc, force);
        axis_file = doc.file;
        took.push_back("C-axis location X0C Y0C A0C B0C");
      } else {
        for (const auto& p : locationParameters(k))
          if (!errs.contains(std::string(p.name)))
            doc.fail(j, "location_errors",
                     fmt::format("'location_errors' lacks {}: compensate needs all {} location errors of the machine's "
                                 "kinematics (a missing one is not zero)",
                                 p.name, kNumLocationErrors));
        if (full)
          doc.fail(j, "location_errors", fmt::format("the location errors are given twice (also by {}): give one report "
                                                     "per kind of error",
                                                     full_file));
        full = readFullLocation(doc, k, force);
        full_file = doc.file;
        took.push_back(fmt::format("the {} location errors", kNumLocationErrors));
        if (full->covariance) took.back() += " with their covariance";
      }
      if (j.contains("component_errors")) {
        ComponentErrors c = readComponents(doc, force);
        if (out.errors.componentsOf(c.axis))
          doc.fail(j, "component_errors", fmt::format("component errors of {} are given twice (also by {})", c.axis,
                                                      component_file));
        took.push_back(fmt::format("the component errors of {} at {} angles", c.axis, c.angle_deg.size()));
        component_file = doc.file;
        out.errors.components.push_back(std::move(c));
      }
      std::string line;
      for (const auto& t : took) line += (line.empty() ? "" : ", ") + t;
      out.sources.push_back(fmt::format("{}: {}", doc.file, line));
      return 0;
    });
  }
  out.errors.location.kinematics = k;
  const auto targets = axisLocationTargets(k);
  if (full) {
    out.errors.location = full->values;
    out.errors.location_covariance = full->covariance;
    if (axis_location) {
      // The full model's C axis at the tilt axis's zero, to first order (001 Table 1 against 000 Eq. (1), 002 Eq. (2)-(3)).
      const ErrorVector& e = full->values.values;
      const ErrorVector& u = full->u;
      auto at = [&](const char* n) { return parameterIndex(k, n); };
      Eigen::Vector4d predicted, pu;
      if (k == Kinematics::TableAC) {
        predicted << e[at("dx_AY")], e[at("dy_AY")] + e[at("dy_CA")], e[at("a_AY")], e[at("b_AY")] + e[at("b_CA")];
        pu << u[at("dx_AY")], std::hypot(u[at("dy_AY")], u[at("dy_CA")]), u[at("a_AY")],
            std::hypot(u[at("b_AY")], u[at("b_CA")]);
      } else {
        predicted << e[at("dx_BY")] + e[at("dx_CB")], e[at("dy_CB")], e[at("a_BY")] + e[at("a_CB")], e[at("b_BY")];
        pu << std::hypot(u[at("dx_BY")], u[at("dx_CB")]), u[at("dy_CB")], std::hypot(u[at("a_BY")], u[at("a_CB")]),
            u[at("b_BY")];
      }
      std::string diffs;
      for (int i = 0; i < 4; ++i) {
        const ParamKind kind = i < 2 ? ParamKind::Length : ParamKind::Angle;
        const double d = toReport(axis_location->values[i] - predicted[i], kind);
        const double ud = toReport(std::hypot(axis_location->u[i], pu[i]), kind);
        diffs += fmt::format("{}{} {:+.2f} {} (u {:.2f})", diffs.empty() ? "" : ", ", kAxisLocationIso[static_cast<size_t>(i)],
                             d, reportUnit(kind), ud);
      }
      // The component errors are error motions about the axis average line of the report that
      // identified them: its location of that line is the one they belong to. The full report
      // keeps what only it sees (the tilt axis's own terms and the table's height).
      if (!out.errors.components.empty()) {
        LocationErrors& L = out.errors.location;
        if (k == Kinematics::TableAC) {
          L.set("dx_AY", axis_location->values[0]);
          L.set("dy_CA", axis_location->values[1] - L.get("dy_AY"));
          L.set("a_AY", axis_location->values[2]);
          L.set("b_CA", axis_location->values[3] - L.get("b_AY"));
        } else {
          L.set("dx_CB", axis_location->values[0] - L.get("dx_BY"));
          L.set("dy_CB", axis_location->values[1]);
          L.set("a_CB", axis_location->values[2] - L.get("a_BY"));
          L.set("b_BY", axis_location->values[3]);
        }
        out.errors.location_covariance.reset();  // no longer the full report's estimate
      }
      out.notes.push_back(fmt::format("cross-check: the C axis's location of {} minus that of {}'s location errors at "
                                      "the tilt axis's zero: {}; {}",
                                      axis_file, full_file, diffs,
                                      out.errors.components.empty()
                                          ? "the location errors of " + full_file + " are used"
                                          : "the C axis's location at the tilt axis's zero is taken from " + axis_file +
                                                " (its component errors are about that line), the rest from " + full_file));
    }
  } else if (axis_location) {
    for (int i = 0; i < 4; ++i) out.errors.location.set(targets[static_cast<size_t>(i)], axis_location->values[i]);
    std::string zero;
    for (const auto& p : locationParameters(k)) {
      bool set = false;
      for (const char* t : targets) set = set || p.name == t;
      if (!set) zero += (zero.empty() ? "" : " ") + std::string(p.name);
    }
    out.notes.push_back(fmt::format("{} measured the C axis at the tilt axis's zero only: X0C Y0C A0C B0C are taken as "
                                    "{} {} {} {}, and {} as zero; the compensation is exact at the tilt axis's zero and "
                                    "not beyond it (give a report with all {} location errors as well)",
                                    axis_file, targets[0], targets[1], targets[2], targets[3], zero, kNumLocationErrors));
  }
  // What a controller table already holds (`comp-table` loaded on the control) is not compensated
  // again in the program: the two routes split the errors between them.
  for (const std::string& held : held_by_controller) {
    bool taken = false;
    for (auto& comp : out.errors.components) {
      const auto names = componentErrorNames(comp.axis);
      for (size_t c = 0; c < names.size(); ++c)
        if (names[c] == held) {
          for (auto& v : comp.values) v[static_cast<Eigen::Index>(c)] = 0.0;
          for (auto& v : comp.u) v[static_cast<Eigen::Index>(c)] = 0.0;
          taken = true;
        }
    }
    out.notes.push_back(taken ? fmt::format("{} is held by the controller's compensation table: left out of the program's "
                                            "compensation (applied once, by the table)",
                                            held)
                              : fmt::format("{} is held by the controller's table, and no report gives it: nothing to "
                                            "leave out",
                                            held));
  }
  if (std::string why; !out.errors.validate(&why))
    throw InputError(component_file.empty() ? reports.front().file : component_file, 1, why);
  return out;
}

GeometricErrors errorsFromReport(const JsonDoc& report, Kinematics kinematics, bool force) {
  return errorsFromReports({report}, kinematics, force, {}).errors;
}

}  // namespace rotacal
