// rotacal diagnose: where the model disagrees with the data, the physical cause, the gain.
#include <memory>
#include <string>
#include <vector>

#include "cli/cmd_tooltip.hpp"
#include "cli/cmd_rtest.hpp"
#include "cli/command.hpp"
#include "cli/output.hpp"
#include "cli/progress.hpp"
#include "cli/spaceframe_diagnose_cli.hpp"
#include "cli/spheres3_cli.hpp"
#include "core/diagnosis.hpp"
#include "core/diagnosis_figures.hpp"
#include "core/json_io.hpp"
#include "core/probe_plan.hpp"

namespace rotacal {

std::vector<Command> diagnoseCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string plan_file, dialect, json_out, text_out, html_out;
    std::vector<std::string> results;
    double alpha = 1e-3;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("diagnose", "find what the model misses, name the cause, extend the model, measure the gain");
  cmd->add_option("--plan", a->plan_file, "PLAN.json")->required();
  cmd->add_option("--results", a->results, "RESULTS... (repeats of the plan, in time order)")->required();
  cmd->add_option("--dialect", a->dialect, "csv | linuxcnc | fanuc | haas | siemens | heidenhain | okuma")->required();
  cmd->add_option("--json", a->json_out, "DIAGNOSIS.json (- for stdout)")->required();
  cmd->add_option("--html", a->html_out, "DIAGNOSIS.html: the report to look at, self-contained");
  cmd->add_option("--text", a->text_out, "the readable summary, also printed on stdout");
  cmd->add_option("--alpha", a->alpha, "false-alarm rate of the tests (default 0.001)");
  return {{cmd, [a, &common] {
             std::vector<std::string> inputs = a->results;
             inputs.push_back(a->plan_file);
             checkOutputs({{"--json", a->json_out}, {"--text", a->text_out}, {"--html", a->html_out}}, inputs);
             const ProbePlan plan = loadPlan(a->plan_file);
             const Dialect& d = dialectOrFail(a->dialect);
             if (plan.cycle == "tooltip")
               return diagnoseTooltipCmd(common, plan, a->results, a->alpha, a->json_out, a->text_out, a->html_out);
             if (plan.cycle == "rtest") return rtestDiagnose(common, plan, a->results, a->json_out, a->text_out, a->alpha, a->html_out);
             std::vector<MeasurementRun> runs;
             const std::vector<std::string> texts = readResultsFiles(a->results);
             for (size_t i = 0; i < texts.size(); ++i) runs.push_back(d.parseResults(texts[i], a->results[i], plan));
             if (plan.cycle == "spheres3")
               return diagnoseSpheres3Cli(common, plan, runs, a->results, a->alpha, a->json_out, a->text_out, a->html_out);
             if (plan.cycle == "spaceframe")
               return diagnoseSpaceframeCli(common, plan, runs, a->results, a->alpha, a->json_out, a->text_out, a->html_out);
             DiagnosisOptions o;
             o.alpha = a->alpha;
             o.prior_sigma_um = plan.machine.probe.repeatability_um;
             std::string why;
             if (!o.validate(&why)) throw CLI::ValidationError("--alpha", why);
             const auto progress = progressIndicator(common, "rotacal diagnose", "candidate fits");
             auto total = std::make_shared<int>(0);
             if (progress)
               o.progress = [progress, total](int done, int all) {
                 *total = all;
                 progress(done, all);
               };
             const Diagnosis dg = diagnose(plan, runs, o);
             if (progress && *total > 0) progress(*total, *total);  // ends the line
             if (dg.baseline.summary.termination != Termination::Converged)
               failFile(a->results.front(), "baseline fit failed: " + dg.baseline.summary.message);
             const std::string text = diagnosisText(dg);
             Json dj = diagnosisToJson(dg);
             dj["figures"] = diagnosisFigures(dg, plan);  // drawn by the HTML report
             writeDocuments(common, dj, text, a->json_out, a->text_out, a->html_out);
             return 0;
           }}};
}

}  // namespace rotacal
