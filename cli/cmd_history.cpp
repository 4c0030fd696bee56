// rotacal history add | show: every calibration of a machine kept in one SQLite file, and its
// trend with drift and step changes flagged (history/trend.hpp, docs/reports.md).
#include <ctime>
#include <memory>
#include <string>

#include <fmt/format.h>

#include "cli/command.hpp"
#include "cli/output.hpp"
#include "core/json_io.hpp"
#include "history/store.hpp"
#include "history/trend_report.hpp"

namespace rotacal {

std::vector<Command> historyCommands(CLI::App& app, const Common& common) {
  struct Args {
    std::string report, machine_id, db, time, plan, html_out, json_out;
    double alpha = 1e-3;
  };
  auto a = std::make_shared<Args>();
  auto* hist = app.add_subcommand("history", "keep every calibration of a machine and show its trend");
  hist->require_subcommand(1);
  auto* add = hist->add_subcommand("add", "store the calibration of a REPORT.json");
  add->add_option("report", a->report, "REPORT.json (rotacal analyze --json)")->required();
  add->add_option("--machine-id", a->machine_id, "the machine's name in the history")->required();
  add->add_option("--db", a->db, "history file (default $XDG_DATA_HOME/rotacal/history.sqlite)");
  add->add_option("--time", a->time, "when the calibration was made, YYYY-MM-DD[Thh:mm:ssZ] UTC (default: now)");
  add->add_option("--plan", a->plan, "PLAN.json to keep with it (default: the report's cycle and machine)");
  auto* show = hist->add_subcommand("show", "the trend of each parameter, drift and steps flagged");
  show->add_option("--machine-id", a->machine_id, "the machine's name in the history")->required();
  show->add_option("--db", a->db, "history file (default $XDG_DATA_HOME/rotacal/history.sqlite)");
  show->add_option("--html", a->html_out, "TREND.html");
  show->add_option("--json", a->json_out, "TREND.json (- for stdout)");
  show->add_option("--alpha", a->alpha, "false-alarm rate of each test (default 0.001)");

  auto dbPath = [a] {
    try {
      return a->db.empty() ? history::defaultDatabasePath() : a->db;
    } catch (const std::runtime_error& e) {
      throw CLI::ValidationError("--db", e.what());
    }
  };
  return {{add, [a, &common, dbPath] {
             const JsonDoc doc = readJsonFile(a->report);
             // The calibration's time: given, or when its report was analyzed, or now.
             double t = nowUnixS();
             if (a->time.empty() && doc.value.is_object() && doc.value.contains("analyzed_utc") &&
                 doc.value["analyzed_utc"].is_string()) {
               try {
                 t = history::parseIsoTime(doc.value["analyzed_utc"].get<std::string>());
               } catch (const std::invalid_argument& e) {
                 failFile(a->report, std::string("analyzed_utc: ") + e.what());
               }
             }
             if (!a->time.empty()) {
               try {
                 t = history::parseIsoTime(a->time);
               } catch (const std::invalid_argument& e) {
                 throw CLI::ValidationError("--time", e.what());
               }
             }
             history::Calibration c = history::calibrationFromReport(doc, a->machine_id, t);
             if (!a->plan.empty()) c.plan_json = readJsonFile(a->plan).value.dump();
             const std::string path = dbPath();
             history::Database db(path);
             // What is there already is read back first: a damaged history is refused, not added to.
             (void)db.list(a->machine_id);
             const long long id = db.add(c);
             say(common, fmt::format("history: calibration {} of machine {} ({}) -> {}\n", id, a->machine_id, c.time_utc, path));
             return 0;
           }},
          {show, [a, &common, dbPath] {
             history::TrendOptions o;
             o.alpha = a->alpha;
             std::string why;
             if (!o.validate(&why)) throw CLI::ValidationError("--alpha", why);
             const std::string path = dbPath();
             checkOutputs({{"--json", a->json_out}, {"--html", a->html_out}}, {path});
             const history::Database db(path, false);
             const auto cals = db.list(a->machine_id);
             if (cals.empty()) failFile(path, "no calibration of machine '" + a->machine_id + "'");
             const Json h = history::historyJson(a->machine_id, cals, o);
             OutputSet outputs({path});
             outputs.add("--json", a->json_out, h.dump(1) + "\n");
             addHtml(outputs, a->html_out, h);
             outputs.commit();
             sayUnlessPiped(common, history::historyText(h), a->json_out, a->html_out);
             return 0;
           }}};
}

}  // namespace rotacal
