#include "cycles/touch154/budget.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "core/units.hpp"
#include "cycles/touch154/uncertainty.hpp"

namespace rotacal {

bool measuredByTypeA(const ContributorInfo& c) {
  return c.kind == ContributorKind::ProbeRepeatability || c.kind == ContributorKind::SurfaceRoughness;
}

namespace {

// analyze's estimators as the linearised chain knows them.
bool chainMethod(Method m, UncertaintyMethod* out) {
  switch (m) {
    case Method::LeastSquaresPerPoint: *out = UncertaintyMethod::LsqPerPoint; return true;
    case Method::ClosedForm: *out = UncertaintyMethod::ClosedFormPooled; return true;
    case Method::LeastSquaresRigidSetup: *out = UncertaintyMethod::LsqRigidSetup; return true;
  }
  return false;
}

}  // namespace

UncertaintyBudget touch154Budget(const ProbePlan& plan, const IdentificationResult& main,
                                 const std::vector<IdentificationResult>& per_run, const ContributorSet* contributors,
                                 const Touch154BudgetOptions& options) {
  options.validateOrThrow();
  const auto& params = locationParameters(main.estimate.kinematics);
  UncertaintyBudget b;
  Eigen::VectorXd f(kNumLocationErrors);  // internal -> report units
  for (int i = 0; i < kNumLocationErrors; ++i) {
    b.names.emplace_back(params[i].name);
    b.units.emplace_back(reportUnit(params[i].kind));
    f[i] = params[i].kind == ParamKind::Length ? mmToUm(1.0) : radToMdeg(1.0);
  }
  const int n = kNumLocationErrors;

  b.cov_b = Eigen::MatrixXd::Zero(n, n);
  const double runs_n = static_cast<double>(std::max<size_t>(1, per_run.size()));

  // Type A when nothing else is declared: the fit's covariance scaled by its own residual.
  Eigen::MatrixXd cov_a = f.asDiagonal() * Eigen::MatrixXd(main.covariance) * f.asDiagonal();
  b.type_a_source = fmt::format("the fit's covariance scaled by its residual ({:.3f} um, {} dof)",
                                main.summary.sigma_um, main.summary.dof);
  std::string type_b_missing;
  UncertaintyMethod um{};
  ContributorSet type_b;
  std::optional<LinearChain> chain;
  if (!contributors) {
    type_b_missing =
        typeBNotDeclared();
  } else if (!chainMethod(main.method, &um)) {
    type_b_missing = fmt::format("not evaluated: no Monte Carlo model of the estimator {} (use lsq_per_point or closed_form)",
                                 methodName(main.method));
  } else {
    type_b = *contributors;
    type_b.items.erase(std::remove_if(type_b.items.begin(), type_b.items.end(),
                                      [](const Contributor& c) { return measuredByTypeA(*c.info); }),
                       type_b.items.end());
    chain = lineariseChain(plan, main.estimate);
    if (!chain->has[static_cast<size_t>(um)]) {
      type_b_missing = "not evaluated: " + (um == UncertaintyMethod::LsqRigidSetup ? chain->rigid_setup_why
                                            : chain->closed_form_why.empty() ? chain->least_squares_why
                                                                             : chain->closed_form_why);
      chain.reset();
    }
  }
  if (chain) {
    // Type A with declared contributors: the per-touch scatter (repeatability, roughness) through
    // the estimator's own map G, sigma^2 G G^T / repeats. The residual measures that scatter, but
    // also carries the part of the systematic contributors (linear-axis errors between nodes, form)
    // that the model cannot absorb; that part is already in u_B, so it is taken out of the
    // residual (its expected value, trace(P C P) / dof with P the residual projector and C the
    // triggers' covariance under the Type B contributors). What remains is floored at the declared
    // per-touch scatter: the user's claim is kept when the data show less.
    double declared_mm2 = 0.0;
    for (const auto& c : contributors->items)
      if (measuredByTypeA(*c.info)) declared_mm2 += c.u[0] * c.u[0];
    double sigma2 = declared_mm2;
    std::string how;
    if (main.method != Method::ClosedForm && main.summary.dof > 0) {
      // readingScatter with the contributors' residual share by its expected value alone: the
      // linear chain gives it in closed form (trace of the trigger covariance left by the fit).
      std::vector<double> sys_um2;
      if (!type_b.items.empty()) {
        const Eigen::MatrixXd C = triggerCovariance(*chain, type_b);
        const Eigen::MatrixXd& U = um == UncertaintyMethod::LsqRigidSetup ? chain->range_rs : chain->range_lp;
        const double dof = static_cast<double>(chain->points - U.cols());
        if (dof > 0)
          sys_um2.push_back(mmToUm(1.0) * mmToUm(1.0) * std::max(0.0, (C.trace() - (U.transpose() * C * U).trace()) / dof));
      }
      const ReadingScatter scatter = readingScatter(mmToUm(1.0) * mmToUm(1.0) * declared_mm2,
                                                    main.summary.sigma_um * main.summary.sigma_um, main.summary.dof, sys_um2);
      sigma2 = umToMm(1.0) * umToMm(1.0) * scatter.variance_um2;
      how = scatter.why;
    } else {
      how = fmt::format("the declared {:.3f} um (the closed form leaves no residual to measure it)",
                        mmToUm(std::sqrt(declared_mm2)));
    }
    const IdentificationMap& G = chain->G[static_cast<size_t>(um)];
    cov_a = f.asDiagonal() * (sigma2 / runs_n * G * G.transpose()) * f.asDiagonal();
    b.type_a_source = fmt::format("the per-touch scatter {:.3f} um ({}) through the estimator, {} run(s)",
                                  mmToUm(std::sqrt(sigma2)), how, per_run.size() > 1 ? per_run.size() : 1);
  }
  // Repeats: a parameter whose repeats scatter more than that (drift between runs, set-up
  // changes) takes the scatter of the runs' mean instead; correlations kept by scaling.
  {
    std::vector<Eigen::VectorXd> each;
    for (const auto& r : per_run) each.push_back(f.cwiseProduct(Eigen::VectorXd(r.estimate.values)));
    b.type_a_source += raiseToRepeatScatter(&cov_a, each);
  }
  b.cov_a = cov_a;
  b.terms.push_back({"data", b.uA()});
  if (!chain) {
    b.type_b_source = type_b_missing;
    return b;
  }
  if (type_b.items.empty()) {
    b.type_b_evaluated = true;
    b.type_b_source = "every declared contributor acts at each touch independently: u_A measures them all";
    return b;
  }
  const auto mi = static_cast<size_t>(um);
  const DrawModel model = drawModel(type_b);
  const LinearChain& ch = *chain;
  MethodMask mask{};
  mask[mi] = true;
  runTypeB(&b, type_b, options, [&](std::uint64_t seed, int run, int c) -> Eigen::VectorXd {
    thread_local RunDraw d;
    drawRun(model, ch, seed, run, &d);
    const ErrorVector dev = c < 0 ? linearisedDeviation(ch, mask, d)[mi]
                                  : linearisedDeviation(ch, mask, onlyContributor(d, *type_b.items[static_cast<size_t>(c)].info))[mi];
    return f.cwiseProduct(Eigen::VectorXd(dev));
  });
  b.type_b_source = fmt::format(
      "{} declared contributors (from {}) propagated through {} by the linearised Monte Carlo of the exact simulator "
      "(000 Sec. 5), {} runs, seed {}, around the identified errors; the per-touch ones are in u_A",
      type_b.items.size(), contributorsSource(*contributors), methodName(main.method), options.runs, options.seed);
  return b;
}

}  // namespace rotacal
