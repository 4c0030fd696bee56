// The independent generator (bench/independent_machine.hpp) against rotacal's own simulator and
// against the closed form of 000 Eq. (22)-(23). The generator shares no code with
// core/simulation, so agreement on a clean machine checks both readings of 000 Eq. (1), the
// set-up and the contact; the statistics check that its linear axes are the model the
// contributors file declares.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "bench/independent_machine.hpp"
#include "bench/independent_rtest.hpp"
#include "core/contributors.hpp"
#include "core/machine.hpp"
#include "core/simulation.hpp"
#include "cycles/cycle.hpp"
#include "cycles/rtest/analyze.hpp"
#include "cycles/rtest/plan.hpp"
#include "cycles/spaceframe/analyze.hpp"
#include "cycles/tooltip/plan.hpp"

namespace rotacal {
namespace {

namespace ind = independent;

const std::string kMachine = std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/ac_trunnion.json";
const std::string kContrib = std::string(ROTACAL_SOURCE_DIR) + "/examples/contributors/table5.json";

const ProbePlan& touch154() {
  static const ProbePlan plan = makePlan("touch154", loadMachine(kMachine), {});
  return plan;
}

// The largest difference between two runs' triggers, um.
double maxDiffUm(const MeasurementRun& a, const MeasurementRun& b) {
  EXPECT_EQ(a.points.size(), b.points.size());
  double worst = 0;
  for (size_t i = 0; i < a.points.size() && i < b.points.size(); ++i) {
    EXPECT_EQ(a.points[i].point_id, b.points[i].point_id);
    worst = std::max(worst, 1e3 * (a.points[i].position_m_mm - b.points[i].position_m_mm).norm());
  }
  return worst;
}

LocationErrors table4() {
  LocationErrors e;
  e.kinematics = Kinematics::TableAC;
  const double v[8] = {14.6, 23.2, 27.7, 3.9, -0.5, -0.1, -0.5, 0.2};
  const char* names[8] = {"dx_AY", "dy_AY", "dz_AY", "dy_CA", "a_AY", "b_AY", "c_AY", "b_CA"};
  for (int i = 0; i < 8; ++i) e.setReportValue(parameterIndex(Kinematics::TableAC, names[i]), v[i]);
  return e;
}

struct Moments {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double x) { sum += x, sum2 += x * x, ++n; }
  double mean() const { return sum / n; }
  double var() const { return (sum2 - sum * sum / n) / (n - 1); }
};

double triggerShiftUm(const MeasurementRun& a, const MeasurementRun& nominal) {
  double worst = 0;
  for (size_t i = 0; i < a.points.size(); ++i)
    worst = std::max(worst, 1e3 * (a.points[i].position_m_mm - nominal.points[i].position_m_mm).norm());
  return worst;
}

// A clean machine (location errors only, no noise): both simulators give the same triggers, for
// 000 Table 4's errors and for each error alone at a size that shows its sign (100 um, 10 mdeg).
TEST(IndependentMachine, CleanMachineTriggersEqualRotacalSimulate) {
  const ProbePlan& plan = touch154();
  std::vector<LocationErrors> cases = {table4()};
  for (int k = 0; k < kNumLocationErrors; ++k) {
    LocationErrors e;
    e.kinematics = Kinematics::TableAC;
    const bool length = locationParameters(Kinematics::TableAC)[static_cast<size_t>(k)].kind == ParamKind::Length;
    e.setReportValue(k, length ? 100.0 : 10.0);
    cases.push_back(e);
  }
  Truth perfect;
  const MeasurementRun nominal = simulate(plan, perfect, {});
  for (const LocationErrors& e : cases) {
    Truth truth;
    truth.errors = e;
    const MeasurementRun theirs = simulate(plan, truth, {});
    const MeasurementRun ours = ind::measure(plan, ind::cleanMachine(e));
    EXPECT_LT(maxDiffUm(ours, theirs), 1e-6);
    // and the case moves the triggers at all (a test of nothing would pass too)
    EXPECT_GT(triggerShiftUm(ours, nominal), 5.0);
  }
}

// The set-up and each part of the form alone, against rotacal's ArtefactTruth. The tilt axes are
// defined differently (here Z x n on the sides; rotacal's +Y or +X): the same physical tilt is
// handed to each in its own convention.
TEST(IndependentMachine, SetupAndFormEqualRotacalSimulate) {
  const ProbePlan& plan = touch154();
  const LocationErrors e = table4();
  ind::Machine ours = ind::cleanMachine(e);
  Truth truth;
  truth.errors = e;
  ours.setup_translation_mm = truth.artefact.setup.translation_mm = Eigen::Vector3d(0.5, -0.4, 0.12);
  ours.setup_rotation_rad = truth.artefact.setup.rotation_rad = Eigen::Vector3d(1e-3, -2e-3, 3e-3);
  EXPECT_LT(maxDiffUm(ind::measure(plan, ours), simulate(plan, truth, {})), 1e-6);

  for (const bool tilts : {false, true}) {
    for (Face f : kAllFaces) {
      const size_t i = static_cast<size_t>(f);
      if (!tilts) {
        ours.form[i] = {0.05 * (1 + static_cast<double>(i)), 0, 0};
        truth.artefact.form[i] = {0.05 * (1 + static_cast<double>(i)), 0, 0};
        continue;
      }
      const Eigen::Vector3d n = faceNormal_w(f);
      const Eigen::Vector3d u_ours = f == Face::Top ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ().cross(n);
      const auto axes = faceAxes_w(f);
      const double tu = 2e-3 * (1 + static_cast<double>(i)), tv = -1e-3 * (1 + static_cast<double>(i));
      ours.form[i] = {0, tu, tv};
      truth.artefact.form[i] = {0, tu * u_ours.dot(axes[0]), tv};
    }
    EXPECT_LT(maxDiffUm(ind::measure(plan, ours), simulate(plan, truth, {})), 1e-6) << (tilts ? "tilts" : "offsets");
  }
}

// The contact with the linear axes' error field: rotacal's simulator given this generator's
// field (drawn from 000 Table 5) and pretravel by direction finds the same triggers; the
// field itself is what the statistics below check.
TEST(IndependentMachine, LinearAxesAndPretravelContactEqualsRotacalSimulate) {
  const ProbePlan& plan = touch154();
  ContributorSet c = loadContributors(kContrib);
  ind::DrawOptions o;
  o.setup = o.form = o.repeatability = o.roughness = false;
  ind::Machine m = ind::drawMachine(c, plan.machine, o, 7);
  m.pretravel_mm = {1e-3, -2e-3, 3e-3, 0.5e-3, -1.5e-3, 2.5e-3};
  Truth truth;
  truth.errors = m.location;
  truth.linear_axis_error = [&m](const Eigen::Vector3d& read) { return m.axes.error(read); };
  truth.pretravel_by_direction_um = [&m](const Eigen::Vector3d& u) {
    double pt = 0;
    for (int k = 0; k < 3; ++k) pt += u[k] * u[k] * m.pretravel_mm[static_cast<size_t>(2 * k + (u[k] < 0 ? 1 : 0))];
    return 1e3 * pt;
  };
  const MeasurementRun ours = ind::measure(plan, m);
  EXPECT_LT(maxDiffUm(ours, simulate(plan, truth, {})), 1e-6);
  Truth without = truth;
  without.linear_axis_error = nullptr;
  EXPECT_GT(maxDiffUm(ours, simulate(plan, without, {})), 1.0);  // the axes do act (um)
}

// A sphere cycle's plan (one_sphere): the same agreement on the sphere, moved off its place, with
// and without this generator's linear-axis field.
TEST(IndependentMachine, SphereTriggersEqualRotacalSimulate) {
  const ProbePlan plan = makePlan("one_sphere", loadMachine(kMachine), {});
  ContributorSet c = loadContributors(kContrib);
  ind::DrawOptions o;
  o.form = o.pretravel = o.repeatability = o.roughness = false;
  for (const bool axes : {false, true}) {
    o.linear_axes = axes;
    const ind::Machine m = ind::drawMachine(c, plan.machine, o, 3);
    Truth truth;
    truth.errors = m.location;
    for (const auto& p : plan.points) truth.sphere_center_error_w_mm[p.sphere->id] = m.setup_translation_mm;
    if (axes) truth.linear_axis_error = [&m](const Eigen::Vector3d& read) { return m.axes.error(read); };
    EXPECT_LT(maxDiffUm(ind::measure(plan, m), simulate(plan, truth, {})), 1e-6) << (axes ? "with axes" : "");
    EXPECT_GT(m.setup_translation_mm.norm(), 1e-3);  // the sphere is off its place (mm)
  }
}

// The space frame's bundled plan (003's seven spheres, the reduced map of ac_trunnion.json): a
// clean machine, then the frame set up off its place, turned about one axis at a time (where the
// two conventions of a turn agree) about its origin and shifted, its spheres placed by the
// cycle's own FrameModel (written for the identification, not for this generator), then the
// linear axes' field as well: the same triggers as rotacal's `simulate` to 1e-6 um.
const ProbePlan& spaceframe() {
  static const ProbePlan plan = makePlan("spaceframe", loadMachine(kMachine), {{"phi_list", "-90,-45,0"}});
  return plan;
}
TEST(IndependentMachine, SpaceframeTriggersEqualRotacalSimulate) {
  const ProbePlan& plan = spaceframe();
  ASSERT_GT(plan.points.size(), 700u);
  const LocationErrors e = table4();
  Truth truth;
  truth.errors = e;
  ind::Machine ours = ind::cleanMachine(e);
  EXPECT_LT(maxDiffUm(ind::measure(plan, ours), simulate(plan, truth, {})), 1e-6);
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  const ContributorSet c = loadContributors(kContrib);
  for (int axis = 0; axis < 4; ++axis) {
    ours = ind::cleanMachine(e);
    ours.setup_translation_mm = Eigen::Vector3d(0.03, -0.02, 0.15);
    if (axis < 3) ours.setup_rotation_rad[axis] = 2e-3 * (axis + 1);
    if (axis == 3) {  // and with the linear axes' field drawn by this generator
      ind::DrawOptions o;
      o.setup = o.form = o.pretravel = o.repeatability = o.roughness = false;
      const ind::Machine drawn = ind::drawMachine(c, plan.machine, o, 9);
      ours.has_linear_axes = true;
      ours.axes = drawn.axes;
      ours.setup_rotation_rad = Eigen::Vector3d(0, 0, 1e-3);
    }
    FrameModel frame;
    frame.setup_translation_mm = ours.setup_translation_mm;
    frame.setup_rotation_rad = ours.setup_rotation_rad;
    Truth t;
    t.errors = e;
    for (int s = 1; s <= 7; ++s) {
      const Eigen::Vector3d p = layout.origin_w_mm + layout.frame.spheres_mm[static_cast<size_t>(s - 1)];
      t.sphere_center_error_w_mm[s] = frame.placedCentre_w(p, s, layout.origin_w_mm) - p;
    }
    const ind::Machine& m = ours;
    if (axis == 3) t.linear_axis_error = [&m](const Eigen::Vector3d& read) { return m.axes.error(read); };
    const MeasurementRun theirs = simulate(plan, t, {});
    EXPECT_LT(maxDiffUm(ind::measure(plan, ours), theirs), 1e-6) << "case " << axis;
    // and the turn acts beyond the shift (um): a sphere 200 mm from the origin moves 0.4 mm
    ind::Machine shifted = ours;
    shifted.setup_rotation_rad.setZero();
    EXPECT_GT(maxDiffUm(ind::measure(plan, shifted), theirs), 50.0) << "case " << axis;
  }
}

// The frame's set-up draw against its closed form: each sphere's centre moves by the shift t plus
// the turn r about the frame's origin, to first order t + r x l (l the sphere's lever from the
// origin), so Var(d_x) = u_tx^2 + u_ry^2 l_z^2 + u_rz^2 l_y^2 and cyclically, with u from the
// contributors file (setup_position, setup_orientation). 4000 machines; 4 standard errors.
TEST(IndependentMachine, SpaceframeSetupDrawHasItsClosedFormSpread) {
  const ProbePlan& plan = spaceframe();
  const ContributorSet c = loadContributors(kContrib);
  const SpaceframeLayout layout = SpaceframeLayout::fromOptions(plan.options);
  const Contributor* pos = c.find("setup_position");
  const Contributor* ori = c.find("setup_orientation");
  ASSERT_TRUE(pos && ori);
  const int N = 4000;
  for (const int sphere : {1, 3, 7}) {
    const ProbePoint* point = nullptr;
    for (const auto& p : plan.points)
      if (p.sphere->id == sphere) point = &p;
    ASSERT_NE(point, nullptr);
    const Eigen::Vector3d l = point->sphere->center_w_mm - layout.origin_w_mm;
    std::array<Moments, 3> d;
    for (int k = 0; k < N; ++k) {
      const ind::Machine m = ind::drawMachine(c, plan.machine, {}, 5000 + static_cast<std::uint64_t>(k));
      const Eigen::Vector3d x = ind::sphereCentre_w(plan, *point, m) - point->sphere->center_w_mm;
      for (int i = 0; i < 3; ++i) d[static_cast<size_t>(i)].add(x[i]);
    }
    const double se = std::sqrt(2.0 / (N - 1));
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      const double v = std::pow(pos->u[i], 2) + std::pow(ori->u[j] * l[k], 2) + std::pow(ori->u[k] * l[j], 2);
      EXPECT_NEAR(d[static_cast<size_t>(i)].var() / v, 1.0, 4 * se) << "sphere " << sphere << " axis " << i;
      EXPECT_NEAR(d[static_cast<size_t>(i)].mean(), 0.0, 4 * std::sqrt(v / N));
    }
  }
}

// The tool-tip test (004) on its bundled machine (head_ab.json), stepping A and stepping B: the
// head's pivot-length and angular errors alone, then with this generator's linear axes under the
// pivot and its tilted beams, give rotacal's simulateTooltip's readings (no noise) to 1e-6 um.
const std::string kHead = std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/head_ab.json";
const std::string kTooltipContrib = std::string(ROTACAL_SOURCE_DIR) + "/examples/contributors/tooltip_004.json";

double maxDiffUm(const TooltipRun& a, const TooltipRun& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    EXPECT_EQ(a[i].angle_deg, b[i].angle_deg);
    worst = std::max({worst, std::abs(a[i].t_um - b[i].t_um), std::abs(a[i].z_um - b[i].z_um)});
  }
  return worst;
}

TEST(IndependentMachine, TooltipReadingsEqualRotacalSimulate) {
  const MachineModel machine = loadMachine(kHead);
  const ContributorSet c = loadContributors(kTooltipContrib);
  for (const char* axis : {"A", "B"}) {
    const ProbePlan plan = makePlan("tooltip", machine, {{"axis", axis}});
    ASSERT_EQ(plan.points.size(), 19u);
    for (const bool machine_terms : {false, true}) {
      ind::HeadDrawOptions o;
      o.per_reading = false;
      o.linear_axes = o.alignment = machine_terms;
      const ind::Head head = ind::drawHead(c, machine, o, 21);
      TooltipTruth truth;
      truth.dR_um = 1e3 * head.dR_mm;
      truth.offset_mdeg = head.angular_mdeg[0];
      truth.slope_mdeg_per_90deg = head.angular_mdeg[1];
      truth.sin_mdeg = head.angular_mdeg[2];
      truth.sin2_mdeg = head.angular_mdeg[3];
      TooltipMachine theirs;
      if (machine_terms) {
        theirs.pivot_error_mm = [&head](const Eigen::Vector3d& p) { return head.axes.error(p); };
        theirs.beam_t = head.beamT(axis[0]);
        theirs.beam_z = head.beamZ(axis[0]);
      }
      const TooltipRun ours = ind::measureHead(plan, head);
      EXPECT_LT(maxDiffUm(ours, simulateTooltip(plan, truth, 1, theirs)), 1e-6) << axis << machine_terms;
      // and what is compared moves the readings (um): the head's errors, then the machine's terms
      EXPECT_GT(maxDiffUm(ours, simulateTooltip(plan, TooltipTruth{}, 1)), 5.0);
      if (machine_terms) {
        EXPECT_GT(maxDiffUm(ours, simulateTooltip(plan, truth, 1)), 1.0);
      }
    }
  }
}

// The per-reading scatter against its closed form: each beam's raw reading scatters by the laser's
// own error, the sphere's form and the lateral coupling (tooltip_004.json, k = 1), s^2 their sum
// of squares, and the laser is zeroed on the sweep's first reading, whose scatter every later
// reading carries: Var = 2 s^2 per value, Cov = s^2 between two readings of one beam, 0 between
// the beams. The beams' alignment: a tilt a towards the other in-plane axis reads a x that axis's
// deviation, Var = u_a^2 d^2 to first order (d the aligned beams' reading there). The linear axes'
// node values have the declared u of E_yy_rand and none where the file declares none.
// 4000 machines; 4 standard errors.
TEST(IndependentMachine, TooltipDrawHasItsClosedFormSpread) {
  const MachineModel machine = loadMachine(kHead);
  const ContributorSet c = loadContributors(kTooltipContrib);
  const ProbePlan plan = makePlan("tooltip", machine, {});
  const double s2 = std::pow(c.find("laser_resolution")->u[0], 2) + std::pow(c.find("laser_sphere_form")->u[0], 2) +
                    std::pow(c.find("laser_lateral_coupling")->u[0], 2);  // mm^2
  const double ua = c.find("laser_alignment")->u[0];
  const int N = 4000;
  const double se = std::sqrt(2.0 / (N - 1));
  ind::HeadDrawOptions fixed;  // the head itself the same on every machine: dR 200 um, no angular error
  fixed.dR_um = 200.0, fixed.sd_dR_um = 0.0, fixed.sd_mdeg = 0.0, fixed.angular_mdeg = {0, 0, 0, 0};
  fixed.linear_axes = false;
  ind::HeadDrawOptions scatter = fixed, aligned = fixed;
  scatter.alignment = false;
  aligned.per_reading = false;
  ind::HeadDrawOptions none = aligned;
  none.alignment = false;
  const TooltipRun d = ind::measureHead(plan, ind::drawHead(c, machine, none, 1));
  const size_t k = 9, l = 14;  // A = 45 and 70 deg
  Moments tk, zk, cov_tl, at, az, node_yy;
  std::vector<double> tl;
  double yx_max = 0;
  for (int i = 0; i < N; ++i) {
    const std::uint64_t seed = 9000 + static_cast<std::uint64_t>(i);
    const TooltipRun r = ind::measureHead(plan, ind::drawHead(c, machine, scatter, seed));
    tk.add(r[k].t_um - d[k].t_um);
    zk.add(r[k].z_um - d[k].z_um);
    cov_tl.add((r[k].t_um - d[k].t_um) * (r[l].t_um - d[l].t_um));
    const TooltipRun a = ind::measureHead(plan, ind::drawHead(c, machine, aligned, seed));
    at.add(a[l].t_um - d[l].t_um);
    az.add(a[k].z_um - d[k].z_um);
    const ind::Head h = ind::drawHead(c, machine, {}, seed);
    node_yy.add(h.axes.randomPart(1, 1, 2 * h.axes.spacing_mm[1]));
    yx_max = std::max(yx_max, std::abs(h.axes.randomPart(1, 0, 2 * h.axes.spacing_mm[1])));
  }
  const double s2_um = 1e6 * s2;
  EXPECT_NEAR(tk.var() / (2 * s2_um), 1.0, 4 * se);
  EXPECT_NEAR(zk.var() / (2 * s2_um), 1.0, 4 * se);
  EXPECT_NEAR(tk.mean(), 0.0, 4 * std::sqrt(2 * s2_um / N));
  EXPECT_NEAR(cov_tl.mean() / s2_um, 1.0, 4 * std::sqrt(5.0 / N));
  // the alignment reads the other in-plane component: t at 70 deg reads a x dz, z at 45 deg a x dy
  ASSERT_GT(std::abs(d[l].z_um), 20.0);
  ASSERT_GT(std::abs(d[k].t_um), 20.0);
  EXPECT_NEAR(at.var() / std::pow(ua * d[l].z_um, 2), 1.0, 4 * se);
  EXPECT_NEAR(az.var() / std::pow(ua * d[k].t_um, 2), 1.0, 4 * se);
  EXPECT_NEAR(node_yy.var() / std::pow(c.find("E_yy_rand")->u[0], 2), 1.0, 4 * se);
  EXPECT_EQ(yx_max, 0.0);
}

// A chip of c under one touch moves that trigger back along the approach by c (to the
// cosine of the face's tilt) and no other.
TEST(IndependentMachine, ChipReadsTheSurfaceCloserAtItsTouchAlone) {
  const ProbePlan& plan = touch154();
  ContributorSet c = loadContributors(kContrib);
  ind::DrawOptions o;
  o.linear_axes = false;  // their slope would change the shift by ~1e-4 c
  const ind::Machine m = ind::drawMachine(c, plan.machine, o, 11);
  const MeasurementRun clean = ind::measure(plan, m);
  const int id = plan.points[40].id;
  const MeasurementRun chipped = ind::measure(plan, m, ind::Chip{id, 0.020});
  for (size_t i = 0; i < plan.points.size(); ++i) {
    const Eigen::Vector3d d = chipped.points[i].position_m_mm - clean.points[i].position_m_mm;
    if (plan.points[i].id != id) {
      EXPECT_EQ(d.norm(), 0.0);
      continue;
    }
    // back along the approach by c over the cosine between the approach and the true face's
    // normal (the form's tilts and the set-up turn it by a few mrad)
    const double cosine = std::abs(ind::facePlane_m(plan, plan.points[i], m).normal_m.dot(plan.points[i].approach_m));
    EXPECT_NEAR(d.dot(plan.points[i].approach_m), -0.020 / cosine, 1e-12);
    EXPECT_NEAR(d.norm(), 0.020, 1e-6);
  }
}

// Var(E_ba,rand(q)) at a fixed q averaged over the spacing p ~ U[p_min, p_max]: u^2 times
// E_p[(1 - f)^2 + f^2], f = frac(q / p), integrated numerically (midpoint rule, 2e5 steps).
double interpolationFactor(double q, double p_min, double p_max) {
  const int n = 200000;
  double s = 0;
  for (int i = 0; i < n; ++i) {
    const double p = p_min + (p_max - p_min) * (i + 0.5) / n;
    const double f = q / p - std::floor(q / p);
    s += (1 - f) * (1 - f) + f * f;
  }
  return s / n;
}


// 000 Eq. (22)-(23) in closed form against the drawn machines: at a node the random part has the
// declared variance u^2, midway between nodes u^2 / 2 (two independent nodes weighed 1/2 each);
// at a fixed position, over the drawn spacings, u^2 E_p[(1 - f)^2 + f^2] plus the slope's
// (u_slope q)^2; the spacing is uniform on the file's range. Tolerances: 4 standard errors.
TEST(IndependentMachine, LinearAxisDrawHasEq22And23Statistics) {
  const ContributorSet c = loadContributors(kContrib);
  const MachineModel machine = loadMachine(kMachine);
  const int N = 4000;
  const double u_rand = c.find("E_xy_rand")->u[0], u_S = c.find("S_xy")->u[0], u_lin = c.find("E_yy_lin")->u[0];
  const double q = 137.0;  // mm along Y, not a multiple of anything
  Moments node, mid, fixed_xy, fixed_yy, spacing, node_zz;
  for (int k = 0; k < N; ++k) {
    const ind::Machine m = ind::drawMachine(c, machine, {}, 1000 + static_cast<std::uint64_t>(k));
    const ind::LinearAxes& a = m.axes;
    const double p = a.spacing_mm[1];
    spacing.add(p);
    node.add(a.randomPart(1, 0, 3 * p));           // E_xy,rand at a node
    mid.add(a.randomPart(1, 0, 3.5 * p));          // midway
    fixed_xy.add(a.component(1, 0, q));            // S_xy q + E_xy,rand(q)
    fixed_yy.add(a.component(1, 1, q));            // E_yy,lin q + E_yy,rand(q)
    node_zz.add(a.component(2, 2, -2 * a.spacing_mm[2]) + 2 * a.spacing_mm[2] * a.scale[2]);  // random part at a node
  }
  const double se = std::sqrt(2.0 / (N - 1));  // relative standard error of a variance
  const double g = interpolationFactor(q, c.node_spacing_min_mm, c.node_spacing_max_mm);
  EXPECT_NEAR(node.var() / (u_rand * u_rand), 1.0, 4 * se);
  EXPECT_NEAR(node_zz.var() / std::pow(c.find("E_zz_rand")->u[0], 2), 1.0, 4 * se);
  EXPECT_NEAR(mid.var() / (u_rand * u_rand), 0.5, 4 * se * 0.5);
  const double v_xy = u_S * u_S * q * q + u_rand * u_rand * g;
  const double v_yy = u_lin * u_lin * q * q + std::pow(c.find("E_yy_rand")->u[0], 2) * g;
  EXPECT_NEAR(fixed_xy.var() / v_xy, 1.0, 4 * se);
  EXPECT_NEAR(fixed_yy.var() / v_yy, 1.0, 4 * se);
  EXPECT_NEAR(node.mean(), 0.0, 4 * u_rand / std::sqrt(N));
  EXPECT_NEAR(fixed_xy.mean(), 0.0, 4 * std::sqrt(v_xy / N));
  // the spacing: uniform on [20, 50] mm has mean 35 and variance 30^2 / 12
  EXPECT_NEAR(spacing.mean(), 0.5 * (c.node_spacing_min_mm + c.node_spacing_max_mm),
              4 * (c.node_spacing_max_mm - c.node_spacing_min_mm) / std::sqrt(12.0 * N));
  EXPECT_NEAR(spacing.var() / (std::pow(c.node_spacing_max_mm - c.node_spacing_min_mm, 2) / 12), 1.0, 4 * 0.02);
  // the factor itself lies between the midway 1/2 and the node's 1
  EXPECT_GT(g, 0.5);
  EXPECT_LT(g, 1.0);
}

// Two machines from one seed are the same machine; another seed is another.
TEST(IndependentMachine, SeededDraws) {
  const ContributorSet c = loadContributors(kContrib);
  const ProbePlan& plan = touch154();
  const MeasurementRun a = ind::measure(plan, ind::drawMachine(c, plan.machine, {}, 5));
  const MeasurementRun b = ind::measure(plan, ind::drawMachine(c, plan.machine, {}, 5));
  const MeasurementRun d = ind::measure(plan, ind::drawMachine(c, plan.machine, {}, 6));
  EXPECT_EQ(maxDiffUm(a, b), 0.0);
  EXPECT_GT(maxDiffUm(a, d), 1.0);
}

// ---- The R-test (002) on the B/C table ----

const std::string kBcMachine = std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/bc_trunnion.json";
const std::string kRtestContrib = std::string(ROTACAL_SOURCE_DIR) + "/examples/contributors/rtest_002.json";

// The bundled example's plan (`plan --cycle rtest` with no options: one cycle, the reset read
// before the first pose and again after the last).
const ProbePlan& rtestPlan() {
  static const ProbePlan plan = makePlan("rtest", loadMachine(kBcMachine), {});
  return plan;
}
// Three cycles of the thermal schedule (the clock across cycles).
const ProbePlan& rtestThermalPlan() {
  static const ProbePlan plan =
      makePlan("rtest", loadMachine(kBcMachine), {{"thermal", "1"}, {"interval_min", "15"}, {"duration_h", "0.5"}});
  return plan;
}

// Every reading of a series in order (reset, poses, re-read per cycle).
std::vector<RtestReading> readingsOf(const RtestSeries& s) {
  std::vector<RtestReading> out;
  for (const RtestCycle& c : s.cycles) {
    if (c.reset) out.push_back(*c.reset);
    out.insert(out.end(), c.readings.begin(), c.readings.end());
    if (c.reread) out.push_back(*c.reread);
  }
  return out;
}

// The largest difference between two series' readings (um), the poses, angles and times equal.
double maxReadingDiffUm(const RtestSeries& a, const RtestSeries& b) {
  const auto ra = readingsOf(a), rb = readingsOf(b);
  EXPECT_EQ(ra.size(), rb.size());
  double worst = 0;
  for (size_t i = 0; i < ra.size() && i < rb.size(); ++i) {
    EXPECT_EQ(ra[i].pose_id, rb[i].pose_id);
    EXPECT_DOUBLE_EQ(ra[i].t_s, rb[i].t_s);
    EXPECT_DOUBLE_EQ(ra[i].tilt_deg, rb[i].tilt_deg);
    EXPECT_DOUBLE_EQ(ra[i].c_deg, rb[i].c_deg);
    worst = std::max(worst, 1e3 * (ra[i].dq_w_mm - rb[i].dq_w_mm).norm());
  }
  return worst;
}

// The bundled example's truth (examples/truth/bc_location.json), B/C order.
LocationErrors bcLocation() {
  LocationErrors e;
  e.kinematics = Kinematics::TableBC;
  const double v[8] = {12.4, -8.6, -15.3, 24.0, -31.0, 18.0, -27.0, 9.7};
  for (int k = 0; k < kNumLocationErrors; ++k) e.setReportValue(k, v[k]);
  return e;
}

RtestSeries rotacalRtest(const ProbePlan& plan, const Truth& truth, const RtestTruthExtras& extras) {
  RtestSimOptions o;
  o.noise_um = 0.0;
  return simulateRtest(plan, truth, extras, o);
}

// A clean machine (location errors only, no noise): the generator's readings equal rotacal's
// `simulate`, for the example's eight errors together and for each alone at a size that shows its
// sign (100 um, 10 mdeg): both readings of 002 Eq. (1)-(4) agree.
TEST(IndependentRtest, CleanMachineReadingsEqualRotacalSimulate) {
  const ProbePlan& plan = rtestPlan();
  std::vector<LocationErrors> cases = {bcLocation()};
  for (int k = 0; k < kNumLocationErrors; ++k) {
    LocationErrors e;
    e.kinematics = Kinematics::TableBC;
    const bool length = locationParameters(Kinematics::TableBC)[static_cast<size_t>(k)].kind == ParamKind::Length;
    e.setReportValue(k, length ? 100.0 : 10.0);
    cases.push_back(e);
  }
  for (const LocationErrors& e : cases) {
    Truth truth;
    truth.errors = e;
    const RtestSeries theirs = rotacalRtest(plan, truth, {});
    const RtestSeries ours = ind::measureRtest(plan, ind::cleanRtestMachine(e));
    ASSERT_EQ(ours.cycles.size(), 1u);
    ASSERT_TRUE(ours.cycles[0].reset && ours.cycles[0].reread);
    EXPECT_LT(maxReadingDiffUm(ours, theirs), 1e-6);
    // and the case moves the readings at all
    double largest = 0;
    for (const auto& r : readingsOf(ours)) largest = std::max(largest, 1e3 * r.dq_w_mm.norm());
    EXPECT_GT(largest, 5.0);
  }
}

// A whole drawn machine without its per-reading scatter (location errors, linear axes, sphere
// offset, drift, the sensors' gain and directions) handed to rotacal's simulator as its truth
// (linear_axis_error, sphere offset and drift, sensor_response) gives the same readings over
// three cycles of the thermal schedule.
TEST(IndependentRtest, DrawnMachineEqualsRotacalSimulateGivenItsParts) {
  const ProbePlan& plan = rtestThermalPlan();
  const ContributorSet c = loadContributors(kRtestContrib);
  ind::RtestDrawOptions o;
  o.noise = o.form = false;
  const ind::RtestMachine m = ind::drawRtestMachine(c, plan, o, 11);
  Truth truth;
  truth.errors = m.location;
  truth.linear_axis_error = [&m](const Eigen::Vector3d& read) { return m.axes.error(read); };
  RtestTruthExtras extras;
  extras.sphere_offset_m_mm = m.sphere_offset_mm;
  extras.sphere_drift_m_mm = [&m](double t) { return Eigen::Vector3d(m.drift_mm_per_s * t); };
  extras.sensor_response = m.response();
  const RtestSeries ours = ind::measureRtest(plan, m);
  ASSERT_EQ(ours.cycles.size(), 3u);
  EXPECT_LT(maxReadingDiffUm(ours, rotacalRtest(plan, truth, extras)), 1e-6);
  // each part moves the readings: without it rotacal's differ by more than 0.01 um
  Truth bare = truth;
  bare.linear_axis_error = nullptr;
  EXPECT_GT(maxReadingDiffUm(ours, rotacalRtest(plan, bare, extras)), 0.5);
  RtestTruthExtras no_sensors = extras;
  no_sensors.sensor_response = Eigen::Matrix3d::Identity();
  EXPECT_GT(maxReadingDiffUm(ours, rotacalRtest(plan, truth, no_sensors)), 0.01);
}

// Each of the sensors' errors alone against its closed form: a gain scales its sensor's reading
// by 1 + g; a direction error tilts the plunger, which reads the displacement along its own unit
// direction: (d_i + e_j d_j + e_k d_k) / sqrt(1 + e_j^2 + e_k^2).
TEST(IndependentRtest, SensorGainAndDirectionHaveTheirClosedForm) {
  const ProbePlan& plan = rtestPlan();
  const ind::RtestMachine clean = ind::cleanRtestMachine(bcLocation());
  const auto base = readingsOf(ind::measureRtest(plan, clean));
  ind::RtestMachine gain = clean;
  gain.gain = {1e-3, -2e-3, 3e-3};
  const auto g = readingsOf(ind::measureRtest(plan, gain));
  ind::RtestMachine dir = clean;
  dir.direction = {2e-3, -1e-3, 3e-3, 1.5e-3, -2.5e-3, 0.5e-3};  // xy xz yx yz zx zy
  const auto d = readingsOf(ind::measureRtest(plan, dir));
  ASSERT_EQ(g.size(), base.size());
  double moved_g = 0, moved_d = 0;
  for (size_t r = 0; r < base.size(); ++r) {
    const Eigen::Vector3d q = base[r].dq_w_mm;
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(g[r].dq_w_mm[i], (1.0 + gain.gain[static_cast<size_t>(i)]) * q[i], 1e-12);
      const int j = i == 0 ? 1 : 0, k = i == 2 ? 1 : 2;
      const double ej = dir.direction[static_cast<size_t>(2 * i)], ek = dir.direction[static_cast<size_t>(2 * i + 1)];
      EXPECT_NEAR(d[r].dq_w_mm[i], (q[i] + ej * q[j] + ek * q[k]) / std::sqrt(1 + ej * ej + ek * ek), 1e-12);
    }
    moved_g = std::max(moved_g, 1e3 * (g[r].dq_w_mm - q).norm());
    moved_d = std::max(moved_d, 1e3 * (d[r].dq_w_mm - q).norm());
  }
  EXPECT_GT(moved_g, 0.05);
  EXPECT_GT(moved_d, 0.05);
}

// The sphere's offset and its drift alone on a perfect table, in closed form: the sphere at
// rq + s + v t reads (R_z(C) R_y(B)) (s + v t) - (s + v t0) against the zero at the first reset
// (t0); the re-read minus the reset is the drift over the time between them, and the drift over
// one measuring cycle is what the contributors file declares (rtest_cycle_drift).
TEST(IndependentRtest, SphereOffsetAndDriftHaveTheirClosedForm) {
  const ProbePlan& plan = rtestThermalPlan();
  LocationErrors none;
  none.kinematics = Kinematics::TableBC;
  ind::RtestMachine m = ind::cleanRtestMachine(none);
  m.sphere_offset_mm = Eigen::Vector3d(2e-3, -3e-3, 5e-3);
  const Eigen::Vector3d per_cycle(0.05e-3, 0.1e-3, -0.05e-3);
  m.drift_mm_per_s = per_cycle / rtestCycleTime_s(plan);
  const RtestSeries s = ind::measureRtest(plan, m);
  const double t0 = s.cycles.front().reset->t_s;
  const Eigen::Vector3d zero = m.sphere_offset_mm + m.drift_mm_per_s * t0;
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  for (const auto& r : readingsOf(s)) {
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(r.c_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(r.tilt_deg * kDeg, Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();
    const Eigen::Vector3d expected = R * (m.sphere_offset_mm + m.drift_mm_per_s * r.t_s) - zero;
    EXPECT_LT(1e3 * (r.dq_w_mm - expected).norm(), 1e-9);
  }
  for (const RtestCycle& c : s.cycles) {
    const Eigen::Vector3d d = c.reread->dq_w_mm - c.reset->dq_w_mm;
    EXPECT_LT(1e3 * (d - m.drift_mm_per_s * (c.reread->t_s - c.reset->t_s)).norm(), 1e-9);
  }
  // the drawn drift is declared over one cycle: the rate times the cycle's time is the draw
  const ContributorSet c = loadContributors(kRtestContrib);
  ind::RtestDrawOptions only;
  only.linear_axes = only.sphere = only.sensors = only.noise = only.form = false;
  const ind::RtestMachine drawn = ind::drawRtestMachine(c, plan, only, 3);
  const Eigen::Vector3d over_cycle = drawn.drift_mm_per_s * rtestCycleTime_s(plan);
  for (int i = 0; i < 3; ++i) {
    EXPECT_GT(std::abs(over_cycle[i]), 0.0);
    EXPECT_LT(std::abs(over_cycle[i]), 5 * c.find("rtest_cycle_drift")->u[i]);
  }
}

// The per-reading scatter: each value of a clean machine's series is the sensor's and the
// sphere form's draw, normal with variance u_sensor^2 + u_form^2 (0.2 and 0.1 um: 0.05 um^2),
// independent between values; over 200 machines x 81 values x 3 sensors.
TEST(IndependentRtest, PerReadingScatterHasItsDeclaredVariance) {
  const ProbePlan& plan = rtestPlan();
  const ContributorSet c = loadContributors(kRtestContrib);
  ind::RtestDrawOptions o;
  o.linear_axes = o.sphere = o.sensors = o.drift = false;
  LocationErrors none;
  none.kinematics = Kinematics::TableBC;
  Moments v, lag;
  double prev = 0;
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    ind::RtestMachine m = ind::drawRtestMachine(c, plan, o, seed);
    m.location = none;  // a perfect table: every reading is its scatter alone
    bool first = true;
    for (const auto& r : readingsOf(ind::measureRtest(plan, m)))
      for (int i = 0; i < 3; ++i) {
        const double x = 1e3 * r.dq_w_mm[i];
        v.add(x);
        if (!first) lag.add(x * prev);
        prev = x, first = false;
      }
  }
  const double expected = 0.2 * 0.2 + 0.1 * 0.1;
  const double se = std::sqrt(2.0 / v.n);
  EXPECT_NEAR(v.var() / expected, 1.0, 4 * se);
  EXPECT_NEAR(v.mean(), 0.0, 4 * std::sqrt(expected / v.n));
  EXPECT_NEAR(lag.mean() / expected, 0.0, 4 / std::sqrt(static_cast<double>(lag.n)));  // no correlation between values
}

// A chip (a sensor glitch) moves its one value by c and nothing else.
TEST(IndependentRtest, ChipMovesOneValueAlone) {
  const ProbePlan& plan = rtestThermalPlan();
  const ContributorSet c = loadContributors(kRtestContrib);
  const ind::RtestMachine m = ind::drawRtestMachine(c, plan, {}, 9);
  const auto base = readingsOf(ind::measureRtest(plan, m));
  const ind::RtestChip chip{1, 7, 2, 0.020};
  const auto chipped = readingsOf(ind::measureRtest(plan, m, chip));
  ASSERT_EQ(base.size(), chipped.size());
  int moved = 0;
  const size_t per_cycle = plan.points.size() + 2;
  for (size_t r = 0; r < base.size(); ++r)
    for (int i = 0; i < 3; ++i) {
      const double d = chipped[r].dq_w_mm[i] - base[r].dq_w_mm[i];
      const bool here = r / per_cycle == 1 && base[r].pose_id == 7 && i == 2;
      EXPECT_NEAR(d, here ? 0.020 : 0.0, 1e-12);
      moved += here;
    }
  EXPECT_EQ(moved, 1);
}

// The per-tilt truth (the table's own pose at each tilt, in the reset's convention) against
// 002 Eq. (2) to first order in closed form (docs/rtest.md's table): X0C - X0B = 10 um and
// A0C - A0B = 5 mdeg alone give dx 10 cos B, dz 10 sin B, a 5 cos B, c 5 sin B; C0B = 18 mdeg
// and Z0B = 15 um alone are invisible at tilt 0 and give the reset's pattern: rotations
// -18 (-sin B, 0, cos B) + 18 z, translations -15 (-sin B, 0, cos B) + 15 z.
TEST(IndependentRtest, PerTiltTruthHasTheFirstOrderClosedForm) {
  const ProbePlan& plan = rtestPlan();
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  LocationErrors e;
  e.kinematics = Kinematics::TableBC;
  e.setReportValue(parameterIndex(Kinematics::TableBC, "dx_CB"), 10.0);
  e.setReportValue(parameterIndex(Kinematics::TableBC, "a_CB"), 5.0);
  const ind::PerTiltTruth t = ind::perTiltTruth(plan, ind::cleanRtestMachine(e));
  ASSERT_EQ(t.tilt_deg.size(), 5u);
  // first order: the X-Y-Z angles of a 5 mdeg turn differ from its rotation vector by ~1e-4 mdeg
  for (size_t i = 0; i < t.tilt_deg.size(); ++i) {
    const double B = t.tilt_deg[i] * kDeg;
    const std::array<double, 6> want{10 * std::cos(B), 0, 10 * std::sin(B), 5 * std::cos(B), 0, 5 * std::sin(B)};
    for (size_t p = 0; p < 6; ++p) EXPECT_NEAR(t.value[i][p], want[p], 1e-3) << "tilt " << t.tilt_deg[i] << " p " << p;
  }
  LocationErrors g;
  g.kinematics = Kinematics::TableBC;
  g.setReportValue(parameterIndex(Kinematics::TableBC, "c_BY"), 18.0);
  g.setReportValue(parameterIndex(Kinematics::TableBC, "dz_BY"), 15.0);
  const ind::PerTiltTruth h = ind::perTiltTruth(plan, ind::cleanRtestMachine(g));
  for (size_t i = 0; i < h.tilt_deg.size(); ++i) {
    const double B = h.tilt_deg[i] * kDeg;
    const std::array<double, 6> want{15 * std::sin(B), 0, 15 - 15 * std::cos(B), 18 * std::sin(B), 0, 18 - 18 * std::cos(B)};
    // first order: the rotation of 18 mdeg turns the 15 um by 3e-4 of it
    for (size_t p = 0; p < 6; ++p) EXPECT_NEAR(h.value[i][p], want[p], 1e-2) << "tilt " << h.tilt_deg[i] << " p " << p;
  }
}

// The per-tilt truth against rotacal's own identification on the generator's clean readings
// (the example's eight errors, no noise): the analysis and the truth read the same convention.
// What separates them is second order: the analysis is linear about zero, the truth's reset
// convention first order, and the errors are 10-30 um / mdeg (second order: 1e-2 um).
TEST(IndependentRtest, PerTiltTruthIsWhatTheAnalysisReportsOnACleanMachine) {
  const ProbePlan& plan = rtestPlan();
  const ind::RtestMachine m = ind::cleanRtestMachine(bcLocation());
  const RtestSeries s = ind::measureRtest(plan, m);
  RtestFitOptions o;
  o.screen = false;
  const RtestAnalysis a = analyzeRtest(plan, s.cycles, o);
  const ind::PerTiltTruth t = ind::perTiltTruth(plan, m);
  ASSERT_EQ(a.tilt_deg.size(), t.tilt_deg.size());
  constexpr double kMdeg = 180.0 / 3.14159265358979323846 * 1e3;
  double largest = 0;
  for (size_t i = 0; i < t.tilt_deg.size(); ++i) {
    EXPECT_DOUBLE_EQ(a.tilt_deg[i], t.tilt_deg[i]);
    for (int p = 0; p < kRtestParams; ++p) {
      const double est = a.cycles[0].value(p, static_cast<Eigen::Index>(i)) * (p < 3 ? 1e3 : kMdeg);
      EXPECT_NEAR(est, t.value[i][static_cast<size_t>(p)], 0.02) << "tilt " << t.tilt_deg[i] << " p " << p;
      largest = std::max(largest, std::abs(t.value[i][static_cast<size_t>(p)]));
    }
  }
  EXPECT_GT(largest, 20.0);
}

// Two machines from one seed are the same machine; another seed is another.
TEST(IndependentRtest, SeededDraws) {
  const ProbePlan& plan = rtestPlan();
  const ContributorSet c = loadContributors(kRtestContrib);
  const RtestSeries a = ind::measureRtest(plan, ind::drawRtestMachine(c, plan, {}, 5));
  const RtestSeries b = ind::measureRtest(plan, ind::drawRtestMachine(c, plan, {}, 5));
  const RtestSeries d = ind::measureRtest(plan, ind::drawRtestMachine(c, plan, {}, 6));
  EXPECT_EQ(maxReadingDiffUm(a, b), 0.0);
  EXPECT_GT(maxReadingDiffUm(a, d), 1.0);
}

}  // namespace
}  // namespace rotacal
