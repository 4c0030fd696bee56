// The independent generator (bench/independent_machine.hpp) against rotacal's own simulator and
// against the closed form of 000 Eq. (22)-(23). The generator shares no code with
// core/simulation, so agreement on a clean machine checks both readings of 000 Eq. (1), the
// set-up and the contact; the statistics check that its linear axes are the model the
// contributors file declares.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "bench/independent_machine.hpp"
#include "core/contributors.hpp"
#include "core/machine.hpp"
#include "core/simulation.hpp"
#include "cycles/cycle.hpp"
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

}  // namespace
}  // namespace rotacal
