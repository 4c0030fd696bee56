// probe_qual (issue 19 item 5): the probe's repeatability, effective radius and pretravel by
// direction on the one_sphere cycle's calibration sphere, for MACHINE.json's probe section and
// the contributors' probe entries.
#include "core/singleton.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "cycles/probe_qual/analyze.hpp"
#include "cycles/probe_qual/diagnose.hpp"
#include "cycles/probe_qual/plan.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {
namespace {

PlanRules probeQualPlanRules() {
  PlanRules r;
  r.spheres = 1;  // one sphere, every touch on it
  r.safe_height_over_artefact = false;  // the plan keeps the test piece out of reach sideways (plan.cpp)
  r.check_options = [](const ProbePlan& p) { (void)probeQualLayoutOf(p); };
  return r;
}

class ProbeQual final : public Cycle {
 public:
  ProbeQual() : Cycle({"probe_qual",
                       "issue 19: the probe's repeatability, effective radius and pretravel by direction on one sphere",
                       {"examples/machines/ac_trunnion.json", {}},
                       7230,  // 7000 + 230 (ISO 230-10, the probing system's test)
                       makeProbeQualPlan, probeProgram, probeQualPlanRules()}) {}
  Simulated simulate(const SimulateRequest& request) const override { return simulateProbing(request); }

  std::string_view noOffsetsReason() const override {
    return "probe_qual qualifies the probe: its figures go to MACHINE.json's probe section and the contributors "
           "(REPORT.json machine_probe, contributors), not to the machine's offsets";
  }

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    const ProbeQualification q = qualifyProbe(plan, readProbeRuns(plan, r.results, *r.dialect));
    std::vector<std::string> files;
    for (const auto& f : r.results) files.push_back(f.path);
    return documents(probeQualReportJson(plan, q, files), probeQualText(q));
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    JudgeOptions o;
    o.alpha = r.alpha;
    const ProbeQualDiagnosis d = diagnoseProbeQual(plan, readProbeRuns(plan, r.results, *r.dialect), o);
    return documents(probeQualDiagnosisJson(d, plan), judgeText(d.summary));
  }
};

}  // namespace

const Cycle& probe_qualCycle() { return singleton<ProbeQual>(); }

}  // namespace rotacal
