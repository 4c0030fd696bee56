// The battery every dialect with its own results text passes (dialect_battery.hpp): the round
// trip within the printed digits in mm and in inch, the recovery of injected errors, and the
// checker on the generated programs.
#include <gtest/gtest.h>

#include <string>

#include "dialect_battery.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

struct Printed {
  std::string dialect;
  double inch_unit_mm;  // the unit an inch machine's results are printed in
  int inch_decimals;
  test::Clock clock;
};

class EveryDialect : public ::testing::TestWithParam<Printed> {
 protected:
  const Dialect& d() const { return dialectByName(GetParam().dialect); }
};

TEST_P(EveryDialect, RoundTripWithinThePrintedDigits) {
  const Printed& p = GetParam();
  test::expectRoundTrip(d(), test::acPlan(), 1.0, 4, p.clock);
  test::expectRoundTrip(d(), test::acPlan(LengthUnit::Inch), p.inch_unit_mm, p.inch_decimals, p.clock);
}

TEST_P(EveryDialect, RecoversInjectedErrors) { test::expectRecovery(d(), test::acPlan()); }

TEST_P(EveryDialect, GeneratedProgramsPassTheChecker) { test::expectCleanPrograms(d()); }

INSTANTIATE_TEST_SUITE_P(Dialects, EveryDialect,
                         ::testing::Values(Printed{"haas", 25.4, 5, test::Clock::Milliseconds},
                                           // Klartext programs are written in MM whatever the
                                           // machine, and so are their results.
                                           Printed{"heidenhain", 1.0, 4, test::Clock::Seconds},
                                           Printed{"okuma", 25.4, 5, test::Clock::None},
                                           Printed{"siemens", 25.4, 5, test::Clock::None}),
                         [](const ::testing::TestParamInfo<Printed>& info) { return info.param.dialect; });

}  // namespace
}  // namespace rotacal
