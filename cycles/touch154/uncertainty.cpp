#include "cycles/touch154/uncertainty.hpp"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/limits.hpp"

#include "cycles/touch154/causes.hpp"
#include "cycles/touch154/closed_form.hpp"
#include "cycles/touch154/closed_form_map.hpp"
#include "cycles/touch154/identification.hpp"
#include "core/units.hpp"
#include "core/require_valid.hpp"

namespace rotacal {

std::string_view uncertaintyMethodName(UncertaintyMethod m) {
  switch (m) {
    case UncertaintyMethod::ClosedForm: return "closed_form";
    case UncertaintyMethod::ClosedFormPooled: return "closed_form_pooled";
    case UncertaintyMethod::LeastSquares: return "least_squares";
    case UncertaintyMethod::LsqPerPoint: return "lsq_per_point";
    case UncertaintyMethod::LsqRigidSetup: return "lsq_rigid_setup";
  }
  return "?";
}

UncertaintyMethod uncertaintyMethodFromName(std::string_view name) {
  for (int m = 0; m < kNumUncertaintyMethods; ++m)
    if (uncertaintyMethodName(static_cast<UncertaintyMethod>(m)) == name) return static_cast<UncertaintyMethod>(m);
  throw std::invalid_argument("unknown estimator '" + std::string(name) +
                              "' (expected closed_form, closed_form_pooled, least_squares, lsq_per_point, "
                              "lsq_rigid_setup)");
}

std::string_view uncertaintyMethodDescription(UncertaintyMethod m) {
  switch (m) {
    case UncertaintyMethod::ClosedForm:
      return "closed form, 000 Eqs. (14)-(19) corrected, Patterns 3 from poses III -> VI as in 000";
    case UncertaintyMethod::ClosedFormPooled:
      return "closed form of `analyze --method closed_form`, Patterns 3 pooled over II->V, III->VI, IV->VII";
    case UncertaintyMethod::LeastSquares:
      return "least squares over all points, form-immune, squareness of the linear axes fitted alongside";
    case UncertaintyMethod::LsqPerPoint:
      return "least squares over all points, form-immune (`analyze`'s default lsq_per_point)";
    case UncertaintyMethod::LsqRigidSetup:
      return "least squares over all points, the piece one rigid body (`analyze --method lsq_rigid_setup`; not form-immune)";
  }
  return "?";
}

bool UncertaintyOptions::validate(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (runs < 2) return fail(fmt::format("runs must be >= 2 (got {}): a standard deviation needs two runs", runs));
  if (runs > kMaxMonteCarloRuns) return fail(fmt::format("runs must be <= {} (got {})", kMaxMonteCarloRuns, runs));
  if (threads < 0 || threads > kMaxThreads) return fail(fmt::format("threads must be from 0 to {} (0: all cores)", kMaxThreads));
  if (!truth.values.allFinite()) return fail("the simulated machine's location errors must be finite");
  return true;
}

namespace {

constexpr int kStreamsPerRun = 16;
enum Stream { kRepeat = 0, kRough, kPretravel, kLinearFixed, kNodesX, kNodesY, kNodesZ, kSetup, kForm };

/// Central difference of the exact triggers with respect to one drawn value.
template <class Apply>
Eigen::VectorXd sensitivity(const ProbePlan& plan, const Truth& base, double h, Apply apply) {
  Truth tp = base, tm = base;
  apply(tp, h);
  apply(tm, -h);
  return (triggersAlong(plan, tp) - triggersAlong(plan, tm)) / (2.0 * h);
}

/// First-order map of identify(LeastSquaresPerPoint): the location-error rows of the
/// pseudo-inverse of the model's Jacobian [J_s_e, per-target offsets, extra columns] at the truth.
/// `extra` holds the trigger sensitivities of fitted nuisance parameters (e.g. squareness).
IdentificationMap leastSquaresMap(const ProbePlan& plan, const LocationErrors& truth, const Eigen::MatrixXd& J_e,
                                  const Eigen::MatrixXd& extra, Eigen::MatrixXd* range = nullptr,
                                  bool per_target = true) {
  const long n = static_cast<long>(plan.points.size());
  const auto& params = locationParameters(plan.machine.kinematics);
  std::map<int, int> target_index;
  for (const auto& p : plan.points)
    if (!target_index.count(p.target)) target_index.emplace(p.target, static_cast<int>(target_index.size()));
  const long nt = per_target ? static_cast<long>(target_index.size()) : 0;
  const long p = kNumLocationErrors + nt + extra.cols();
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(n, p);
  X.leftCols<kNumLocationErrors>() = J_e;
  // One surface offset per target point (lsq_per_point): the plane moves by d along its normal,
  // the trigger by d / (n . u) (exact for a plane).
  for (long i = 0; per_target && i < n; ++i) {
    const ProbePoint& pt = plan.points[static_cast<size_t>(i)];
    const Eigen::Vector3d n_m = T_m_w(truth, pt.pose).linear() * pt.normal_w;
    X(i, kNumLocationErrors + target_index.at(pt.target)) = 1.0 / n_m.dot(pt.approach_m);
  }
  if (extra.cols() > 0) X.rightCols(extra.cols()) = extra;
  Eigen::VectorXd scale = X.colwise().norm().transpose();
  for (long j = 0; j < p; ++j) scale[j] = scale[j] > 0 ? 1.0 / scale[j] : 1.0;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(X * scale.asDiagonal(), Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  const double tol = IdentificationOptions{}.rank_tolerance * sv[0];  // identify()'s rank test
  long rank = 0;
  for (long i = 0; i < sv.size(); ++i)
    if (sv[i] > tol) ++rank;
  if (rank < p || n < p) {
    std::set<std::string> names;
    for (long c = rank; c < svd.matrixV().cols(); ++c)
      for (int j = 0; j < kNumLocationErrors; ++j)
        if (std::abs(svd.matrixV()(j, c)) > 0.05) names.insert(std::string(params[static_cast<size_t>(j)].name));
    std::string list;
    for (const auto& s : names) list += (list.empty() ? "" : ", ") + s;
    throw std::invalid_argument(fmt::format("the plan cannot identify the location errors by least squares: {}",
                                            names.empty() ? fmt::format("rank {} of {}", rank, p)
                                                          : list + " move no trigger independently"));
  }
  if (range) *range = svd.matrixU();
  const Eigen::MatrixXd pinv =
      scale.asDiagonal() * svd.matrixV() * sv.cwiseInverse().asDiagonal() * svd.matrixU().transpose();
  return pinv.topRows<kNumLocationErrors>();
}

}  // namespace

LinearChain lineariseChain(const ProbePlan& plan, const LocationErrors& truth) {
  if (!plan.machine.artefact) throw std::invalid_argument("the plan has no artefact to simulate");
  LinearChain c;
  const long n = static_cast<long>(plan.points.size());
  c.points = static_cast<int>(n);
  Truth base;
  base.errors = truth;
  const MeasurementRun run0 = simulate(plan, base, {1});

  c.coord.resize(n, 3);
  for (long i = 0; i < n; ++i) c.coord.row(i) = run0.points[static_cast<size_t>(i)].position_m_mm.transpose();
  c.lo = c.coord.colwise().minCoeff().transpose();
  c.hi = c.coord.colwise().maxCoeff().transpose();

  // Linear-axis errors: a constant error moves every trigger by its component along the normal.
  c.dsdE.resize(n, 3);
  for (int b = 0; b < 3; ++b)
    c.dsdE.col(b) = sensitivity(plan, base, 1e-3, [b](Truth& t, double d) {
      t.linear_axis_error = [b, d](const Eigen::Vector3d&) { return Eigen::Vector3d(Eigen::Vector3d::Unit(b) * d); };
    });

  namespace fv = fixed_var;
  c.S.resize(n, fv::kCount);
  for (int k = 0; k < 6; ++k)
    c.S.col(fv::kPretravel + k) = sensitivity(plan, base, 1e-3, [k](Truth& t, double d) {
      std::array<double, 6> v{};
      v[static_cast<size_t>(k)] = d;
      t.pretravel_by_direction_um = [v](const Eigen::Vector3d& u) { return mmToUm(pretravelAlong(v, u)); };
    });
  for (int a = 0; a < 3; ++a)
    c.S.col(fv::kScale + a) = sensitivity(plan, base, 1e-5, [a](Truth& t, double d) {
      t.linear_axis_error = [a, d](const Eigen::Vector3d& x) {
        Eigen::Vector3d e = Eigen::Vector3d::Zero();
        e[a] = d * x[a];
        return e;
      };
    });
  // Squareness: S_xy (X error along Y), S_xz (X error along Z), S_yz (Y error along Z).
  const int sq_dir[3] = {0, 0, 1}, sq_axis[3] = {1, 2, 2};
  for (int q = 0; q < 3; ++q) {
    const int dir = sq_dir[q], ax = sq_axis[q];
    c.S.col(fv::kSquareness + q) = sensitivity(plan, base, 1e-5, [dir, ax](Truth& t, double d) {
      t.linear_axis_error = [dir, ax, d](const Eigen::Vector3d& x) {
        Eigen::Vector3d e = Eigen::Vector3d::Zero();
        e[dir] = d * x[ax];
        return e;
      };
    });
  }
  for (int k = 0; k < 3; ++k) {
    c.S.col(fv::kSetupT + k) =
        sensitivity(plan, base, 1e-3, [k](Truth& t, double d) { t.artefact.setup.translation_mm[k] = d; });
    c.S.col(fv::kSetupR + k) =
        sensitivity(plan, base, 1e-5, [k](Truth& t, double d) { t.artefact.setup.rotation_rad[k] = d; });
  }
  for (int f = 0; f < 5; ++f) {
    const size_t fi = static_cast<size_t>(f);
    c.S.col(fv::kForm + 3 * f) = sensitivity(plan, base, 1e-3, [fi](Truth& t, double d) { t.artefact.form[fi].offset_mm = d; });
    c.S.col(fv::kForm + 3 * f + 1) =
        sensitivity(plan, base, 1e-5, [fi](Truth& t, double d) { t.artefact.form[fi].tilt_u_rad = d; });
    c.S.col(fv::kForm + 3 * f + 2) =
        sensitivity(plan, base, 1e-5, [fi](Truth& t, double d) { t.artefact.form[fi].tilt_v_rad = d; });
  }

  // Least squares to first order: lsq_per_point, and with the squareness columns (the model of
  // the linear_axis_squareness extension: E = (S_xy y + S_xz z, S_yz z, 0)).
  const Eigen::MatrixXd J_e = J_s_e(plan, truth);
  const auto ls = static_cast<size_t>(UncertaintyMethod::LeastSquares);
  const auto lp = static_cast<size_t>(UncertaintyMethod::LsqPerPoint);
  c.G[lp] = leastSquaresMap(plan, truth, J_e, Eigen::MatrixXd(n, 0), &c.range_lp);  // throws: nothing to do without it
  c.has[lp] = true;
  c.G[ls].setZero(kNumLocationErrors, n);
  try {
    c.G[ls] = leastSquaresMap(plan, truth, J_e, c.S.middleCols<3>(fv::kSquareness));
    c.has[ls] = true;
  } catch (const std::invalid_argument& e) {
    c.least_squares_why = std::string(e.what()) + " when the squareness of the linear axes is fitted too";
  }
  // lsq_rigid_setup: the piece's six set-up parameters instead of one offset per target (any
  // parametrisation of a rigid motion spans the same columns to first order).
  const auto rs = static_cast<size_t>(UncertaintyMethod::LsqRigidSetup);
  c.G[rs].setZero(kNumLocationErrors, n);
  try {
    Eigen::MatrixXd setup(n, 6);
    setup << c.S.middleCols<3>(fv::kSetupT), c.S.middleCols<3>(fv::kSetupR);
    c.G[rs] = leastSquaresMap(plan, truth, J_e, setup, &c.range_rs, false);
    c.has[rs] = true;
  } catch (const std::invalid_argument& e) {
    c.rigid_setup_why = std::string(e.what()) + " with the piece as one rigid body";
  }
  c.bias[lp].setZero();  // the model is the exact simulator: with no contributor, no deviation
  c.bias[ls].setZero();
  c.bias[rs].setZero();

  // Closed forms: linear in the measured coordinates (cycles/touch154/closed_form_map.hpp).
  const auto cf = static_cast<size_t>(UncertaintyMethod::ClosedForm);
  const auto cp = static_cast<size_t>(UncertaintyMethod::ClosedFormPooled);
  Eigen::VectorXd s0(n);
  for (long i = 0; i < n; ++i) s0[i] = alongApproach(plan.points[static_cast<size_t>(i)], run0.points[static_cast<size_t>(i)]);
  for (size_t m : {cf, cp}) {
    c.G[m].setZero(kNumLocationErrors, n);
    c.bias[m].setZero();
  }
  try {
    c.G[cf] = closedFormMap(plan, tiltPairs000());
    c.G[cp] = closedFormMap(plan, tiltPairsPooled());
    // With no contributor the closed forms still miss by their second-order terms (zero at zero errors).
    c.bias[cf] = c.G[cf] * s0 - truth.values;
    c.bias[cp] = solvePatterns(touch154Patterns(plan, run0)).values - truth.values;
    c.has[cf] = c.has[cp] = true;
  } catch (const std::invalid_argument& e) {
    c.closed_form_why = e.what();
  }
  for (size_t m = 0; m < kNumUncertaintyMethods; ++m) c.GS[m] = c.G[m] * c.S;
  return c;
}

DrawModel drawModel(const ContributorSet& cs) {
  DrawModel d;
  d.linear = cs.linearAxisModel();
  for (const auto& c : cs.items) {
    d.present.push_back(c.info);
    switch (c.info->kind) {
      case ContributorKind::ProbeRepeatability: d.repeat_mm = c.u[0]; break;
      case ContributorKind::ProbePretravel: d.pretravel_mm = c.u[0]; break;
      case ContributorKind::SurfaceRoughness: d.rough_mm = c.u[0]; break;
      case ContributorKind::SetupPosition: d.setup_mm = c.u; break;
      case ContributorKind::SetupOrientation: d.setup_rad = c.u; break;
      case ContributorKind::FormError:
        d.form_offset_mm = c.u[0];
        d.form_tilt_rad = c.u[1];
        break;
      default: break;  // linear axes: in d.linear
    }
  }
  return d;
}

void drawRun(const DrawModel& m, const LinearChain& chain, std::uint64_t seed, int run, RunDraw* out) {
  const std::uint64_t base = static_cast<std::uint64_t>(run) * kStreamsPerRun;
  const long n = chain.points;
  auto perTouch = [&](Eigen::VectorXd& v, double u, Stream s) {
    v.resize(n);
    if (u <= 0) {
      v.setZero();
      return;
    }
    Rng r(seed, base + s);
    for (long i = 0; i < n; ++i) v[i] = u * r.normal();
  };
  perTouch(out->repeat_mm, m.repeat_mm, kRepeat);
  perTouch(out->rough_mm, m.rough_mm, kRough);
  {
    Rng r(seed, base + kPretravel);
    for (auto& v : out->pretravel_mm) v = m.pretravel_mm * r.normal();
  }
  {
    Rng rf(seed, base + kLinearFixed), rx(seed, base + kNodesX), ry(seed, base + kNodesY), rz(seed, base + kNodesZ);
    drawLinearAxisErrors(m.linear, chain.lo, chain.hi, rf, {&rx, &ry, &rz}, &out->linear);
  }
  {
    Rng r(seed, base + kSetup);
    for (int k = 0; k < 3; ++k) out->setup.translation_mm[k] = m.setup_mm[k] * r.normal();
    for (int k = 0; k < 3; ++k) out->setup.rotation_rad[k] = m.setup_rad[k] * r.normal();
  }
  {
    Rng r(seed, base + kForm);
    for (auto& f : out->form) {
      f.offset_mm = m.form_offset_mm * r.normal();
      f.tilt_u_rad = m.form_tilt_rad * r.normal();
      f.tilt_v_rad = m.form_tilt_rad * r.normal();
    }
  }
}

RunDraw onlyContributor(const RunDraw& d, const ContributorInfo& c) {
  RunDraw o;
  o.repeat_mm = Eigen::VectorXd::Zero(d.repeat_mm.size());
  o.rough_mm = Eigen::VectorXd::Zero(d.rough_mm.size());
  for (int a = 0; a < 3; ++a) {  // keep the node grids, zero the values
    const size_t ai = static_cast<size_t>(a);
    o.linear.nodes[ai].spacing_mm = d.linear.nodes[ai].spacing_mm;
    o.linear.nodes[ai].first = d.linear.nodes[ai].first;
    for (int b = 0; b < 3; ++b)
      o.linear.nodes[ai].mm[static_cast<size_t>(b)].assign(d.linear.nodes[ai].mm[static_cast<size_t>(b)].size(), 0.0);
  }
  switch (c.kind) {
    case ContributorKind::ProbeRepeatability: o.repeat_mm = d.repeat_mm; break;
    case ContributorKind::SurfaceRoughness: o.rough_mm = d.rough_mm; break;
    case ContributorKind::ProbePretravel: o.pretravel_mm = d.pretravel_mm; break;
    case ContributorKind::LinearScale: o.linear.scale[c.axis] = d.linear.scale[c.axis]; break;
    case ContributorKind::LinearRandom: {
      const size_t a = static_cast<size_t>(c.axis), b = static_cast<size_t>(c.direction);
      o.linear.nodes[a].mm[b] = d.linear.nodes[a].mm[b];
      break;
    }
    case ContributorKind::Squareness:
      if (c.id == "S_xy") o.linear.S_xy = d.linear.S_xy;
      else if (c.id == "S_xz") o.linear.S_xz = d.linear.S_xz;
      else o.linear.S_yz = d.linear.S_yz;
      break;
    case ContributorKind::SetupPosition: o.setup.translation_mm = d.setup.translation_mm; break;
    case ContributorKind::SetupOrientation: o.setup.rotation_rad = d.setup.rotation_rad; break;
    case ContributorKind::FormError: o.form = d.form; break;
    default: break;  // the R-test's contributors do not act on a touch cycle
  }
  return o;
}

namespace {

/// The drawn values with fixed trigger sensitivities, in the order of LinearChain::S.
Eigen::Matrix<double, fixed_var::kCount, 1> fixedValues(const RunDraw& d) {
  namespace fv = fixed_var;
  Eigen::Matrix<double, fv::kCount, 1> v;
  for (int k = 0; k < 6; ++k) v[fv::kPretravel + k] = d.pretravel_mm[static_cast<size_t>(k)];
  v.segment<3>(fv::kScale) = d.linear.scale;
  v[fv::kSquareness] = d.linear.S_xy;
  v[fv::kSquareness + 1] = d.linear.S_xz;
  v[fv::kSquareness + 2] = d.linear.S_yz;
  v.segment<3>(fv::kSetupT) = d.setup.translation_mm;
  v.segment<3>(fv::kSetupR) = d.setup.rotation_rad;
  for (int f = 0; f < 5; ++f) {
    const FaceForm& ff = d.form[static_cast<size_t>(f)];
    v[fv::kForm + 3 * f] = ff.offset_mm;
    v[fv::kForm + 3 * f + 1] = ff.tilt_u_rad;
    v[fv::kForm + 3 * f + 2] = ff.tilt_v_rad;
  }
  return v;
}

/// Scratch space of one thread (no allocation per run).
struct Workspace {
  RunDraw draw;
  Eigen::VectorXd ds;
  Eigen::Matrix<int, Eigen::Dynamic, 3> node;
  Eigen::Matrix<double, Eigen::Dynamic, 3> weight;
};

/// Trigger change from the random part of axis a's error in direction b.
void randomTriggers(const LinearChain& c, const RunDraw& d, const Workspace& w, int a, int b, Eigen::VectorXd* ds) {
  const auto& v = d.linear.nodes[static_cast<size_t>(a)].mm[static_cast<size_t>(b)];
  for (long i = 0; i < c.points; ++i) {
    const int k = w.node(i, a);
    const double t = w.weight(i, a);
    (*ds)[i] += c.dsdE(i, b) * ((1.0 - t) * v[static_cast<size_t>(k)] + t * v[static_cast<size_t>(k + 1)]);
  }
}

/// The same for the three directions of axis a at once (the combined run's hot loop).
void allRandomTriggers(const LinearChain& c, const RunDraw& d, const Workspace& w, int a, Eigen::VectorXd* ds) {
  const auto& nodes = d.linear.nodes[static_cast<size_t>(a)];
  const double* v0 = nodes.mm[0].data();
  const double* v1 = nodes.mm[1].data();
  const double* v2 = nodes.mm[2].data();
  for (long i = 0; i < c.points; ++i) {
    const int k = w.node(i, a);
    const double t = w.weight(i, a);
    (*ds)[i] += c.dsdE(i, 0) * (v0[k] + t * (v0[k + 1] - v0[k])) + c.dsdE(i, 1) * (v1[k] + t * (v1[k + 1] - v1[k])) +
                c.dsdE(i, 2) * (v2[k] + t * (v2[k + 1] - v2[k]));
  }
}

void locateNodes(const LinearChain& c, const RunDraw& d, Workspace* w) {
  w->node.resize(c.points, 3);
  w->weight.resize(c.points, 3);
  for (int a = 0; a < 3; ++a) {
    const AxisNodes& nodes = d.linear.nodes[static_cast<size_t>(a)];
    if (nodes.spacing_mm <= 0) continue;
    for (long i = 0; i < c.points; ++i) {
      int k;
      double t;
      nodes.locate(c.coord(i, a), &k, &t);
      w->node(i, a) = k;
      w->weight(i, a) = t;
    }
  }
}

bool hasRandom(const RunDraw& d, int a) { return d.linear.nodes[static_cast<size_t>(a)].spacing_mm > 0; }

/// Linearised deviations of the active estimators: all contributors into `combined`, and, when
/// `per` is given, each contributor of `present` (catalog order) alone into per[j].
void linearisedRun(const LinearChain& c, const MethodMask& active, const std::vector<const ContributorInfo*>& present,
                   Workspace* w, std::array<ErrorVector, kNumUncertaintyMethods>* combined,
                   std::vector<std::array<ErrorVector, kNumUncertaintyMethods>>* per) {
  const RunDraw& d = w->draw;
  const auto v = fixedValues(d);
  locateNodes(c, d, w);
  for (size_t m = 0; m < kNumUncertaintyMethods; ++m) (*combined)[m] = c.bias[m];
  if (!per) {
    w->ds = d.repeat_mm - d.rough_mm;
    for (int a = 0; a < 3; ++a)
      if (hasRandom(d, a)) allRandomTriggers(c, d, *w, a, &w->ds);
    for (size_t m = 0; m < kNumUncertaintyMethods; ++m) {
      if (!active[m]) continue;
      (*combined)[m].noalias() += c.G[m] * w->ds;
      (*combined)[m].noalias() += c.GS[m] * v;
    }
    return;
  }
  namespace fv = fixed_var;
  per->resize(present.size());
  for (size_t j = 0; j < present.size(); ++j) {
    const ContributorInfo& ci = *present[j];
    auto& e = (*per)[j];
    auto fixedCols = [&](int first, int count) {
      for (size_t m = 0; m < kNumUncertaintyMethods; ++m)
        if (active[m]) e[m].noalias() = c.GS[m].middleCols(first, count) * v.segment(first, count);
    };
    auto perTrigger = [&](const Eigen::VectorXd& ds) {
      for (size_t m = 0; m < kNumUncertaintyMethods; ++m)
        if (active[m]) e[m].noalias() = c.G[m] * ds;
    };
    for (auto& x : e) x.setZero();
    switch (ci.kind) {
      case ContributorKind::ProbeRepeatability: perTrigger(d.repeat_mm); break;
      case ContributorKind::SurfaceRoughness: perTrigger(-d.rough_mm); break;
      case ContributorKind::ProbePretravel: fixedCols(fv::kPretravel, 6); break;
      case ContributorKind::LinearScale: fixedCols(fv::kScale + ci.axis, 1); break;
      case ContributorKind::Squareness:
        fixedCols(fv::kSquareness + (ci.id == "S_xy" ? 0 : ci.id == "S_xz" ? 1 : 2), 1);
        break;
      case ContributorKind::SetupPosition: fixedCols(fv::kSetupT, 3); break;
      case ContributorKind::SetupOrientation: fixedCols(fv::kSetupR, 3); break;
      case ContributorKind::FormError: fixedCols(fv::kForm, 15); break;
      case ContributorKind::LinearRandom:
        w->ds.setZero(c.points);
        if (hasRandom(d, ci.axis)) randomTriggers(c, d, *w, ci.axis, ci.direction, &w->ds);
        perTrigger(w->ds);
        break;
      default: break;  // the R-test's contributors do not act on a touch cycle
    }
    for (size_t m = 0; m < kNumUncertaintyMethods; ++m) (*combined)[m] += e[m];
  }
}

}  // namespace

Eigen::VectorXd linearisedTriggerChange(const LinearChain& chain, const RunDraw& draw) {
  Workspace w;
  locateNodes(chain, draw, &w);
  Eigen::VectorXd ds = draw.repeat_mm - draw.rough_mm;
  for (int a = 0; a < 3; ++a)
    if (hasRandom(draw, a)) allRandomTriggers(chain, draw, w, a, &ds);
  ds.noalias() += chain.S * fixedValues(draw);
  return ds;
}

std::array<ErrorVector, kNumUncertaintyMethods> linearisedDeviation(const LinearChain& chain, const MethodMask& active,
                                                                      const RunDraw& draw) {
  Workspace w;
  w.draw = draw;
  std::array<ErrorVector, kNumUncertaintyMethods> out;
  linearisedRun(chain, active, {}, &w, &out, nullptr);
  for (size_t m = 0; m < kNumUncertaintyMethods; ++m)
    if (!active[m]) out[m].setZero();
  return out;
}

Truth truthOfDraw(const LocationErrors& errors, const RunDraw& d) {
  Truth t;
  t.errors = errors;
  t.artefact.setup = d.setup;
  t.artefact.form = d.form;
  bool any_linear = (d.linear.scale.array() != 0.0).any() || d.linear.S_xy != 0 || d.linear.S_xz != 0 || d.linear.S_yz != 0;
  for (const auto& nodes : d.linear.nodes)
    for (const auto& v : nodes.mm)
      for (double x : v) any_linear = any_linear || x != 0;
  if (any_linear) t.linear_axis_error = d.linear.asFunction();
  if (std::any_of(d.pretravel_mm.begin(), d.pretravel_mm.end(), [](double x) { return x != 0; }))
    t.pretravel_by_direction_um = [v = d.pretravel_mm](const Eigen::Vector3d& u) { return mmToUm(pretravelAlong(v, u)); };
  return t;
}

std::array<ErrorVector, kNumUncertaintyMethods> exactDeviation(const ProbePlan& plan, const LinearChain& chain,
                                                                 const MethodMask& active, const LocationErrors& truth,
                                                                 const RunDraw& d, bool* ok) {
  MeasurementRun run = simulate(plan, truthOfDraw(truth, d), {1});
  // Per-touch effects along the approach: repeatability, and the surface height under the ball
  // (a surface raised by h along its outward normal triggers h earlier: n . u = -1).
  const long n = static_cast<long>(plan.points.size());
  Eigen::VectorXd s(n);
  for (long i = 0; i < n; ++i) {
    const size_t si = static_cast<size_t>(i);
    run.points[si].position_m_mm += (d.repeat_mm[i] - d.rough_mm[i]) * plan.points[si].approach_m;
    s[i] = alongApproach(plan.points[si], run.points[si]);
  }
  std::array<ErrorVector, kNumUncertaintyMethods> out;
  for (auto& x : out) x.setZero();
  if (ok) *ok = true;
  const auto cf = static_cast<size_t>(UncertaintyMethod::ClosedForm);
  const auto cp = static_cast<size_t>(UncertaintyMethod::ClosedFormPooled);
  // 000's closed form is exactly this linear map of the triggers (cycles/touch154/closed_form_map.hpp).
  if (active[cf]) out[cf] = chain.G[cf] * s - truth.values;
  if (active[cp]) out[cp] = solvePatterns(touch154Patterns(plan, run)).values - truth.values;
  for (auto m : {UncertaintyMethod::LeastSquares, UncertaintyMethod::LsqPerPoint, UncertaintyMethod::LsqRigidSetup}) {
    const auto mi = static_cast<size_t>(m);
    if (!active[mi]) continue;
    IdentificationOptions o;
    o.method = m == UncertaintyMethod::LsqRigidSetup ? Method::LeastSquaresRigidSetup : Method::LeastSquaresPerPoint;
    if (m == UncertaintyMethod::LeastSquares) o.extensions = {linearAxisSquareness()};
    const IdentificationResult r = identify(plan, {run}, o);
    if (r.summary.termination == Termination::RankDeficient || r.summary.termination == Termination::InvalidInput)
      throw std::invalid_argument("least squares failed in the Monte Carlo: " + r.summary.message);
    if (ok && r.summary.termination != Termination::Converged) *ok = false;
    out[mi] = r.estimate.values - truth.values;
  }
  return out;
}

namespace {

/// Welford accumulators for one block of runs: rows = combined, then each contributor.
struct Block {
  int count = 0;
  int failed = 0;
  std::vector<std::array<ErrorVector, kNumUncertaintyMethods>> mean, m2;

  void init(size_t rows) {
    std::array<ErrorVector, kNumUncertaintyMethods> zero;
    for (auto& z : zero) z.setZero();
    mean.assign(rows, zero);
    m2.assign(rows, zero);
  }
  void add(size_t row, const std::array<ErrorVector, kNumUncertaintyMethods>& x, int n) {
    for (size_t m = 0; m < kNumUncertaintyMethods; ++m) {
      const ErrorVector delta = x[m] - mean[row][m];
      mean[row][m] += delta / n;
      m2[row][m] += delta.cwiseProduct(x[m] - mean[row][m]);
    }
  }
  /// Chan et al.'s pairwise combination, in block order (deterministic).
  void merge(const Block& b) {
    if (b.count == 0) return;
    const double na = count, nb = b.count, n = na + nb;
    for (size_t r = 0; r < mean.size(); ++r)
      for (size_t m = 0; m < kNumUncertaintyMethods; ++m) {
        const ErrorVector delta = b.mean[r][m] - mean[r][m];
        mean[r][m] += delta * (nb / n);
        m2[r][m] += b.m2[r][m] + delta.cwiseAbs2() * (na * nb / n);
      }
    count += b.count;
    failed += b.failed;
  }
};

constexpr int kBlockRuns = 32;

}  // namespace

UncertaintySummary runUncertainty(const ProbePlan& plan, const ContributorSet& contributors,
                                  const UncertaintyOptions& options) {
  requireValid(options, "uncertainty options");
  const auto t0 = std::chrono::steady_clock::now();
  const LinearChain chain = lineariseChain(plan, options.truth);
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  UncertaintySummary s = runUncertainty(plan, chain, contributors, options);
  s.setup_seconds = setup;
  return s;
}

UncertaintySummary runUncertainty(const ProbePlan& plan, const LinearChain& chain, const ContributorSet& contributors,
                                  const UncertaintyOptions& options) {
  requireValid(options, "uncertainty options");
  requireValid(contributors, "contributors");
  if (chain.points != static_cast<int>(plan.points.size()))
    throw std::invalid_argument("the linear chain was built for another plan");
  const DrawModel model = drawModel(contributors);
  MethodMask active{};
  for (int m = 0; m < kNumUncertaintyMethods; ++m) active[static_cast<size_t>(m)] = options.methods.empty();
  for (auto m : options.methods) active[static_cast<size_t>(m)] = true;
  for (size_t m = 0; m < kNumUncertaintyMethods; ++m) active[m] = active[m] && chain.has[m];
  if (std::none_of(active.begin(), active.end(), [](bool b) { return b; }))
    throw std::invalid_argument("none of the requested estimators applies to this plan" +
                                (chain.closed_form_why.empty() ? std::string() : ": " + chain.closed_form_why));
  const size_t rows = 1 + (options.combined_only ? 0 : model.present.size());
  const int nblocks = (options.runs + kBlockRuns - 1) / kBlockRuns;
  std::vector<Block> blocks(static_cast<size_t>(nblocks));
  int threads = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(1, std::min(threads, nblocks));

  std::atomic<int> next{0};
  std::mutex progress_mutex;
  int done = 0;
  std::vector<std::exception_ptr> errors(static_cast<size_t>(threads));
  auto worker = [&](int tid) {
    try {
      Workspace w;
      std::array<ErrorVector, kNumUncertaintyMethods> combined;
      std::vector<std::array<ErrorVector, kNumUncertaintyMethods>> per;
      for (int b = next++; b < nblocks; b = next++) {
        Block& blk = blocks[static_cast<size_t>(b)];
        blk.init(rows);
        const int first = b * kBlockRuns, last = std::min(options.runs, first + kBlockRuns);
        for (int r = first; r < last; ++r) {
          drawRun(model, chain, options.seed, r, &w.draw);
          ++blk.count;
          if (!options.exact) {
            linearisedRun(chain, active, model.present, &w, &combined, options.combined_only ? nullptr : &per);
            blk.add(0, combined, blk.count);
            if (!options.combined_only)
              for (size_t j = 0; j < per.size(); ++j) blk.add(j + 1, per[j], blk.count);
          } else {
            bool ok = true;
            blk.add(0, exactDeviation(plan, chain, active, options.truth, w.draw, &ok), blk.count);
            if (!ok) ++blk.failed;
            if (!options.combined_only)
              for (size_t j = 0; j < model.present.size(); ++j) {
                const RunDraw alone = onlyContributor(w.draw, *model.present[j]);
                blk.add(j + 1, exactDeviation(plan, chain, active, options.truth, alone, &ok), blk.count);
                if (!ok) ++blk.failed;
              }
          }
        }
        if (options.progress) {
          std::lock_guard<std::mutex> lock(progress_mutex);
          done += last - first;
          options.progress(done, options.runs);
        }
      }
    } catch (...) {
      errors[static_cast<size_t>(tid)] = std::current_exception();
      next = nblocks;  // stop the others
    }
  };
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker, t);
  worker(0);
  for (auto& th : pool) th.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  Block total;
  total.init(rows);
  for (const auto& b : blocks) total.merge(b);

  UncertaintySummary s;
  s.kinematics = plan.machine.kinematics;
  s.runs = options.runs;
  s.seed = options.seed;
  s.exact = options.exact;
  s.threads = threads;
  s.points = static_cast<int>(plan.points.size());
  s.poses = static_cast<int>(plan.poses.size());
  s.machine_time_s = plan.points.empty() ? 0.0 : plan.points.back().t_s;
  s.run_seconds = secs;
  s.failed = total.failed;
  s.closed_form_why = chain.closed_form_why;
  s.least_squares_why = chain.least_squares_why;
  const double dof = static_cast<double>(total.count - 1);
  auto stat = [&](size_t row, size_t m) {
    UncertaintyStat st;
    st.mean = total.mean[row][m];
    st.u = (total.m2[row][m] / dof).cwiseSqrt();
    return st;
  };
  for (int m = 0; m < kNumUncertaintyMethods; ++m) {
    const auto method = static_cast<UncertaintyMethod>(m);
    if (!active[static_cast<size_t>(m)]) continue;
    MethodUncertainty mu;
    mu.method = method;
    mu.description = std::string(uncertaintyMethodDescription(method));
    mu.combined = stat(0, static_cast<size_t>(m));
    if (!options.combined_only)
      for (size_t j = 0; j < model.present.size(); ++j)
        mu.contributors.emplace_back(std::string(model.present[j]->id), stat(j + 1, static_cast<size_t>(m)));
    s.methods.push_back(mu);
  }
  return s;
}

namespace {

double toReport(ParamKind k, double v) { return k == ParamKind::Length ? mmToUm(v) : radToMdeg(v); }

Json statJson(Kinematics kin, const UncertaintyStat& st) {
  Json j = Json::object();
  const auto& params = locationParameters(kin);
  for (size_t i = 0; i < params.size(); ++i) {
    const ParamKind k = params[i].kind;
    j[std::string(params[i].name)] = {{"u", toReport(k, st.u[static_cast<long>(i)])},
                                      {"unit", std::string(reportUnit(k))},
                                      {"mean", toReport(k, st.mean[static_cast<long>(i)])}};
  }
  return j;
}

}  // namespace

Json uncertaintyToJson(const UncertaintySummary& s, const ContributorSet& cs, const std::string& plan_file) {
  const Kinematics kin = s.kinematics;
  Json j;
  j["format"] = "rotacal-uncertainty/1";
  j["runs"] = s.runs;
  j["seed"] = s.seed;
  j["k"] = 1;
  j["evaluation"] = s.exact ? "exact" : "linearised";
  j["sampling_relative_u"] = 1.0 / std::sqrt(2.0 * s.runs);
  j["plan"] = {{"file", plan_file}, {"points", s.points}, {"poses", s.poses}, {"machine_time_s", s.machine_time_s}};
  j["contributors_file"] = cs.file;
  j["threads"] = s.threads;
  j["seconds"] = {{"setup", s.setup_seconds}, {"runs", s.run_seconds}};
  if (s.exact) j["failed_identifications"] = s.failed;
  Json methods = Json::object();
  for (const auto& m : s.methods) {
    Json mj;
    mj["estimator"] = m.description;
    mj["combined"] = statJson(kin, m.combined);
    if (!m.contributors.empty()) {
      Json c = Json::object();
      for (const auto& [id, st] : m.contributors) c[id] = statJson(kin, st);
      mj["contributors"] = c;
    }
    methods[std::string(uncertaintyMethodName(m.method))] = mj;
  }
  j["methods"] = methods;
  if (!s.closed_form_why.empty()) j["closed_form_not_applicable"] = s.closed_form_why;
  if (!s.least_squares_why.empty()) j["least_squares_not_applicable"] = s.least_squares_why;
  if (cs.reference) {
    Json r;
    r["source"] = cs.reference->source;
    Json c = Json::object();
    for (const auto& [p, u] : cs.reference->combined) {
      const int i = parameterIndex(kin, p);
      c[p] = {{"u", u}, {"unit", std::string(reportUnit(locationParameters(kin)[static_cast<size_t>(i)].kind))}};
    }
    r["combined"] = c;
    j["reference"] = r;
  }
  return j;
}

std::string uncertaintyText(const UncertaintySummary& s, const ContributorSet& cs) {
  const Kinematics kin = s.kinematics;
  const auto& params = locationParameters(kin);
  std::string t;
  t += fmt::format("uncertainty (k = 1) of the location errors: {} runs, seed {}, {} evaluation, {} thread(s)\n",
                   s.runs, s.seed, s.exact ? "exact" : "linearised", s.threads);
  t += fmt::format("plan: {} points in {} poses, {:.1f} min of machine time; sampling uncertainty of each u: {:.1f} %\n",
                   s.points, s.poses, s.machine_time_s / 60.0, 100.0 / std::sqrt(2.0 * s.runs));
  if (!s.closed_form_why.empty()) t += "closed forms not applicable to this plan: " + s.closed_form_why + "\n";
  if (!s.least_squares_why.empty()) t += "least_squares not applicable: " + s.least_squares_why + "\n";
  auto header = [&](const std::string& first) {
    std::string h = fmt::format("{:<20}", first);
    for (const auto& p : params) h += fmt::format("{:>8}", p.name);
    return h + "\n";
  };
  auto units = [&]() {
    std::string h = fmt::format("{:<20}", "");
    for (const auto& p : params) h += fmt::format("{:>8}", reportUnit(p.kind));
    return h + "\n";
  };
  auto row = [&](const std::string& name, const ErrorVector& u) {
    std::string r = fmt::format("{:<20}", name);
    for (size_t i = 0; i < params.size(); ++i) r += fmt::format("{:>8.2f}", toReport(params[i].kind, u[static_cast<long>(i)]));
    return r + "\n";
  };
  for (const auto& m : s.methods) {
    t += fmt::format("\n{}: {}\n", uncertaintyMethodName(m.method), m.description);
    t += header("contributor") + units();
    for (const auto& [id, st] : m.contributors) t += row(id, st.u);
    t += row("combined", m.combined.u);
    if (cs.reference && !cs.reference->combined.empty()) {
      std::string r = fmt::format("{:<20}", "reference");
      for (const auto& p : params) {
        const auto it = cs.reference->combined.find(std::string(p.name));
        r += it == cs.reference->combined.end() ? fmt::format("{:>8}", "-") : fmt::format("{:>8.2f}", it->second);
      }
      t += r + "\n";
    }
  }
  if (cs.reference && !cs.reference->contributors.empty()) {
    t += fmt::format("\nper-contributor entries of the reference ({}):\n", cs.reference->source);
    t += fmt::format("{:<20}{:>8}{:>10}", "contributor", "param", "paper");
    for (const auto& m : s.methods) t += fmt::format("{:>20}", uncertaintyMethodName(m.method));
    t += "\n";
    for (const auto& info : contributorCatalog()) {
      const auto found = cs.reference->contributors.find(std::string(info.id));
      if (found == cs.reference->contributors.end()) continue;
      const std::string id(info.id);
      for (const auto& [p, u] : found->second) {
        const int i = parameterIndex(kin, p);
        t += fmt::format("{:<20}{:>8}{:>10.2f}", id, p, u);
        for (const auto& m : s.methods) {
          double v = NAN;
          for (const auto& [cid, st] : m.contributors)
            if (cid == id) v = toReport(params[static_cast<size_t>(i)].kind, st.u[i]);
          t += std::isnan(v) ? fmt::format("{:>20}", "-") : fmt::format("{:>20.2f}", v);
        }
        t += "\n";
      }
    }
  }
  if (cs.reference && !cs.reference->combined.empty()) {
    t += fmt::format("\ncombined, side by side with the reference ({}):\n", cs.reference->source);
    t += fmt::format("{:<8}{:>6}{:>10}", "param", "unit", "paper");
    for (const auto& m : s.methods) t += fmt::format("{:>20}{:>7}", uncertaintyMethodName(m.method), "ratio");
    t += "\n";
    for (size_t i = 0; i < params.size(); ++i) {
      const auto it = cs.reference->combined.find(std::string(params[i].name));
      if (it == cs.reference->combined.end()) continue;
      t += fmt::format("{:<8}{:>6}{:>10.2f}", params[i].name, reportUnit(params[i].kind), it->second);
      for (const auto& m : s.methods) {
        const double v = toReport(params[i].kind, m.combined.u[static_cast<long>(i)]);
        t += fmt::format("{:>20.2f}{:>7.2f}", v, v / it->second);
      }
      t += "\n";
    }
  }
  if (s.exact && s.failed > 0) t += fmt::format("\nwarning: {} least-squares identifications did not converge\n", s.failed);
  return t;
}

Eigen::MatrixXd triggerCovariance(const LinearChain& c, const ContributorSet& cs) {
  namespace fv = fixed_var;
  const DrawModel m = drawModel(cs);
  const long n = c.points;
  Eigen::Matrix<double, fv::kCount, 1> var = Eigen::Matrix<double, fv::kCount, 1>::Zero();
  for (int k = 0; k < 6; ++k) var[fv::kPretravel + k] = m.pretravel_mm * m.pretravel_mm;
  var.segment<3>(fv::kScale) = m.linear.u_scale.cwiseAbs2();
  var[fv::kSquareness] = m.linear.u_S_xy * m.linear.u_S_xy;
  var[fv::kSquareness + 1] = m.linear.u_S_xz * m.linear.u_S_xz;
  var[fv::kSquareness + 2] = m.linear.u_S_yz * m.linear.u_S_yz;
  var.segment<3>(fv::kSetupT) = m.setup_mm.cwiseAbs2();
  var.segment<3>(fv::kSetupR) = m.setup_rad.cwiseAbs2();
  for (int f = 0; f < 5; ++f) {
    var[fv::kForm + 3 * f] = m.form_offset_mm * m.form_offset_mm;
    var[fv::kForm + 3 * f + 1] = var[fv::kForm + 3 * f + 2] = m.form_tilt_rad * m.form_tilt_rad;
  }
  Eigen::MatrixXd C = c.S * var.asDiagonal() * c.S.transpose();
  C.diagonal().array() += m.repeat_mm * m.repeat_mm + m.rough_mm * m.rough_mm;
  for (int a = 0; a < 3; ++a) {
    if (m.linear.u_rand.col(a).maxCoeff() <= 0) continue;
    // Kernel over the distinct coordinates of this axis (points share few of them).
    std::vector<double> xs;
    std::vector<int> idx(static_cast<size_t>(n));
    for (long i = 0; i < n; ++i) {
      const double x = c.coord(i, a);
      auto it = std::find_if(xs.begin(), xs.end(), [x](double v) { return std::abs(v - x) < 1e-9; });
      if (it == xs.end()) {
        xs.push_back(x);
        idx[static_cast<size_t>(i)] = static_cast<int>(xs.size() - 1);
      } else {
        idx[static_cast<size_t>(i)] = static_cast<int>(it - xs.begin());
      }
    }
    const long nx = static_cast<long>(xs.size());
    Eigen::MatrixXd K(nx, nx);
    for (long i = 0; i < nx; ++i)
      for (long j = i; j < nx; ++j)
        K(i, j) = K(j, i) = nodeCorrelation(xs[static_cast<size_t>(i)], xs[static_cast<size_t>(j)], m.linear.spacing_min_mm,
                                       m.linear.spacing_max_mm);
    // C_ij += sum_b dsdE(i, b) dsdE(j, b) u_ba^2 K(x_i, x_j)
    Eigen::MatrixXd W = c.dsdE * m.linear.u_rand.col(a).cwiseAbs2().asDiagonal() * c.dsdE.transpose();
    for (long i = 0; i < n; ++i)
      for (long j = 0; j < n; ++j) C(i, j) += W(i, j) * K(idx[static_cast<size_t>(i)], idx[static_cast<size_t>(j)]);
  }
  return C;
}

ErrorVector propagatedUncertainty(const LinearChain& c, UncertaintyMethod method, const Eigen::MatrixXd& C) {
  const auto& G = c.G[static_cast<size_t>(method)];
  return (G * C * G.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
}

}  // namespace rotacal
