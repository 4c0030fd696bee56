#pragma once
// The results of the dialects whose programs print tagged lines with their own output statements
// (Siemens WRITE, Okuma PUT): the header "ROTACAL-RESULTS DIALECT <tag> CYCLE <cycle_token>
// POINTS <n> UNIT MM|INCH", one "P<id> X<x> Y<y> Z<z>" line per point (any spacing),
// "NOT-TRIGGERED P<id>" where the program stopped, and "END".
#include <string>
#include <string_view>

#include "controllers/dialect.hpp"
#include "core/measurement.hpp"
#include "core/probe_plan.hpp"

namespace rotacal::ctl {

/// The header line of a tagged results file, "ROTACAL-RESULTS DIALECT <tag> CYCLE <cycle_token>
/// POINTS <n> UNIT MM|INCH" (the trimmed text `s` of line `line` of `file`): throws InputError
/// naming what differs from the plan; returns the file's mm per unit (1 or 25.4).
double taggedHeaderMmPerUnit(const std::string& s, const std::string& file, int line, const ProbePlan& plan,
                             std::string_view tag, std::string_view cycle_token);

/// The whole tagged results file; `second_header_why` is added to the message when a second
/// header shows an appended old run.
MeasurementRun parseTaggedResults(const std::string& text, const std::string& file, const ProbePlan& plan,
                                  std::string_view tag, std::string_view cycle_token, std::string_view second_header_why);

/// The results side of the dialects whose programs print tagged lines with their own output
/// statements (okuma PUT, siemens WRITE): parseTaggedResults reads what writeResults writes, the
/// header, "P<id> X<x> Y<y> Z<z>" per point with the coordinates in 5 decimals in inch and 4 in
/// mm, right-aligned in `width` characters (0: unpadded), and "END", every line ended by `eol`,
/// in a .txt file.
class TaggedResultsDialect : public Dialect {
 public:
  struct Form {
    std::string_view name;               // the dialect's
    std::string_view program_extension;  // ".min"
    std::string_view tag;                // "OKUMA"
    std::string (*cycle_token)(std::string_view);  // the cycle's name as the programs print it
    int width = 0;
    std::string_view eol;
    std::string_view second_header_why;  // parseTaggedResults'
  };
  TaggedResultsDialect(const Form& form, DialectIdentity identity) : Dialect(std::move(identity)), form_(form) {}
  std::string_view name() const override { return form_.name; }
  std::string_view programExtension() const override { return form_.program_extension; }
  std::string_view resultsExtension() const override { return ".txt"; }
  /// Decimals of the printed coordinates, the programs' and writeResults': 4 in mm, 5 in inch (4
  /// inch decimals would round by up to 1.27 um and move the identified errors by up to 3.1 um,
  /// docs/dialects.md).
  static int resultDecimals(bool inch) { return inch ? 5 : 4; }
  std::string writeResults(const ProbePlan& plan, const MeasurementRun& run) const override;
  MeasurementRun parseResults(const std::string& text, const std::string& file, const ProbePlan& plan) const override;

 private:
  Form form_;
};

}  // namespace rotacal::ctl
