#include "core/uncertainty_budget.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

#include "core/report_envelope.hpp"

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
  std::atomic<size_t> next{0};
  const auto work = [&] {
    for (size_t t; (t = next.fetch_add(1)) < tasks.size();)
      for (int r = tasks[t].first; r < tasks[t].last; ++r) partial[t].add(p.deviation(seed, r, tasks[t].contributor));
  };
  int nt = threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  nt = std::min<int>(nt, static_cast<int>(tasks.size()));
  std::vector<std::thread> pool;
  for (int i = 1; i < nt; ++i) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
  MonteCarloResult out;
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
}

Json budgetJson(const UncertaintyBudget& b, int top) {
  const Eigen::VectorXd ua = b.uA(), ub = b.uB(), uc = b.uC();
  Json params = Json::object();
  for (int i = 0; i < b.size(); ++i)
    params[b.names[i]] = {{"unit", b.units[i]},
                          {"u_a", round6(ua[i])},
                          {"u_b", round6(ub[i])},
                          {"u_c", round6(uc[i])},
                          {"U", round6(kCoverageFactor * uc[i])}};
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
  Json j = {{"k", kCoverageFactor},
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

void addBudgetFields(Json* parameters, const UncertaintyBudget& b) {
  const Eigen::VectorXd ua = b.uA(), ub = b.uB(), uc = b.uC(), ubetween = b.uBetween();
  for (int i = 0; i < b.size(); ++i) {
    if (!parameters->contains(b.names[i])) continue;
    Json& e = (*parameters)[b.names[i]];
    e["u_a"] = round6(ua[i]);
    e["u_b"] = round6(ub[i]);
    e["u_c"] = round6(uc[i]);
    e["u_between"] = round6(ubetween[i]);
    e["U"] = round6(kCoverageFactor * uc[i]);
    e["k"] = kCoverageFactor;
  }
}

std::string budgetText(const UncertaintyBudget& b, const Eigen::VectorXd& values, int top) {
  const Eigen::VectorXd ua = b.uA(), ub = b.uB(), uc = b.uC();
  std::string s = fmt::format("uncertainty (u: k = 1; U: k = {:g}, about 95 %)\n", kCoverageFactor);
  s += fmt::format("  Type A: {}\n  Type B: {}\n", b.type_a_source, b.type_b_source);
  s += fmt::format("{:<10} {:>10} {:>9} {:>9} {:>9} {:>9}  {:<6} {}\n", "parameter", "value", "u_A", "u_B", "u_c", "U",
                   "unit", "largest contributors (u alone)");
  for (int i = 0; i < b.size(); ++i) {
    std::vector<std::pair<double, std::string>> shares;
    for (const auto& t : b.terms) shares.push_back({t.u[i], t.contributor});
    std::stable_sort(shares.begin(), shares.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    std::string largest;
    for (int k = 0; k < static_cast<int>(shares.size()) && k < top; ++k)
      if (shares[k].first > 0)
        largest += fmt::format("{}{} {:.2f}", largest.empty() ? "" : ", ", shares[k].second, shares[k].first);
    s += fmt::format("{:<10} {:>10.3f} {:>9.3f} {:>9.3f} {:>9.3f} {:>9.3f}  {:<6} {}\n", b.names[i],
                     i < values.size() ? values[i] : 0.0, ua[i], ub[i], uc[i], kCoverageFactor * uc[i], b.units[i],
                     largest);
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

std::string raiseToRepeatScatter(Eigen::MatrixXd* cov_a, const std::vector<Eigen::VectorXd>& per_repeat) {
  if (per_repeat.size() < 2) return {};
  const Eigen::Index n = cov_a->rows();
  SampleMoments m(static_cast<int>(n));
  for (const auto& v : per_repeat) m.add(v);
  const Eigen::MatrixXd of_mean = m.covariance() / static_cast<double>(per_repeat.size());
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  for (Eigen::Index i = 0; i < n; ++i)
    if ((*cov_a)(i, i) > 0 && of_mean(i, i) > (*cov_a)(i, i)) d[i] = std::sqrt(of_mean(i, i) / (*cov_a)(i, i));
  *cov_a = d.asDiagonal() * (*cov_a) * d.asDiagonal();
  return fmt::format(
      "; each parameter raised to the scatter of the {} repeats' own estimates (standard error of their mean) where "
      "that is larger",
      per_repeat.size());
}

}  // namespace rotacal
