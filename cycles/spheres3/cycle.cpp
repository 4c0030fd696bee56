// spheres3 (001): the 4 location and 6 component errors of the C axis from three spheres.
#include "cycles/spheres3/plan.hpp"
#include "cycles/spheres3/diagnose.hpp"
#include "cycles/spheres3/analyze.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {
namespace {

std::vector<std::string> paths(const std::vector<InputFile>& files) {
  std::vector<std::string> p;
  for (const auto& f : files) p.push_back(f.path);
  return p;
}

class Spheres3 final : public Cycle {
 public:
  std::string_view name() const override { return "spheres3"; }
  std::string_view summary() const override {
    return "001: the 4 location and 6 component errors of the C axis from three spheres";
  }
  CycleExample example() const override { return {"examples/machines/ac_trunnion.json", {}}; }
  ProbePlan plan(const MachineModel& machine, const CycleOptions& options) const override {
    return makeSpheres3Plan(machine, options);
  }
  PlanRules planRules() const override {
    PlanRules r;
    r.spheres = 3;  // 001 Fig. 2: three spheres, each fitted at every pose
    return r;
  }
  int programNumber() const override { return 7001; }  // 7000 + its source document (001).
  nc::Program buildProgram(const ProbePlan& plan, const std::string& dialect) const override {
    return probeProgram(plan, dialect);
  }
  Simulated simulate(const SimulateRequest& request) const override { return simulateProbing(request); }

  std::string_view noOffsetsReason() const override {
    return "spheres3 identifies component errors as functions of C: they need the controller's rotary compensation "
        "table, which no dialect writes yet";
  }

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    Spheres3Options opt;
    opt.prior_sigma_um = plan.machine.probe.repeatability_um;
    const Spheres3Result res = identifySpheres3(plan, readProbeRuns(plan, r.results, *r.dialect), opt);
    CycleDocuments out;
    out.text = spheres3Text(res);
    out.doc = spheres3ReportJson(plan, res, paths(r.results));
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    Spheres3DiagnosisOptions o;
    o.judge.alpha = r.alpha;
    o.sigma_um = plan.machine.probe.repeatability_um;  // the declared noise, never the fit's own
    const Spheres3Diagnosis d = diagnoseSpheres3(plan, readProbeRuns(plan, r.results, *r.dialect), o);
    CycleDocuments out;
    out.text = spheres3DiagnosisText(d);
    out.doc = spheres3DiagnosisJson(d);
    return out;
  }
};

}  // namespace

const Cycle& spheres3Cycle() {
  static const Spheres3 cycle;
  return cycle;
}

}  // namespace rotacal
