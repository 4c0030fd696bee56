// Plan -> neutral program: one guarded move per plan point, started from the approach start,
// rotary angles in the controller's sign, indexing only at the index height, lengths in the
// machine's unit.
#include <gtest/gtest.h>

#include "cycles/cycle.hpp"
#include "postproc/probe_program.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

TEST(ProbeProgram, OneGuardedMovePerPointFromItsApproachStart) {
  const ProbePlan plan = test::touch154Plan();
  const nc::Program prog = probeProgram(plan, "fanuc");
  int probes = 0;
  Eigen::Vector3d cur = Eigen::Vector3d::Zero();
  for (const auto& op : prog.ops) {
    if (op.kind == nc::Op::Kind::Probe) {
      const ProbePoint& p = *plan.findPoint(op.point_id);
      EXPECT_EQ(op.point_id, ++probes);
      EXPECT_LT((cur - p.start_m(plan.machine.approach_mm)).norm(), 1e-9);
      EXPECT_LT((op.xyz - p.end_m(plan.machine.overtravel_mm)).norm(), 1e-9);
      EXPECT_DOUBLE_EQ(op.feed, plan.machine.feeds.probing_mm_min);
    }
    if (op.kind == nc::Op::Kind::Index) {
      EXPECT_NEAR(cur.z(), plan.index_z_mm, 1e-9) << "index only when clear";
    }
    if (op.kind != nc::Op::Kind::Comment && op.kind != nc::Op::Kind::Index) cur = op.xyz;
  }
  EXPECT_EQ(probes, 154);
}

TEST(ProbeProgram, RotaryAnglesFollowTheDialectSign) {
  const ProbePlan plan = test::touch154Plan();
  for (const auto& [dialect, sign] : {std::pair<std::string, double>{"fanuc", 1.0}, {"linuxcnc", -1.0}}) {
    const nc::Program prog = probeProgram(plan, dialect);
    std::vector<std::pair<double, double>> ac;
    for (const auto& op : prog.ops)
      if (op.kind == nc::Op::Kind::Index) ac.emplace_back(op.rotary[0].second, op.rotary[1].second);
    ASSERT_EQ(ac.size(), 7u);
    EXPECT_EQ(ac[4].first, sign * -90.0) << dialect << ": pose V is A* = -90 deg";
    EXPECT_EQ(ac[4].second, sign * 90.0) << dialect;
  }
}

TEST(ProbeProgram, InchMachineGetsInchCoordinates) {
  MachineModel m = test::acMachine();
  m.units = LengthUnit::Inch;
  const ProbePlan plan = makePlan("touch154", m, {});
  const nc::Program prog = probeProgram(plan, "fanuc");
  EXPECT_EQ(prog.unit, nc::Unit::Inch);
  for (const auto& op : prog.ops) {
    if (op.kind == nc::Op::Kind::Probe) {
      EXPECT_LT((op.nominal_trigger * kMmPerInch - plan.findPoint(op.point_id)->trigger_m_mm).norm(), 1e-9);
      EXPECT_NEAR(op.feed * kMmPerInch, m.feeds.probing_mm_min, 1e-9);
    }
  }
}

}  // namespace
}  // namespace rotacal
