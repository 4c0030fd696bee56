// The neutral dialect (contract.md "Neutral results"): no NC program; results as
// `point,x_mm,y_mm,z_mm,t_s`, full precision, t_s empty when unknown; offsets as a plain table.
#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "controllers/comp_table.hpp"
#include "controllers/dialect.hpp"
#include "controllers/offsets.hpp"
#include "controllers/result_checks.hpp"
#include "controllers/results_lines.hpp"
#include "controllers/text.hpp"
#include "core/singleton.hpp"
#include "core/units.hpp"

namespace rotacal {
namespace ctl {
namespace {

// The rotary compensation table in this control's form (controllers/comp_table.hpp).
CompTable compTable(const CompTableRequest& r, const PeriodicInterpolant& E, double step) {
  const int n = compTableStepsPerTurn(step);
  const CompTableGrid g = compTableGrid(E, r.controller_sign, 0.0, step, n);
  CompTable t;
  t.rows = g.rows;
  t.max_error_mdeg = g.max_abs_mdeg;
  t.text = "controller_angle_deg,error_mdeg\n";
  for (const auto& row : g.rows) t.text += fmt::format("{},{}\n", fixed(row.controller_deg, 6), fixed(row.error_deg * 1e3, 6));
  t.setup = {"error_mdeg = actual - commanded angle in the control's counting; a control cancels it by commanding "
             "-error_mdeg more"};
  return t;
}

}  // namespace
}  // namespace ctl

namespace {

constexpr const char* kHeader = "point,x_mm,y_mm,z_mm,t_s";

std::vector<std::string> splitCommas(const std::string& line) {
  std::vector<std::string> f;
  size_t start = 0;
  for (;;) {
    const size_t c = line.find(',', start);
    f.push_back(line.substr(start, c == std::string::npos ? std::string::npos : c - start));
    if (c == std::string::npos) break;
    start = c + 1;
  }
  return f;
}

DialectIdentity csvIdentity() {
  DialectIdentity d;
  d.language = ProgramLanguage::None;
  d.comp_table = ctl::compTable;
  return d;
}

class CsvDialect final : public Dialect {
 public:
  CsvDialect() : Dialect(csvIdentity()) {}
  std::string_view name() const override { return "csv"; }
  std::string_view programExtension() const override { return ".csv"; }
  std::string_view resultsExtension() const override { return ".csv"; }

  std::vector<std::string> commentLines(std::string_view) const override {
    throw std::invalid_argument("csv: no NC program, so no comments");
  }

  std::string writeProgram(const nc::Program&) const override {
    throw std::invalid_argument("the csv dialect has no NC program; choose linuxcnc or fanuc");
  }

  std::string writeResults(const ProbePlan&, const MeasurementRun& run) const override {
    std::string out = std::string(kHeader) + "\n";
    for (const auto& p : run.points) {
      const Eigen::Vector3d& x = p.position_m_mm;
      out += fmt::format("{},{:.17g},{:.17g},{:.17g},{}\n", p.point_id, x.x(), x.y(), x.z(),
                         std::isnan(p.t_s) ? std::string() : fmt::format("{:.17g}", p.t_s));
    }
    return out;
  }

  MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const override {
    ctl::requireText(text, file);
    const auto lines = ctl::splitLines(text);
    ctl::PointCollector points(plan, file);
    bool header = false;
    int last = 1;
    for (const auto& l : lines) {
      const std::string s = ctl::trim(l.text);
      if (s.empty()) continue;
      last = l.number;
      if (!header) {
        if (s != kHeader)
          ctl::fail(file, l.number, fmt::format("expected the header '{}', got '{}'", kHeader, s));
        header = true;
        continue;
      }
      const auto f = splitCommas(s);
      if (f.size() != 5)
        ctl::fail(file, l.number, fmt::format("expected 5 fields (point,x_mm,y_mm,z_mm,t_s), got {}", f.size()));
      const auto id = ctl::parseDigits(ctl::trim(f[0]));
      if (!id || *id == 0) ctl::fail(file, l.number, fmt::format("point id '{}' is not a positive integer", f[0]));
      Eigen::Vector3d x;
      const char* names[3] = {"x_mm", "y_mm", "z_mm"};
      for (int i = 0; i < 3; ++i) {
        const auto v = ctl::parseNumber(ctl::trim(f[1 + i]));
        if (!v) ctl::fail(file, l.number, fmt::format("{} '{}' of point {} is not a number", names[i], f[1 + i], *id));
        x[i] = *v;
      }
      double t = std::numeric_limits<double>::quiet_NaN();
      const std::string ts = ctl::trim(f[4]);
      if (!ts.empty()) {
        const auto v = ctl::parseNumber(ts);
        if (!v) ctl::fail(file, l.number, fmt::format("t_s '{}' of point {} is not a number", ts, *id));
        t = *v;
      }
      points.add(l.number, static_cast<int>(*id), x, t);
    }
    if (!header) ctl::fail(file, 1, fmt::format("empty results file: expected the header '{}'", kHeader));
    return points.finish(last);
  }

  std::string writeOffsets(const OffsetRequest& r) const override {
    if (r.identified.kinematics == Kinematics::HeadTable)
      throw std::invalid_argument(ctl::headTableOffsetsRefusal("csv"));
    ctl::requirePlausible(r);
    const auto& params = locationParameters(r.identified.kinematics);
    std::string out = "parameter,iso,value,unit,u\n";
    for (int i = 0; i < kNumLocationErrors; ++i) {
      const ParamKind k = params[i].kind;
      const double u = k == ParamKind::Length ? mmToUm(r.u[i]) : radToMdeg(r.u[i]);
      out += fmt::format("{},{},{},{},{}\n", params[i].name, params[i].iso, ctl::fixed(r.identified.reportValue(i), 4),
                         reportUnit(k), std::isfinite(u) ? ctl::fixed(u, 4) : std::string());
    }
    return out;
  }

  std::vector<std::string> check(const std::string&, const ProbePlan&, const nc::Shape&) const override {
    return {"csv has no program"};
  }
};

}  // namespace

const Dialect& csvDialect() { return singleton<CsvDialect>(); }

}  // namespace rotacal
