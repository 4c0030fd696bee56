#include "controllers/tagged_results.hpp"

#include <fmt/format.h>

#include <limits>
#include <stdexcept>

#include "controllers/result_checks.hpp"
#include "controllers/results_lines.hpp"
#include "core/units.hpp"

namespace rotacal::ctl {

double taggedHeaderMmPerUnit(const std::string& s, const std::string& file, int line, const ProbePlan& plan,
                             std::string_view tag, std::string_view cycle_token) {
  const auto t = tokens(s);
  if (t.size() != 9 || t[1] != "DIALECT" || t[3] != "CYCLE" || t[5] != "POINTS" || t[7] != "UNIT")
    fail(file, line,
         fmt::format("expected the header 'ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT MM|INCH', got '{}'", tag,
                     cycle_token, plan.points.size(), s));
  if (t[2] != tag) fail(file, line, fmt::format("results of dialect '{}', expected {}", t[2], tag));
  if (t[4] != cycle_token) fail(file, line, fmt::format("results of cycle '{}', the plan is '{}'", t[4], cycle_token));
  const auto n = parseDigits(t[6]);
  if (!n) fail(file, line, fmt::format("POINTS '{}' is not a number", t[6]));
  if (static_cast<size_t>(*n) != plan.points.size())
    fail(file, line, fmt::format("header says POINTS {} but the plan has {} points", *n, plan.points.size()));
  if (t[8] == "MM") return 1.0;
  if (t[8] == "INCH") return kMmPerInch;
  fail(file, line, fmt::format("UNIT '{}' must be MM or INCH", t[8]));
}

MeasurementRun parseTaggedResults(const std::string& text, const std::string& file, const ProbePlan& plan,
                                  std::string_view tag, std::string_view cycle_token,
                                  std::string_view second_header_why) {
  requireText(text, file);
  ResultLines in(text, file, "ROTACAL-RESULTS",
                 fmt::format("ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT MM|INCH", tag, cycle_token,
                             plan.points.size()),
                 std::string(second_header_why));
  PointCollector points(plan, file);
  double k = 1.0;
  while (in.next()) {
    if (in.isHeader()) {
      k = taggedHeaderMmPerUnit(in.s, file, in.number, plan, tag, cycle_token);
      continue;
    }
    if (in.isEnd()) continue;
    in.refuseNotTriggered();
    const auto f = letteredFields(in.s, "XYZ", file, in.number);
    Eigen::Vector3d x;
    for (int i = 0; i < 3; ++i) {
      const auto v = parseNumber(f.fields[static_cast<size_t>(i)]);
      if (!v)
        fail(file, in.number,
             fmt::format("{} '{}' of point {} is not a number", "XYZ"[i], f.fields[static_cast<size_t>(i)], f.id));
      x[i] = *v * k;
    }
    points.add(in.number, static_cast<int>(f.id), x, std::numeric_limits<double>::quiet_NaN());
  }
  in.finish(points);
  return points.finish(in.last());
}

std::string TaggedResultsDialect::writeResults(const ProbePlan& plan, const MeasurementRun& run) const {
  const bool inch = plan.machine.units == LengthUnit::Inch;
  const double k = inch ? 1.0 / kMmPerInch : 1.0;
  const std::string eol(form_.eol);
  std::string out = fmt::format("ROTACAL-RESULTS DIALECT {} CYCLE {} POINTS {} UNIT {}{}", form_.tag,
                                form_.cycle_token(plan.cycle), plan.points.size(), inch ? "INCH" : "MM", eol);
  auto field = [&](double v) {
    std::string s = fixed(v, resultDecimals(inch));
    if (s.size() < static_cast<size_t>(form_.width)) s.insert(0, form_.width - s.size(), ' ');
    return s;
  };
  for (const auto& t : run.points) {
    if (!plan.findPoint(t.point_id)) throw std::invalid_argument(fmt::format("run point {} is not in the plan", t.point_id));
    const Eigen::Vector3d x = t.position_m_mm * k;
    out += fmt::format("P{} X{} Y{} Z{}{}", t.point_id, field(x.x()), field(x.y()), field(x.z()), eol);
  }
  return out + "END" + eol;
}

MeasurementRun TaggedResultsDialect::parseResults(const std::string& text, const std::string& file,
                                                  const ProbePlan& plan) const {
  return parseTaggedResults(text, file, plan, form_.tag, form_.cycle_token(plan.cycle), form_.second_header_why);
}

}  // namespace rotacal::ctl
