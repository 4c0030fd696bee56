// rotacal report: the HTML page of any rotacal JSON document (REPORT.json, DIAGNOSIS.json, a
// history trend, or a document holding only `figures`), e.g. to redraw an old report.
#include <memory>
#include <string>

#include "cli/command.hpp"
#include "cli/output.hpp"
#include "core/json_io.hpp"

namespace rotacal {

std::vector<Command> reportCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string in, html_out;
  };
  auto a = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("report", "draw the HTML report of a REPORT.json, DIAGNOSIS.json or history trend");
  cmd->add_option("document", a->in, "the JSON document")->required();
  cmd->add_option("--html", a->html_out, "REPORT.html (- for stdout)")->required();
  return {{cmd, [a, &common] {
             const JsonDoc doc = readJsonFile(a->in);
             std::string html;
             try {
               html = report::reportHtml(doc.value);
             } catch (const std::invalid_argument& e) {
               doc.fail("figures", e.what());
             }
             writeOutput(a->html_out, html);
             if (a->html_out != "-") say(common, "report -> " + a->html_out + "\n");
             return 0;
           }}};
}

}  // namespace rotacal
