// The per-touch deviations behind the report's views of 000 Figs. 7-9, checked against what the
// exact simulator was told: a test piece set up 0.5 mm off in X on a perfect machine shifts
// every +X touch by +500 um and every -X touch by -500 um at pose I (raw deviation, Fig. 7), and
// cancels exactly in the relative displacement of Eq. (21) at every pose (Figs. 8-9), since a
// rigid shift of the piece moves each face along its own normal by the same amount whatever
// the table's angle.
#include <gtest/gtest.h>

#include "cycles/touch154/point_deviations.hpp"
#include "test_util.hpp"

namespace rotacal {
namespace {

TEST(PointDeviations, SetupShiftIsRawButCancelsInEq21) {
  const ProbePlan plan = test::touch154Plan();
  Truth truth;  // perfect machine
  truth.artefact.setup.translation_mm = {0.5, 0.0, 0.0};
  const MeasurementRun run = simulate(plan, truth, {1});
  IdentificationResult none;  // no fit: residuals null
  const Json pts = pointDeviationsJson(plan, {run}, none);
  ASSERT_EQ(pts.size(), plan.points.size());
  int checked_x = 0;
  for (const auto& p : pts) {
    // Exact geometry, no noise: only the rounding of the file (1e-4 um) remains.
    ASSERT_TRUE(p["rel_dev_um"].is_number()) << p.dump();
    EXPECT_NEAR(p["rel_dev_um"].get<double>(), 0.0, 2e-4) << p.dump();
    EXPECT_TRUE(p["residual_um"].is_null());
    if (p["pose_name"] == "I" && (p["face"] == "+X" || p["face"] == "-X")) {
      EXPECT_NEAR(p["dev_um"].get<double>(), p["face"] == "+X" ? 500.0 : -500.0, 2e-4) << p.dump();
      ++checked_x;
    }
  }
  EXPECT_EQ(checked_x, 8);
}

TEST(PointDeviations, LocationErrorShowsOnlyAwayFromPoseI) {
  // dx_AY = 14.6 um shifts the C axis: at pose III (C = 180) the +X face of the piece faces -X
  // in the machine, and the table turning about an axis 14.6 um off moves the piece by
  // 2 x 14.6 um in X (000 Fig. 8(a): "the shift in X ... observed in (II), (III), (IV)").
  const ProbePlan plan = test::touch154Plan();
  LocationErrors e;
  e.kinematics = Kinematics::TableAC;
  e.setReportValue(0, 14.6);  // dx_AY, um
  const MeasurementRun run = simulate(plan, test::truthWith(e), {1});
  const Json pts = pointDeviationsJson(plan, {run}, IdentificationResult{});
  int checked = 0;
  for (const auto& p : pts) {
    if (p["pose_name"] == "I") {
      EXPECT_NEAR(p["rel_dev_um"].get<double>(), 0.0, 1e-9);
    }
    if (p["pose_name"] == "III" && (p["face"] == "+X" || p["face"] == "-X")) {
      // Outward normal of +X at C = 180 is -X in the machine: the piece moved by -2 dx along it?
      EXPECT_NEAR(std::abs(p["rel_dev_um"].get<double>()), 2 * 14.6, 0.01) << p.dump();
      ++checked;
    }
  }
  EXPECT_EQ(checked, 8);
}

}  // namespace
}  // namespace rotacal
