#include "core/uncertainty_budget.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

#include "core/report_envelope.hpp"
#include "core/statistics.hpp"

namespace rotacal {

namespace {

Eigen::VectorXd sqrtDiag(const Eigen::MatrixXd& m) {
  Eigen::VectorXd d = m.diagonal();
  for (Eigen::Index i = 0; i < d.size(); ++i) d[i] = std::sqrt(std::max(0.0, d[i]));
  return d;
}

// Fixed blocks merged in block order: the sums (and so the printed figures) do not depend on
// how many threads ran them.
constexpr int kBlock = 64;

}  // namespace

Eigen::VectorXd UncertaintyBudget::uA() const { return sqrtDiag(cov_a); }
Eigen::VectorXd UncertaintyBudget::uB() const { return sqrtDiag(cov_b); }
Eigen::VectorXd UncertaintyBudget::uC() const { return sqrtDiag(covariance()); }

double UncertaintyBudget::uCOr(std::string_view name, double otherwise) const {
  for (int i = 0; i < size(); ++i)
    if (names[static_cast<size_t>(i)] == name) return std::sqrt(std::max(0.0, cov_a(i, i) + cov_b(i, i)));
  return otherwise;
}

Eigen::VectorXd UncertaintyBudget::coverageFactors() const {
  return coverage_factor.size() == size() ? coverage_factor : Eigen::VectorXd::Constant(size(), kCoverageFactor);
}

Eigen::MatrixXd UncertaintyBudget::correlation() const {
  const Eigen::MatrixXd c = covariance();
  const Eigen::VectorXd s = sqrtDiag(c);
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(c.rows(), c.cols());
  for (Eigen::Index i = 0; i < c.rows(); ++i)
    for (Eigen::Index j = 0; j < c.cols(); ++j)
      r(i, j) = (s[i] > 0 && s[j] > 0) ? std::clamp(c(i, j) / (s[i] * s[j]), -1.0, 1.0) : (i == j ? 1.0 : 0.0);
  return r;
}

bool UncertaintyBudget::validate(std::string* why) const {
  const auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  const Eigen::Index n = static_cast<Eigen::Index>(names.size());
  if (units.size() != names.size()) return fail("uncertainty budget: one unit per parameter");
  if (cov_a.rows() != n || cov_a.cols() != n || cov_b.rows() != n || cov_b.cols() != n)
    return fail("uncertainty budget: covariances must be parameters x parameters");
  if (!cov_a.allFinite() || !cov_b.allFinite()) return fail("uncertainty budget: covariance is not finite");
  for (const auto& t : terms)
    if (t.u.size() != n || !t.u.allFinite()) return fail("uncertainty budget: term '" + t.contributor + "' malformed");
  return true;
}

SampleMoments::SampleMoments(int dimension)
    : sum_(Eigen::VectorXd::Zero(dimension)), sum_outer_(Eigen::MatrixXd::Zero(dimension, dimension)) {}

void SampleMoments::add(const Eigen::VectorXd& x) {
  ++n_;
  sum_ += x;
  sum_outer_.noalias() += x * x.transpose();
}

void SampleMoments::merge(const SampleMoments& o) {
  n_ += o.n_;
  sum_ += o.sum_;
  sum_outer_ += o.sum_outer_;
}

Eigen::VectorXd SampleMoments::mean() const {
  return n_ > 0 ? Eigen::VectorXd(sum_ / n_) : Eigen::VectorXd::Zero(sum_.size());
}

Eigen::MatrixXd SampleMoments::covariance() const {
  if (n_ < 2) return Eigen::MatrixXd::Zero(sum_.size(), sum_.size());
  const Eigen::VectorXd m = mean();
  return (sum_outer_ - static_cast<double>(n_) * m * m.transpose()) / (n_ - 1);
}

MonteCarloResult runMonteCarlo(const MonteCarloProblem& p, int runs, int alone_runs, std::uint64_t seed,
                               int threads) {
  const int nc = static_cast<int>(p.contributors.size());
  // Task t: contributor c (-1 = all) and a block of runs.
  struct Task {
    int contributor, first, last;
  };
  std::vector<Task> tasks;
  for (int c = -1; c < nc; ++c) {
    const int n = c < 0 ? runs : alone_runs;
    for (int b = 0; b < n; b += kBlock) tasks.push_back({c, b, std::min(n, b + kBlock)});
  }
  std::vector<SampleMoments> partial(tasks.size(), SampleMoments(p.parameters));
  MonteCarloResult out;
  out.deviations = Eigen::MatrixXd::Zero(p.parameters, std::max(0, runs));
  std::atomic<size_t> next{0};
  const auto work = [&] {
    for (size_t t; (t = next.fetch_add(1)) < tasks.size();)
      for (int r = tasks[t].first; r < tasks[t].last; ++r) {
        const Eigen::VectorXd d = p.deviation(seed, r, tasks[t].contributor);
        partial[t].add(d);
        if (tasks[t].contributor < 0) out.deviations.col(r) = d;  // each run its own column
      }
  };
  int nt = threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  nt = std::min<int>(nt, static_cast<int>(tasks.size()));
  std::vector<std::thread> pool;
  for (int i = 1; i < nt; ++i) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
  out.combined = SampleMoments(p.parameters);
  out.alone.assign(nc, SampleMoments(p.parameters));
  for (size_t t = 0; t < tasks.size(); ++t)
    (tasks[t].contributor < 0 ? out.combined : out.alone[tasks[t].contributor]).merge(partial[t]);
  return out;
}

void setTypeB(UncertaintyBudget* b, const MonteCarloResult& mc, const std::vector<std::string>& contributors) {
  // The deviation's spread about the truth, bias included: a systematic offset of the estimator
  // is as much an uncertainty as its scatter (mean square error, not variance).
  const Eigen::VectorXd mean = mc.combined.mean();
  b->cov_b = mc.combined.covariance() + mean * mean.transpose();
  b->runs = mc.combined.count();
  b->type_b_evaluated = true;
  for (size_t c = 0; c < contributors.size() && c < mc.alone.size(); ++c) {
    const Eigen::VectorXd m = mc.alone[c].mean();
    Eigen::VectorXd u = sqrtDiag(mc.alone[c].covariance());
    for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = std::sqrt(u[i] * u[i] + m[i] * m[i]);
    b->terms.push_back({contributors[c], u});
  }
  b->coverage_factor.resize(0);
  const int n = b->size();
  if (mc.deviations.cols() < kMinRunsForCoverageFactor || mc.deviations.rows() != n) return;
  const Eigen::VectorXd ua = b->cov_a.rows() == n ? b->uA() : Eigen::VectorXd::Zero(n);
  const Eigen::VectorXd uc = b->uC();
  b->coverage_factor = Eigen::VectorXd::Constant(n, kCoverageFactor);
  std::vector<double> x(static_cast<size_t>(mc.deviations.cols()));
  for (int i = 0; i < n; ++i) {
    if (!(uc[i] > 0)) continue;
    for (Eigen::Index r = 0; r < mc.deviations.cols(); ++r) x[static_cast<size_t>(r)] = mc.deviations(i, r);
    b->coverage_factor[i] = coverageHalfWidth(x, ua[i], kCoverageProbability) / uc[i];
  }
}

ReadingScatter readingScatter(double declared_um2, double observed_um2, int dof, const std::vector<double>& systematic_um2) {
  ReadingScatter out;
  double mean_sys = 0.0;
  for (double s : systematic_um2) mean_sys += s;
  if (!systematic_um2.empty()) mean_sys /= static_cast<double>(systematic_um2.size());
  const std::string contributors =
      systematic_um2.empty() ? std::string() : fmt::format(" and the Type B contributors' own residual, {:.3f} um rms,", std::sqrt(mean_sys));
  if (dof <= 0 || !(observed_um2 >= 0)) {
    out.variance_um2 = declared_um2;
    out.why = fmt::format("no residual degrees of freedom: the declared {:.3f} um", std::sqrt(declared_um2));
    return out;
  }
  const double nu = dof;
  if (declared_um2 > 0) {
    const auto p_given = [&](double s) { return chiSquareSurvival(nu * (observed_um2 - s) / declared_um2, nu); };
    if (systematic_um2.empty()) {
      out.p_value = p_given(0.0);
    } else {
      double p = 0.0;
      for (double s : systematic_um2) p += p_given(s);
      out.p_value = p / static_cast<double>(systematic_um2.size());
    }
  } else {
    out.p_value = 0.0;
  }
  if (out.p_value >= kScatterExcessAlpha) {
    out.variance_um2 = declared_um2;
    out.why = fmt::format("the declared {:.3f} um; the residual, {:.3f} um over {} dof, is within what it{} can leave: p = {:.2g}",
                          std::sqrt(declared_um2), std::sqrt(observed_um2), dof, contributors, out.p_value);
    return out;
  }
  out.variance_um2 = std::max(declared_um2, observed_um2 - mean_sys);
  out.why = fmt::format("the residual, {:.3f} um over {} dof, exceeds what the declared {:.3f} um{} can leave (p = {:.2g}): "
                        "the residual less the contributors' mean share",
                        std::sqrt(observed_um2), dof, std::sqrt(declared_um2), contributors, out.p_value);
  return out;
}

std::string coverageFactorSource(const UncertaintyBudget& b) {
  if (b.coverage_factor.size() == b.size() && b.size() > 0)
    return fmt::format("k per parameter from the Monte Carlo distribution ({} runs) convolved with the normal Type A part "
                       "(JCGM 101 7.7)",
                       b.runs);
  return fmt::format("k = {:g}, the distribution taken as normal ({})", kCoverageFactor,
                     b.type_b_evaluated && b.runs > 0
                         ? fmt::format("{} Monte Carlo runs, fewer than the {} its tail needs", b.runs, kMinRunsForCoverageFactor)
                         : std::string("no Monte Carlo distribution"));
}

Json budgetJson(const UncertaintyBudget& b, const Eigen::VectorXd& values, int top) {
  const Eigen::VectorXd ua = b.uA(), ub = b.uB(), k = b.coverageFactors();
  Json params = Json::object();
  for (int i = 0; i < b.size(); ++i) {
    Json e = {{"unit", b.units[i]}};
    setUncertaintyFields(&e, ua[i], ub[i], k[i]);
    params[b.names[i]] = e;
  }
  if (values.size() == b.size())
    for (int i = 0; i < b.size(); ++i) params[b.names[i]]["value"] = round6(values[i]);
  const Eigen::MatrixXd cov = b.covariance(), cor = b.correlation();
  Json cov_rows = Json::array(), cor_rows = Json::array();
  for (int i = 0; i < b.size(); ++i) {
    Json cr = Json::array(), rr = Json::array();
    for (int j = 0; j < b.size(); ++j) {
      cr.push_back(cov(i, j));
      rr.push_back(std::round(cor(i, j) * 1e4) / 1e4);
    }
    cov_rows.push_back(cr);
    cor_rows.push_back(rr);
  }
  Json budget = Json::object();
  for (int i = 0; i < b.size(); ++i) {
    std::vector<std::pair<double, std::string>> shares;
    for (const auto& t : b.terms) shares.push_back({t.u[i], t.contributor});
    std::stable_sort(shares.begin(), shares.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    Json list = Json::array();
    for (int k = 0; k < static_cast<int>(shares.size()) && k < top; ++k)
      if (shares[k].first > 0) list.push_back({{"contributor", shares[k].second}, {"u", round6(shares[k].first)}});
    budget[b.names[i]] = list;
  }
  Json j = {{"coverage_probability", round6(kCoverageProbability)},
            {"coverage_factor", coverageFactorSource(b)},
            {"type_a", b.type_a_source},
            {"type_b", b.type_b_source},
            {"type_b_evaluated", b.type_b_evaluated},
            {"parameters", params},
            {"order", b.names},
            {"units", b.units},
            {"covariance", cov_rows},
            {"correlation", cor_rows},
            {"budget", budget}};
  j["between_calibrations"] =
      "u_between: u_A and the contributors drawn anew at every calibration (set-up, the R-test sphere's mounting, the "
      "laser's alignment, the cycle's thermal state), each alone; what differs between two calibrations of this machine, "
      "and what history trends with";
  if (b.type_b_evaluated) {
    j["runs"] = b.runs;
    j["seed"] = b.seed;
  }
  return j;
}

void setUncertaintyFields(Json* entry, double u_a, double u_b, double k, double u_between) {
  const double u_c = std::hypot(u_a, u_b);
  Json& e = *entry;
  e["u"] = round6(u_c);
  e["u_a"] = round6(u_a);
  e["u_b"] = round6(u_b);
  e["u_c"] = round6(u_c);
  if (u_between >= 0) e["u_between"] = round6(u_between);
  e["U"] = round6(k * u_c);
  e["k"] = round6(k);
}

void setUncertaintyArrays(Json* entry, const Eigen::VectorXd& u_a, const Eigen::VectorXd& u_b, const Eigen::VectorXd& k) {
  if (u_b.size() != u_a.size() || k.size() != u_a.size())
    throw std::invalid_argument("setUncertaintyArrays: u_a, u_b and k differ in length");
  Json u = Json::array(), a = Json::array(), b = Json::array(), c = Json::array(), big = Json::array(), kk = Json::array();
  for (Eigen::Index i = 0; i < u_a.size(); ++i) {
    Json one = Json::object();
    setUncertaintyFields(&one, u_a[i], u_b[i], k[i]);
    u.push_back(one["u"]);
    a.push_back(one["u_a"]);
    b.push_back(one["u_b"]);
    c.push_back(one["u_c"]);
    big.push_back(one["U"]);
    kk.push_back(one["k"]);
  }
  Json& e = *entry;
  e["u"] = u;
  e["u_a"] = a;
  e["u_b"] = b;
  e["u_c"] = c;
  e["U"] = big;
  e["k"] = kk;
}

void setTypeAOnlyFields(Json* entry, double u_a) { setUncertaintyFields(entry, u_a, 0.0, kCoverageFactor); }

void addBudgetFields(Json* parameters, const UncertaintyBudget& b) {
  const Eigen::VectorXd ua = b.uA(), ub = b.uB(), ubetween = b.uBetween(), k = b.coverageFactors();
  for (int i = 0; i < b.size(); ++i) {
    if (!parameters->contains(b.names[i])) continue;
    setUncertaintyFields(&(*parameters)[b.names[i]], ua[i], ub[i], k[i], ubetween[i]);
  }
}

std::string budgetText(const UncertaintyBudget& b, const Eigen::VectorXd& values, int top) {
  const Eigen::VectorXd ua = b.uA(), ub = b.uB(), uc = b.uC(), k = b.coverageFactors();
  std::string s = fmt::format("uncertainty (u: k = 1; U = k u_c: {:.2f} % coverage, {})\n", 100.0 * kCoverageProbability,
                              coverageFactorSource(b));
  s += fmt::format("  Type A: {}\n  Type B: {}\n", b.type_a_source, b.type_b_source);
  s += fmt::format("{:<10} {:>10} {:>9} {:>9} {:>9} {:>9} {:>5}  {:<6} {}\n", "parameter", "value", "u_A", "u_B", "u_c",
                   "U", "k", "unit", "largest contributors (u alone)");
  for (int i = 0; i < b.size(); ++i) {
    std::vector<std::pair<double, std::string>> shares;
    for (const auto& t : b.terms) shares.push_back({t.u[i], t.contributor});
    std::stable_sort(shares.begin(), shares.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    std::string largest;
    for (int k = 0; k < static_cast<int>(shares.size()) && k < top; ++k)
      if (shares[k].first > 0)
        largest += fmt::format("{}{} {:.2f}", largest.empty() ? "" : ", ", shares[k].second, shares[k].first);
    s += fmt::format("{:<10} {:>10.3f} {:>9.3f} {:>9.3f} {:>9.3f} {:>9.3f} {:>5.2f}  {:<6} {}\n", b.names[i],
                     i < values.size() ? values[i] : 0.0, ua[i], ub[i], uc[i], k[i] * uc[i], k[i], b.units[i], largest);
  }
  const Eigen::MatrixXd cor = b.correlation();
  std::vector<std::pair<double, std::string>> strong;
  for (int i = 0; i < b.size(); ++i)
    for (int j = i + 1; j < b.size(); ++j)
      if (std::abs(cor(i, j)) >= 0.5)
        strong.push_back({std::abs(cor(i, j)), fmt::format("{}/{} {:+.2f}", b.names[i], b.names[j], cor(i, j))});
  std::stable_sort(strong.begin(), strong.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  if (!strong.empty()) {
    s += "correlations |r| >= 0.5:";
    for (size_t k = 0; k < strong.size() && k < 6; ++k) s += (k ? ", " : " ") + strong[k].second;
    s += "\n";
  }
  return s;
}

void runTypeB(UncertaintyBudget* budget, const ContributorSet& type_b, const BudgetOptions& options,
              const std::function<Eigen::VectorXd(std::uint64_t, int, int)>& deviation) {
  MonteCarloProblem p;
  p.parameters = budget->size();
  for (const auto& c : type_b.items) p.contributors.emplace_back(c.info->id);
  p.deviation = deviation;
  const MonteCarloResult mc = runMonteCarlo(p, options.runs, options.alone_runs, options.seed, options.threads);
  setTypeB(budget, mc, p.contributors);
  budget->seed = options.seed;
}

std::string contributorsSource(const ContributorSet& declared) {
  return declared.file.empty() ? std::string("the machine") : declared.file;
}

std::string leftOutNote(std::string_view acts_on, const std::vector<std::string>& left_out) {
  return left_out.empty() ? std::string() : fmt::format("; not acting on {} and left out: {}", acts_on, fmt::join(left_out, ", "));
}

std::string typeBDrawnSource(size_t n, const ContributorSet& declared, std::string_view how, const BudgetOptions& options,
                             std::string_view note) {
  return fmt::format("{} declared contributors (from {}) drawn on {}, {} runs, seed {}{}", n, contributorsSource(declared),
                     how, options.runs, options.seed, note);
}

bool variesBetweenCalibrations(const ContributorInfo& c) {
  switch (c.kind) {
    case ContributorKind::SetupPosition:
    case ContributorKind::SetupOrientation:
    case ContributorKind::RtestSphereOffset:
    case ContributorKind::RtestCycleDrift:
    case ContributorKind::LaserAlignment: return true;
    default: return false;
  }
}

Eigen::VectorXd UncertaintyBudget::uBetween() const {
  Eigen::VectorXd v = uA().cwiseAbs2();
  for (const auto& t : terms) {
    const ContributorInfo* info = findContributor(t.contributor);
    if (info && variesBetweenCalibrations(*info)) v += t.u.cwiseAbs2();
  }
  // The terms come from shorter runs than u_c: never more than u_c.
  return v.cwiseSqrt().cwiseMin(uC());
}

UncertaintyBudget UncertaintyBudget::slice(int first, int count) const {
  UncertaintyBudget b;
  b.names.assign(names.begin() + first, names.begin() + first + count);
  b.units.assign(units.begin() + first, units.begin() + first + count);
  b.cov_a = cov_a.block(first, first, count, count);
  b.cov_b = cov_b.block(first, first, count, count);
  b.type_a_source = type_a_source;
  b.type_b_evaluated = type_b_evaluated;
  b.type_b_source = type_b_source;
  for (const auto& t : terms) b.terms.push_back({t.contributor, t.u.segment(first, count)});
  b.runs = runs;
  b.seed = seed;
  if (coverage_factor.size() == size()) b.coverage_factor = coverage_factor.segment(first, count);
  return b;
}

bool BudgetOptions::validate(std::string* why) const {
  const auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (runs < 100 || runs > 1000000) return fail("Monte Carlo runs must be in [100, 1000000]");
  if (alone_runs < 0 || alone_runs > 1000000) return fail("Monte Carlo runs per contributor must be in [0, 1000000]");
  if (threads < 0 || threads > 256) return fail("threads must be in [0, 256]");
  return true;
}

void BudgetOptions::validateOrThrow() const {
  std::string why;
  if (!validate(&why)) throw std::invalid_argument(why);
}

std::string typeBNotDeclared() {
  return "not evaluated: the machine declares no contributors (MACHINE.json `contributors`, docs/uncertainty.md), so "
         "u_c covers the data's scatter only";
}

std::vector<double> contributorResidualVariances(int draws, std::uint64_t budget_seed,
                                                 const std::function<double(std::uint64_t seed, int draw)>& residual_um2) {
  constexpr std::uint64_t kResidualStream = 0x5245534944ULL;  // "RESID"
  std::vector<double> out;
  out.reserve(static_cast<size_t>(std::max(draws, 0)));
  for (int k = 0; k < draws; ++k) out.push_back(residual_um2(budget_seed ^ kResidualStream, k));
  return out;
}

bool typeBToRun(UncertaintyBudget* b, bool declared, bool any_acting, std::string_view acts_on, std::string_view note) {
  if (!declared) {
    b->type_b_source = typeBNotDeclared();
    return false;
  }
  if (!any_acting) {
    b->type_b_evaluated = true;
    b->type_b_source = fmt::format("no declared contributor acts on {} as Type B{}", acts_on, note);
    return false;
  }
  return true;
}

std::string raiseToRepeatScatter(Eigen::MatrixXd* cov_a, const std::vector<Eigen::VectorXd>& per_repeat) {
  if (per_repeat.size() < 2) return {};
  const Eigen::Index n = cov_a->rows();
  SampleMoments m(static_cast<int>(n));
  for (const auto& v : per_repeat) m.add(v);
  const Eigen::MatrixXd of_mean = m.covariance() / static_cast<double>(per_repeat.size());
  // Under "cov_a is right", (R - 1) of_mean / cov_a is chi^2 with R - 1 dof. Raising wherever
  // of_mean is larger would take every upward fluctuation (two repeats: u_A 20 % high on
  // average): only a significant excess counts, as in readingScatter.
  const double nu = static_cast<double>(per_repeat.size() - 1);
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  int raised = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    if ((*cov_a)(i, i) > 0 && of_mean(i, i) > (*cov_a)(i, i) &&
        chiSquareSurvival(nu * of_mean(i, i) / (*cov_a)(i, i), nu) < kScatterExcessAlpha) {
      d[i] = std::sqrt(of_mean(i, i) / (*cov_a)(i, i));
      ++raised;
    }
  *cov_a = d.asDiagonal() * (*cov_a) * d.asDiagonal();
  return fmt::format(
      "; the {} repeats' own estimates scatter more than that (chi-square, {:g} %) for {} parameter(s), raised to the "
      "standard error of their mean",
      per_repeat.size(), 100.0 * kScatterExcessAlpha, raised);
}

}  // namespace rotacal
