// probe_qual: the probe's repeatability, effective radius and pretravel by
// direction on the one_sphere cycle's calibration sphere, for MACHINE.json's probe section and
// the contributors' probe entries.
#include "core/declared_noise.hpp"
#include "core/errors.hpp"
#include "core/verdict.hpp"
#include "core/singleton.hpp"
#include "cycles/cycle.hpp"
#include "cycles/probing.hpp"
#include "cycles/probe_qual/analyze.hpp"
#include "cycles/probe_qual/diagnose.hpp"
#include "cycles/probe_qual/plan.hpp"
#include "postproc/probe_program.hpp"

namespace rotacal {
namespace {

class ProbeQual final : public Cycle {
 public:
  ProbeQual() : Cycle({"probe_qual",
                       "ISO 230-10: the probe's repeatability, effective radius and pretravel by direction on one sphere",
                       {"examples/machines/ac_trunnion.json", {}, "examples/truth/probe_pretravel.json"},
                       7230,  // 7000 + 230 (ISO 230-10, the probing system's test)
                       makeProbeQualPlan, probeProgram, probeQualPlanRules(),
                       "probe_qual qualifies the probe: its figures go to MACHINE.json's probe section and the "
                       "contributors (REPORT.json machine_probe, contributors), not to the machine's offsets"}) {}

  CycleDocuments analyze(const AnalyzeRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    ProbeQualOptions o;
    o.declared = r.contributors;  // the machine's linear axes: Type B of the pretravels
    const ProbeQualification q = qualifyProbe(plan, readProbeRuns(plan, r.results, *r.dialect), o);
    const std::vector<std::string> files = pathsOf(r.results);
    const Json verdict = probeQualVerdictJson(q, plan.machine.probe.repeatability_um);
    CycleDocuments out = documents(probeQualReportJson(plan, q, files), verdictText(verdict) + "\n" + probeQualText(q));
    out.doc["verdict"] = verdict;
    out.doc["figures"] = probeQualFiguresJson(plan, q);
    // A chip left out is named on stderr: the repeatability copied into MACHINE.json is the rest's.
    if (!q.screen.excluded.empty() || q.screen.too_many) out.warnings.push_back(q.screen.text());
    return out;
  }

  CycleDocuments diagnose(const DiagnoseRequest& r) const override {
    const ProbePlan& plan = *r.plan;
    JudgeOptions o;
    o.alpha = r.alpha;
    const std::vector<MeasurementRun> runs = readProbeRuns(plan, r.results, *r.dialect);
    try {
      perTouchDeclaration(r.contributors, plan.machine.probe.repeatability_um);
    } catch (const std::invalid_argument& e) {
      // Two declarations of the repeatability that disagree: the contributors file's error.
      throw InputError(r.contributors && !r.contributors->file.empty() ? r.contributors->file : "MACHINE.json contributors",
                       0, e.what());
    }
    const JudgedFit d = diagnoseProbeQual(plan, runs, o, r.contributors);
    return documents(judgedDiagnosisJson(std::string(name()), plan, d), judgeText(d.summary, d.separate_with));
  }
};

}  // namespace

const Cycle& probe_qualCycle() { return singleton<ProbeQual>(); }

}  // namespace rotacal
