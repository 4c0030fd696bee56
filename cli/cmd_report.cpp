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
             checkOutputs({{"--html", a->html_out}}, {a->in});
             const JsonDoc doc = readJsonFile(a->in);
             std::string html;
             try {
               html = report::reportHtml(doc.value);
             } catch (const std::invalid_argument& e) {
               doc.fail(doc.value, "figures", e.what());
             } catch (const Json::exception& e) {  // a field of the wrong type somewhere in the document
               doc.fail(doc.value, "", std::string("cannot draw the report: ") + e.what());
             }
             OutputSet outputs({a->in});
             outputs.add("--html", a->html_out, std::move(html));
             outputs.commit();
             if (a->html_out != "-") say(common, "report -> " + a->html_out + "\n");
             return 0;
           }}};
}

}  // namespace rotacal
