#pragma once
// Shared fixtures of the dialect tests: the A/C machine of the brief (built here from JSON, so
// the tests do not depend on the bundled example), its touch154 plan, a run whose triggers are
// displaced by known amounts along the approach, and small text helpers.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cycles/cycle.hpp"
#include "test_util.hpp"
#include "controllers/dialect.hpp"
#include "core/json_io.hpp"
#include "core/machine.hpp"
#include "core/probe_plan.hpp"

namespace rotacal::test {

inline const char* kAcMachineJson = R"({
  "format": "rotacal-machine/1",
  "name": "ac_test",
  "kinematics": "table_ac",
  "units": "mm",
  "strokes": {"X": [-625.0, 625.0], "Y": [-330.0, 330.0], "Z": [-140.0, 400.0]},
  "rotary_axes": {
    "A": {"stroke_deg": [-110.0, 20.0], "controller_sign": 1, "dialect_sign": {"linuxcnc": -1}},
    "C": {"continuous": true, "controller_sign": 1, "dialect_sign": {"linuxcnc": -1}}
  },
  "probe": {"ball_diameter_mm": 6.0, "stylus_length_mm": 50.0},
  "artefact": {"type": "square_column", "top_centre_w_mm": [0.0, -200.0, 170.0], "size_mm": [100.0, 100.0, 150.0]}
})";

inline const char* kBcMachineJson = R"({
  "format": "rotacal-machine/1",
  "name": "bc_test",
  "kinematics": "table_bc",
  "units": "mm",
  "strokes": {"X": [-400.0, 400.0], "Y": [-300.0, 300.0], "Z": [-200.0, 400.0]},
  "rotary_axes": {
    "B": {"stroke_deg": [-120.0, 120.0], "controller_sign": 1, "dialect_sign": {"linuxcnc": -1}},
    "C": {"continuous": true, "controller_sign": 1, "dialect_sign": {"linuxcnc": -1}}
  },
  "probe": {"ball_diameter_mm": 25.4, "stylus_length_mm": 60.0}
})";

inline MachineModel machineFrom(const char* json) {
  const JsonDoc doc = parseJsonText(json, "test_machine.json");
  return machineFromJson(doc, doc.value);
}

inline MachineModel acTestMachine() { return machineFrom(kAcMachineJson); }

inline ProbePlan acPlan(LengthUnit units = LengthUnit::Millimetre) {
  MachineModel m = acTestMachine();
  m.units = units;
  return makePlan("touch154", m, {});
}

/// Known displacement (mm) of point `id` along its approach: -18 um .. +18 um, both signs.
inline double knownDisplacementMm(int id) { return 0.001 * (id % 37) - 0.018; }

/// Triggers at the nominal positions displaced along the approach, times = plan time + 0.25 s.
inline MeasurementRun displacedRun(const ProbePlan& plan) {
  MeasurementRun run;
  run.source = "displaced";
  for (const auto& p : plan.points)
    run.points.push_back({p.id, p.trigger_m_mm + knownDisplacementMm(p.id) * p.approach_m, p.t_s + 0.25});
  return run;
}

inline std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : text) {
    if (c == '\n') {
      if (!cur.empty() && cur.back() == '\r') cur.pop_back();
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

inline std::string join(const std::vector<std::string>& ls, const std::string& eol = "\n") {
  std::string s;
  for (const auto& l : ls) s += l + eol;
  return s;
}

/// Index of the first line starting with `prefix` (throws when none).
inline size_t lineStarting(const std::vector<std::string>& ls, const std::string& prefix) {
  for (size_t i = 0; i < ls.size(); ++i)
    if (ls[i].rfind(prefix, 0) == 0) return i;
  throw std::runtime_error("no line starts with " + prefix);
}

/// The message of the exception `f` throws, or "" when it throws nothing.
template <class E, class F>
std::string messageOf(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

}  // namespace rotacal::test
