// The neutral csv dialect and the registry: full-precision round trip, strict parsing with the
// line of the fault, no program, the offsets table.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>
#include <random>

#include "controllers/dialect.hpp"
#include "core/errors.hpp"
#include "core/units.hpp"
#include "ctl_test_util.hpp"

namespace rotacal {
namespace {

using test::lines;
using test::messageOf;

TEST(Registry, KnowsTheContractDialectsAndRejectsOthers) {
  EXPECT_EQ(dialectNames(),
            (std::vector<std::string>{"csv", "linuxcnc", "fanuc", "haas", "siemens", "heidenhain", "okuma"}));
  for (const auto& n : dialectNames()) EXPECT_EQ(dialectByName(n).name(), n);
  const std::string msg = messageOf<std::invalid_argument>([] { dialectByName("mazak"); });
  EXPECT_NE(msg.find("mazak"), std::string::npos) << msg;
  EXPECT_NE(msg.find("linuxcnc"), std::string::npos) << msg;
}

TEST(CsvDialect, ResultsRoundTripBitExact) {
  const ProbePlan plan = test::acPlan();
  MeasurementRun run = test::displacedRun(plan);
  run.points[3].t_s = std::numeric_limits<double>::quiet_NaN();
  const Dialect& d = dialectByName("csv");
  const std::string text = d.writeResults(plan, run);
  EXPECT_EQ(lines(text)[0], "point,x_mm,y_mm,z_mm,t_s");
  EXPECT_EQ(lines(text)[4].back(), ',') << "unknown time is an empty field";
  const MeasurementRun back = d.parseResults(text, "r.csv", plan);
  ASSERT_EQ(back.points.size(), run.points.size());
  EXPECT_EQ(back.source, "r.csv");
  for (size_t i = 0; i < run.points.size(); ++i) {
    EXPECT_EQ(back.points[i].point_id, run.points[i].point_id);
    // {:.17g} round-trips a double exactly.
    EXPECT_EQ(back.points[i].position_m_mm, run.points[i].position_m_mm);
    if (i == 3) EXPECT_TRUE(std::isnan(back.points[i].t_s));
    else EXPECT_EQ(back.points[i].t_s, run.points[i].t_s);
  }
}

TEST(CsvDialect, ParserNamesFileAndLineOfEachFault) {
  const ProbePlan plan = test::acPlan();
  const Dialect& d = dialectByName("csv");
  auto ls = lines(d.writeResults(plan, test::displacedRun(plan)));
  auto err = [&](std::vector<std::string> v) {
    return messageOf<InputError>([&] { d.parseResults(test::join(v), "r.csv", plan); });
  };
  {
    auto v = ls;
    v[0] = "point,x,y,z,t";
    EXPECT_NE(err(v).find("r.csv:1: expected the header"), std::string::npos) << err(v);
  }
  {
    auto v = ls;
    v[5] = "5,1,2,3";
    EXPECT_NE(err(v).find("r.csv:6: expected 5 fields"), std::string::npos) << err(v);
  }
  {
    auto v = ls;
    v[7] = "7,1.5,2x,3,";
    EXPECT_NE(err(v).find("r.csv:8: y_mm '2x' of point 7 is not a number"), std::string::npos) << err(v);
  }
  {
    auto v = ls;
    v.erase(v.begin() + 10);  // point 10
    EXPECT_NE(err(v).find(fmt::format("r.csv:{}: point 10 is missing", v.size())), std::string::npos) << err(v);
  }
  {
    auto v = ls;
    v.push_back(ls[20]);  // point 20 again
    EXPECT_NE(err(v).find(fmt::format("r.csv:{}: point 20 appears twice (first at line 21)", v.size())),
              std::string::npos)
        << err(v);
  }
  {
    auto v = ls;
    v.push_back("999,1,2,3,");
    EXPECT_NE(err(v).find(fmt::format("r.csv:{}: point 999 is not in the plan", v.size())), std::string::npos)
        << err(v);
  }
  EXPECT_NE(messageOf<InputError>([&] { d.parseResults("", "r.csv", plan); }).find("r.csv:1:"), std::string::npos);
}

TEST(CsvDialect, HasNoProgram) {
  const ProbePlan plan = test::acPlan();
  const Dialect& d = dialectByName("csv");
  EXPECT_THROW(d.writeProgram(nc::Program{}), std::invalid_argument);
  EXPECT_EQ(d.check("G0 X0", plan, nc::Shape{}), std::vector<std::string>{"csv has no program"});
}

TEST(CsvDialect, OffsetsTableListsAllEightInReportUnits) {
  const ProbePlan plan = test::acPlan();
  OffsetRequest r;
  r.plan = &plan;
  r.identified.kinematics = Kinematics::TableAC;
  r.identified.set("dx_AY", 0.0146);
  r.identified.set("a_AY", mdegToRad(-0.5));
  r.u.fill(umToMm(0.9));
  const auto ls = lines(dialectByName("csv").writeOffsets(r));
  ASSERT_EQ(ls.size(), 9u);
  EXPECT_EQ(ls[0], "parameter,iso,value,unit,u");
  EXPECT_EQ(ls[1], "dx_AY,X0A,14.6000,um,0.9000");
  EXPECT_EQ(ls[5].substr(0, 24), "a_AY,A0A,-0.5000,mdeg,51");  // u 0.9e-3 rad = 51.566 mdeg
  r.identified.set("dz_AY", 0.6);
  EXPECT_THROW(dialectByName("csv").writeOffsets(r), std::invalid_argument);
  r.force = true;
  EXPECT_NO_THROW(dialectByName("csv").writeOffsets(r));
}

TEST(ResultsParsers, CorruptedFilesRaiseOnlyInputErrorOrParse) {
  const ProbePlan plan = test::acPlan();
  const MeasurementRun run = test::displacedRun(plan);
  std::mt19937 rng(11);
  const std::string alphabet = "0123456789 .-+PXYZTEND\r\n\t,=#e";
  for (const auto& name : dialectNames()) {
    const Dialect& d = dialectByName(name);
    const std::string good = d.writeResults(plan, run);
    for (int k = 0; k < 300; ++k) {
      std::string bad = good;
      std::uniform_int_distribution<size_t> pos(0, bad.size() - 1);
      std::uniform_int_distribution<size_t> ch(0, alphabet.size() - 1);
      const int edits = 1 + k % 5;
      for (int e = 0; e < edits; ++e) bad[pos(rng)] = alphabet[ch(rng)];
      try {
        d.parseResults(bad, "bad.txt", plan);
      } catch (const InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("bad.txt:", 0), 0u) << e.what();
      } catch (const std::exception& e) {
        ADD_FAILURE() << name << ": " << e.what();
      }
    }
  }
}

}  // namespace
}  // namespace rotacal
