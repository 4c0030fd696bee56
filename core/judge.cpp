#include "core/judge.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "core/declared_noise.hpp"
#include "core/statistics.hpp"
#include "core/require_valid.hpp"

namespace rotacal {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Numerical rank: singular values of the whitened, column-normalised matrix below this
// fraction of the largest are zero. Far below any exact-confounding angle worth stating
// (0.1 deg is 1.7e-3): it only removes columns that are copies of others to rounding.
constexpr double kRankRtol = 1e-9;
// Leaving group S out, the refit's information along a direction of the model is the full
// fit's times an eigenvalue lambda of I - H_SS (Q orthonormal: Q_rest^T Q_rest = I - Q_S^T Q_S),
// and its prediction of S along that direction carries a noise variance 1 / lambda readings'.
// Below this share the other groups do not identify the direction: it is refitted on S itself
// like a parameter only S has data for (lambda = 0). At 1e-2 a fold's prediction may carry at
// most about a hundred readings' worth of noise per such direction; above it, one fold whose
// refit is near-singular decided the mean gain alone (a fold at lambda ~ 1e-7 gave a gain of
// -4e6 and rejected an effect at p = 1e-84). Both models' folds follow the same rule.
constexpr double kFoldInformation = 1e-2;
// Fewer folds than this give no standard error worth the name for the held-out gain.
constexpr int kMinFolds = 3;
// A term of a confounding combination is named when it moves the data by at least this
// fraction of the largest term.
constexpr double kTermShare = 0.05;

double deg(double rad) { return rad * 180.0 / kPi; }

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument("judge: " + what); }

/// An orthonormal basis Q of a whitened matrix's columns (rank r) and the map from Q's
/// coordinates to the columns' coefficients: X coef.col(i) = Q.col(i) (minimum norm).
struct Span {
  Eigen::MatrixXd Q;     // n x r
  Eigen::MatrixXd coef;  // p x r
  Eigen::MatrixXd null;  // p x (p - r): null space of X in parameter coordinates
  int rank() const { return static_cast<int>(Q.cols()); }
};

Span spanOf(const Eigen::MatrixXd& X) {
  Span s;
  const Eigen::Index n = X.rows(), p = X.cols();
  if (p == 0) {
    s.Q.resize(n, 0);
    s.coef.resize(0, 0);
    s.null.resize(0, 0);
    return s;
  }
  // Column normalisation first (mixed units: mm and urad columns): the rank tolerance is then
  // relative to columns of one scale.
  Eigen::VectorXd norm = X.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < p; ++j)
    if (!(norm[j] > 0)) norm[j] = 1.0;
  const Eigen::MatrixXd Xn = X * norm.cwiseInverse().asDiagonal();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(Xn, Eigen::ComputeThinU | Eigen::ComputeFullV);
  const Eigen::VectorXd& sv = svd.singularValues();
  Eigen::Index r = 0;
  const double smax = sv.size() ? sv[0] : 0.0;
  while (r < sv.size() && sv[r] > kRankRtol * smax && sv[r] > 0) ++r;
  s.Q = svd.matrixU().leftCols(r);
  s.coef = norm.cwiseInverse().asDiagonal() * svd.matrixV().leftCols(r) * sv.head(r).cwiseInverse().asDiagonal();
  s.null = svd.matrixV().rightCols(p - r);
  return s;
}

/// Principal directions of span(Qc) against span(Qx) (Bjorck & Golub 1973): SVD of Qx^T Qc.
/// The sines come from the projected-out vectors' norms, exact for small angles (acos of a
/// cosine near 1 is not).
struct Principal {
  Eigen::VectorXd angle;   // per direction of Qc, radians, ascending
  Eigen::MatrixXd V;       // Qc coordinates of each direction (columns)
  Eigen::MatrixXd W;       // Qx coordinates of each direction's projection onto span(Qx)
  Eigen::MatrixXd A;       // n x k_eff: orthonormal, the kept directions with span(Qx) removed
  Eigen::MatrixXd Acoord;  // Qc coordinates of A's columns (direction / its sine)
  std::vector<int> kept;   // indices into angle
};

Principal principal(const Eigen::MatrixXd& Qx, const Eigen::MatrixXd& Qc, double exact_rad) {
  Principal pr;
  const Eigen::Index kc = Qc.cols();
  if (kc == 0) return pr;
  Eigen::MatrixXd V;
  if (Qx.cols() == 0) {
    V = Eigen::MatrixXd::Identity(kc, kc);
  } else {
    const Eigen::MatrixXd M = Qx.transpose() * Qc;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeFullV);
    V = svd.matrixV();  // largest cosine first: smallest angle first
  }
  pr.V = V;
  pr.W = Qx.cols() ? Eigen::MatrixXd(Qx.transpose() * Qc * V) : Eigen::MatrixXd(0, kc);
  pr.angle.resize(kc);
  std::vector<Eigen::VectorXd> a;
  for (Eigen::Index j = 0; j < kc; ++j) {
    const Eigen::VectorXd d = Qc * V.col(j);
    const Eigen::VectorXd w = Qx.cols() ? Eigen::VectorXd(d - Qx * pr.W.col(j)) : d;
    const double sn = w.norm(), cs = pr.W.rows() ? pr.W.col(j).norm() : 0.0;
    pr.angle[j] = std::atan2(sn, cs);
    if (pr.angle[j] >= exact_rad) {
      pr.kept.push_back(static_cast<int>(j));
      a.push_back(w / sn);
    }
  }
  pr.A.resize(Qc.rows(), static_cast<Eigen::Index>(a.size()));
  pr.Acoord.resize(kc, static_cast<Eigen::Index>(a.size()));
  for (size_t i = 0; i < a.size(); ++i) {
    pr.A.col(static_cast<Eigen::Index>(i)) = a[i];
    const int j = pr.kept[i];
    pr.Acoord.col(static_cast<Eigen::Index>(i)) = V.col(j) / std::sin(pr.angle[j]);
  }
  // Directions of one SVD are orthogonal after projection (the cross terms vanish), but
  // rounding is not: one QR pass restores orthonormality at no cost to the span.
  if (pr.A.cols() > 0) {
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(pr.A);
    const Eigen::MatrixXd R = qr.matrixQR().topRows(pr.A.cols()).triangularView<Eigen::Upper>();
    pr.A = qr.householderQ() * Eigen::MatrixXd::Identity(pr.A.rows(), pr.A.cols());
    // A_old = A_new R  =>  A_new = A_old R^-1: coordinates follow.
    pr.Acoord = pr.Acoord * R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(R.rows(), R.cols()));
  }
  return pr;
}

/// Leave-one-group-out prediction errors of the model spanned by Q (whitened), exact through
/// the hat matrix: e_S = (I - Q_S Q_S^T)^-1 r_S.
struct Holdout {
  std::vector<double> ss;      // per group: whitened sum of squares
  std::vector<double> ss_raw;  // per group: in y's unit squared
  std::vector<int> count;     // per group: predictable dimensions
  std::vector<char> valid;
};

Holdout holdout(const Eigen::MatrixXd& Q, const Eigen::VectorXd& yw, const Eigen::VectorXd& sigma,
                const std::vector<std::vector<int>>& members) {
  Holdout h;
  const size_t G = members.size();
  h.ss.assign(G, 0.0);
  h.ss_raw.assign(G, 0.0);
  h.count.assign(G, 0);
  h.valid.assign(G, 0);
  const Eigen::VectorXd r = yw - Q * (Q.transpose() * yw);
  for (size_t g = 0; g < G; ++g) {
    const auto& S = members[g];
    const Eigen::Index m = static_cast<Eigen::Index>(S.size());
    Eigen::MatrixXd QS(m, Q.cols());
    Eigen::VectorXd rS(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      QS.row(i) = Q.row(S[static_cast<size_t>(i)]);
      rS[i] = r[S[static_cast<size_t>(i)]];
    }
    const Eigen::MatrixXd C = Eigen::MatrixXd::Identity(m, m) - QS * QS.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(C);
    // Eigenvalue 0 of C: a direction the model can produce on S alone (a parameter only this
    // group has data for, such as one angular error per commanded angle). It cannot be
    // predicted from the other groups; it is refitted on S itself and the group's prediction
    // error lives in the rest (the full residual r_S is orthogonal to those directions, as
    // r is to the model's span). The pseudo-inverse on the other eigenvalues does both; an
    // eigenvalue below kFoldInformation is such a direction too (the rest barely sees it).
    Eigen::VectorXd inv = Eigen::VectorXd::Zero(m);
    int dims = 0;
    for (Eigen::Index i = 0; i < m; ++i)
      if (es.eigenvalues()[i] > kFoldInformation) {
        inv[i] = 1.0 / es.eigenvalues()[i];
        ++dims;
      }
    if (dims == 0) continue;
    const Eigen::VectorXd e = es.eigenvectors() * (inv.asDiagonal() * (es.eigenvectors().transpose() * rS));
    h.valid[g] = 1;
    h.count[g] = dims;
    h.ss[g] = e.squaredNorm();
    for (Eigen::Index i = 0; i < m; ++i) {
      const double s = sigma[S[static_cast<size_t>(i)]];
      h.ss_raw[g] += e[i] * e[i] * s * s;
    }
  }
  return h;
}

double holdoutRms(const Holdout& h, const std::vector<char>& use) {
  double ss = 0.0;
  int n = 0;
  for (size_t g = 0; g < h.ss.size(); ++g)
    if (use[g]) {
      ss += h.ss_raw[g];
      n += h.count[g];
    }
  return n ? std::sqrt(ss / n) : 0.0;
}

/// The columns that stand for a factor: level indicators, or a centred, scaled quadratic.
Eigen::MatrixXd factorColumns(const JudgeFactor& f, const Eigen::VectorXd& inv_sigma) {
  const Eigen::Index n = inv_sigma.size();
  if (!f.levels.empty()) {
    std::map<std::string, int> idx;
    for (const auto& l : f.levels) idx.emplace(l, static_cast<int>(idx.size()));
    Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(idx.size()));
    for (Eigen::Index i = 0; i < n; ++i) D(i, idx[f.levels[static_cast<size_t>(i)]]) = inv_sigma[i];
    return D;
  }
  const Eigen::Map<const Eigen::VectorXd> x(f.values.data(), n);
  const double mid = 0.5 * (x.maxCoeff() + x.minCoeff());
  const double half = std::max(0.5 * (x.maxCoeff() - x.minCoeff()), 1e-300);
  const Eigen::VectorXd z = (x.array() - mid) / half;
  Eigen::MatrixXd D(n, 2);
  D.col(0) = z.cwiseProduct(inv_sigma);
  D.col(1) = z.cwiseProduct(z).cwiseProduct(inv_sigma);
  return D;
}

std::string fmtg(double v) { return fmt::format("{:.3g}", v); }

struct Context {
  const JudgeProblem& pb;
  const JudgeOptions& o;
  Eigen::VectorXd inv_sigma, yw;
  Eigen::VectorXd sigma;     // per observation: pb.sigma, or sqrt(diag) of pb.covariance
  Eigen::MatrixXd W, W_inv;  // the covariance's inverse root and root; empty: diagonal
  Eigen::MatrixXd null_w;    // the problem's null draws whitened; empty: chi2(dof)
  Eigen::MatrixXd whiten(const Eigen::MatrixXd& X) const {
    return W.size() ? Eigen::MatrixXd(W * X) : Eigen::MatrixXd(inv_sigma.asDiagonal() * X);
  }
  Eigen::VectorXd raw(const Eigen::VectorXd& rw) const {
    return W.size() ? Eigen::VectorXd(W_inv * rw) : Eigen::VectorXd(rw.cwiseQuotient(inv_sigma));
  }
  std::vector<std::vector<int>> members;
  std::vector<Eigen::MatrixXd> factor_cols;  // whitened
  double exact_rad = 0.0, partial_rad = 0.0, thr = 0.0;
};

/// The model's raw columns (W^-1 times its whitened span) orthonormalised: the ordinary least
/// squares residual projector of the model in y's unit.
Eigen::MatrixXd rawSpan(const Context& cx, const Span& sx) {
  const Eigen::MatrixXd R = cx.W_inv * sx.Q;
  if (R.cols() == 0) return R;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(R);
  return qr.householderQ() * Eigen::MatrixXd::Identity(R.rows(), R.cols());
}

Eigen::VectorXd rawResidual(const Context& cx, const Span& sx) {
  const Eigen::MatrixXd Q = rawSpan(cx, sx);
  return cx.pb.y - Q * (Q.transpose() * cx.pb.y);
}

/// The declared scatter of that ordinary residual, rms per degree of freedom:
/// sqrt(tr(M Sigma M) / dof), M = I - Q Q^T (= sigma for equal independent readings).
double declaredResidualRms(const Context& cx, const Span& sx) {
  const Eigen::MatrixXd Q = rawSpan(cx, sx);
  const double dof = static_cast<double>(cx.pb.y.size() - Q.cols());
  if (dof <= 0) return 0.0;
  const double tr = cx.pb.covariance.trace() - (Q.transpose() * cx.pb.covariance * Q).trace();
  return std::sqrt(std::max(0.0, tr) / dof);
}

JudgeAdequacy adequacy(const Context& cx, const Span& sx) {
  JudgeAdequacy a;
  const Eigen::Index n = cx.yw.size();
  const Eigen::VectorXd r = cx.yw - sx.Q * (sx.Q.transpose() * cx.yw);
  a.chi2 = r.squaredNorm();
  a.dof = static_cast<int>(n) - sx.rank();
  a.threshold = cx.thr;
  a.p_value = a.dof > 0 ? chiSquareSurvival(a.chi2, a.dof) : 1.0;
  a.null_dof = a.dof;
  if (a.dof > 0 && cx.null_w.cols() > 0) {
    const Eigen::VectorXd c = (cx.null_w - sx.Q * (sx.Q.transpose() * cx.null_w)).colwise().squaredNorm().transpose();
    const ScaledChiSquare null = scaledChiSquareFromDraws(std::vector<double>(c.data(), c.data() + c.size()));
    if (null.draws > 0) {
      a.null_draws = null.draws;
      a.null_scale = null.scale;
      a.null_dof = null.dof;
      a.p_value = chiSquareSurvival(a.chi2 / a.null_scale, a.null_dof);
    }
  }
  a.passes = !(a.p_value < a.threshold);
  // In y's unit: with a full covariance the whitened residual brought back by W^-1 weighs the
  // shared directions as the test does, and reads tens of micrometres along a set-up the model
  // absorbs anyway; the figure a user compares with the fit is the model's ordinary residual.
  const Eigen::VectorXd raw = cx.W.size() ? rawResidual(cx, sx) : cx.raw(r);
  a.rms_residual = std::sqrt(raw.squaredNorm() / static_cast<double>(n));
  // Harmonic mean of the variances (n / tr Sigma^-1): extra white scatter tau^2 raises E chi2 / dof
  // to 1 + tau^2 / sigma_eff^2 (exactly for equal sigma_i, on average otherwise).
  const double sigma_eff2 =
      static_cast<double>(n) / (cx.W.size() ? cx.W.squaredNorm() : cx.inv_sigma.squaredNorm());
  a.excess_rms = a.dof > 0 ? std::sqrt(sigma_eff2 * std::max(0.0, a.chi2 / a.dof - 1.0)) : 0.0;
  for (size_t f = 0; f < cx.pb.factors.size(); ++f) {
    const JudgeFactor& fac = cx.pb.factors[f];
    const Span sf = spanOf(cx.factor_cols[f]);
    const Principal pr = principal(sx.Q, sf.Q, cx.exact_rad);
    JudgeFactorShare s;
    s.factor = fac.name;
    s.dof = static_cast<int>(pr.A.cols());
    if (s.dof == 0) {
      s.detail = "carries nothing the model does not already absorb";
      a.factors.push_back(s);
      continue;
    }
    const Eigen::VectorXd z = pr.A.transpose() * r;
    s.chi2 = z.squaredNorm();
    s.p_value = chiSquareSurvival(s.chi2, s.dof);
    s.share = a.chi2 > 0 ? s.chi2 / a.chi2 : 0.0;
    if (!fac.levels.empty()) {
      std::map<std::string, std::pair<double, int>> g;
      for (Eigen::Index i = 0; i < n; ++i) {
        auto& e = g[fac.levels[static_cast<size_t>(i)]];
        e.first += raw[i];
        ++e.second;
      }
      double worst = 0.0;
      for (const auto& [level, v] : g) {
        const double mean = v.first / v.second;
        if (std::abs(mean) >= std::abs(worst)) {
          worst = mean;
          s.detail = fmt::format("largest mean residual {:+.3g} {} at {} = {} ({} observations)", mean, cx.pb.unit,
                                 fac.name, level, v.second);
        }
      }
    } else {
      const Eigen::VectorXd fit = cx.raw(pr.A * z);
      s.detail = fmt::format("a quadratic in {} ({} to {} {}) carries a misfit from {:+.3g} to {:+.3g} {}", fac.name,
                             fmtg(*std::min_element(fac.values.begin(), fac.values.end())),
                             fmtg(*std::max_element(fac.values.begin(), fac.values.end())), fac.unit, fit.minCoeff(),
                             fit.maxCoeff(), cx.pb.unit);
    }
    a.factors.push_back(s);
  }
  std::stable_sort(a.factors.begin(), a.factors.end(), [](const JudgeFactorShare& x, const JudgeFactorShare& y) {
    if (x.dof == 0 || y.dof == 0) return x.dof > y.dof;
    return x.p_value < y.p_value || (x.p_value == y.p_value && x.share > y.share);
  });
  return a;
}

/// Estimates of a whitened, named model's parameters: minimum-norm least squares; a parameter
/// is identifiable when it has no component in X's null space.
std::vector<JudgeEstimate> estimates(const Context& cx, const Eigen::MatrixXd& X, const Span& sx,
                                     const std::vector<JudgeParameter>& names, double u_scale) {
  const Eigen::VectorXd z = sx.Q.transpose() * cx.yw;
  const Eigen::VectorXd b = sx.coef * z;
  std::vector<JudgeEstimate> out;
  const Eigen::VectorXd norm = X.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < X.cols(); ++j) {
    JudgeEstimate e;
    e.name = names[static_cast<size_t>(j)].name;
    e.unit = names[static_cast<size_t>(j)].unit;
    e.value = b[j];
    // Null-space component of the unit vector e_j, in the normalised coordinates of spanOf.
    e.identifiable = norm[j] > 0 && (sx.null.cols() == 0 || sx.null.row(j).norm() < 1e-6);
    e.u = e.identifiable ? u_scale * sx.coef.row(j).norm() : std::numeric_limits<double>::quiet_NaN();
    out.push_back(e);
  }
  return out;
}

/// Names the terms of a combination (coefficients on named columns of whitened X), scaled by
/// `scale`, keeping the terms that move the data by at least kTermShare of the largest.
// The scale that gives the cause's leading term (coefficients `a`, weighted by the norms of its
// whitened columns `Jw`) the coefficient 1.
double leadScale(const Eigen::VectorXd& a, const Eigen::MatrixXd& Jw) {
  const Eigen::VectorXd contrib = a.cwiseAbs().cwiseProduct(Jw.colwise().norm().transpose());
  Eigen::Index lead = 0;
  contrib.maxCoeff(&lead);
  return a[lead] != 0 ? 1.0 / a[lead] : 1.0;
}

std::vector<JudgeTerm> terms(const Eigen::VectorXd& coef, const Eigen::MatrixXd& X, const std::vector<JudgeParameter>& names,
                             double scale) {
  std::vector<JudgeTerm> out;
  if (coef.size() == 0) return out;
  const Eigen::VectorXd contrib = coef.cwiseAbs().cwiseProduct(X.colwise().norm().transpose());
  const double top = contrib.maxCoeff();
  std::vector<Eigen::Index> order(static_cast<size_t>(coef.size()));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return contrib[a] > contrib[b]; });
  for (Eigen::Index j : order)
    if (contrib[j] >= kTermShare * top && contrib[j] > 0)
      out.push_back({names[static_cast<size_t>(j)].name, coef[j] * scale, names[static_cast<size_t>(j)].unit});
  return out;
}

/// The stem and number of a parameter named like offset_target14 (number -1 when none).
std::pair<std::string, int> stemAndNumber(const std::string& name) {
  size_t k = name.size();
  while (k > 0 && name[k - 1] >= '0' && name[k - 1] <= '9') --k;
  if (k == name.size() || k == 0 || name.size() - k > 6) return {name, -1};
  return {name.substr(0, k), std::stoi(name.substr(k))};
}

// Beyond this many members of one family (a model's per-point offsets, offset_target1..28) a
// sentence names the family once: a line of 28 names and coefficients says less than its range.
constexpr size_t kFamilyListed = 3;

/// Names, a family of more than kFamilyListed numbered ones as "stem1..28 (28 parameters)".
std::string namesText(const std::vector<std::string>& names) {
  std::map<std::string, std::vector<int>> family;
  for (const auto& n : names)
    if (const auto [stem, k] = stemAndNumber(n); k >= 0) family[stem].push_back(k);
  std::vector<std::string> out;
  std::set<std::string> done;
  for (const auto& n : names) {
    const auto [stem, k] = stemAndNumber(n);
    if (k < 0 || family[stem].size() <= kFamilyListed) {
      out.push_back(n);
      continue;
    }
    if (!done.insert(stem).second) continue;
    auto& ks = family[stem];
    std::sort(ks.begin(), ks.end());
    out.push_back(fmt::format("{}{}..{} ({} parameters)", stem, ks.front(), ks.back(), ks.size()));
  }
  return fmt::format("{}", fmt::join(out, ", "));
}

std::string termsText(const std::vector<JudgeTerm>& t) {
  std::map<std::string, size_t> family;
  for (const auto& x : t)
    if (const auto [stem, k] = stemAndNumber(x.name); k >= 0) ++family[stem];
  std::string s;
  std::map<std::string, std::vector<const JudgeTerm*>> grouped;
  std::set<std::string> done;
  for (const auto& x : t)
    if (const auto [stem, k] = stemAndNumber(x.name); k >= 0 && family[stem] > kFamilyListed) grouped[stem].push_back(&x);
  for (const auto& x : t) {
    const auto [stem, k] = stemAndNumber(x.name);
    if (k >= 0 && family[stem] > kFamilyListed) {
      if (!done.insert(stem).second) continue;
      // The family by its range of coefficients: what each of its members takes.
      double lo = 1e300, hi = -1e300;
      for (const JudgeTerm* g : grouped[stem]) lo = std::min(lo, g->coefficient), hi = std::max(hi, g->coefficient);
      s += (s.empty() ? "" : ", ") +
           fmt::format("{} of {} from {:.4g} to {:.4g} {}", grouped[stem].size(), stem, lo, hi, x.unit);
      continue;
    }
    s += (s.empty() ? "" : ", ") + fmt::format("{} = {:.4g} {}", x.name, x.coefficient, x.unit);
  }
  return s.empty() ? "nothing" : s;
}

/// The current model: whitened columns with names, their span and its held-out errors.
struct Model {
  Eigen::MatrixXd X;
  std::vector<JudgeParameter> names;
  Span span;
  Eigen::VectorXd r;
  double chi2 = 0.0;
  int dof = 0;
  Holdout ho;
};

void refresh(const Context& cx, Model* m) {
  m->span = spanOf(m->X);
  m->r = cx.yw - m->span.Q * (m->span.Q.transpose() * cx.yw);
  m->chi2 = m->r.squaredNorm();
  m->dof = static_cast<int>(cx.yw.size()) - m->span.rank();
  m->ho = holdout(m->span.Q, cx.yw, cx.sigma, cx.members);
}

struct Evaluated {
  JudgeCandidate c;
  Principal pr;
  Span sc;
  Eigen::MatrixXd Jw;  // whitened columns
  bool eligible = true;  // no exact confounding with the model
  bool passes() const { return c.test_passes && c.holdout_passes; }
};

Evaluated evaluate(const Context& cx, const Model& m, size_t ci, int step) {
  const JudgeCause& cause = cx.pb.causes[ci];
  Evaluated ev;
  ev.c.cause = cause.name;
  ev.c.step = step;
  ev.c.k = static_cast<int>(cause.J.cols());
  ev.c.threshold = cx.thr;
  ev.Jw = cx.whiten(cause.J);
  ev.sc = spanOf(ev.Jw);
  ev.pr = principal(m.span.Q, ev.sc.Q, cx.exact_rad);
  ev.c.k_eff = static_cast<int>(ev.pr.A.cols());
  ev.c.angle_deg = ev.pr.angle.size() ? deg(ev.pr.angle.minCoeff()) : 0.0;
  ev.c.separability = ev.pr.angle.size() ? std::sin(ev.pr.angle.minCoeff()) : 0.0;
  ev.eligible = ev.sc.rank() == ev.c.k && ev.c.k_eff == ev.c.k;
  if (ev.c.k_eff == 0) {
    ev.c.reason = ev.sc.rank() == 0 ? "no signal on this plan (its columns are zero)"
                                    : "not testable: every direction it moves the data in is the model's";
    return ev;
  }
  const Eigen::VectorXd z = ev.pr.A.transpose() * m.r;
  ev.c.delta_chi2 = z.squaredNorm();
  ev.c.p_chi2 = chiSquareSurvival(ev.c.delta_chi2, ev.c.k_eff);
  const int dof_ext = m.dof - ev.c.k_eff;
  if (dof_ext > 0) {
    const double chi2_ext = std::max(m.chi2 - ev.c.delta_chi2, 0.0);
    ev.c.f = chi2_ext > 0 ? (ev.c.delta_chi2 / ev.c.k_eff) / (chi2_ext / dof_ext) : std::numeric_limits<double>::infinity();
    ev.c.p_f = fSurvival(ev.c.f, ev.c.k_eff, dof_ext);
  } else {
    ev.c.f = 0.0;
    ev.c.p_f = 1.0;  // no residual left to measure the noise by: the F form cannot pass
  }
  ev.c.p_value = std::max(ev.c.p_chi2, ev.c.p_f);
  ev.c.test_passes = ev.c.p_value < cx.thr;

  Eigen::MatrixXd Qe(m.span.Q.rows(), m.span.Q.cols() + ev.pr.A.cols());
  Qe << m.span.Q, ev.pr.A;
  const Holdout he = holdout(Qe, cx.yw, cx.sigma, cx.members);
  std::vector<char> use(he.valid.size());
  std::vector<double> d;
  for (size_t g = 0; g < use.size(); ++g) {
    use[g] = he.valid[g] && m.ho.valid[g];
    if (use[g]) d.push_back(m.ho.ss[g] - he.ss[g]);
  }
  ev.c.folds = static_cast<int>(d.size());
  ev.c.holdout_rms_model = holdoutRms(m.ho, use);
  ev.c.holdout_rms_cause = holdoutRms(he, use);
  if (ev.c.folds >= kMinFolds) {
    const double G = static_cast<double>(d.size());
    const double mean = std::accumulate(d.begin(), d.end(), 0.0) / G;
    double var = 0.0;
    for (double x : d) var += (x - mean) * (x - mean);
    var /= (G - 1.0);
    ev.c.gain = mean;
    ev.c.gain_se = std::sqrt(var / G);
    ev.c.holdout_passes = mean > 0 && mean > cx.o.holdout_margin * ev.c.gain_se;
  }
  if (!ev.c.test_passes)
    ev.c.reason = fmt::format("residual drop within the declared noise (Delta chi2 {:.1f} on {} dof, p {:.2g} >= {:.2g})",
                              ev.c.delta_chi2, ev.c.k_eff, ev.c.p_value, cx.thr);
  else if (ev.c.folds < kMinFolds)
    ev.c.reason = fmt::format("only {} held-out folds usable: no standard error for the gain", ev.c.folds);
  else if (!ev.c.holdout_passes)
    ev.c.reason = fmt::format("held-out gain {:.3g} is not above {} standard errors ({:.3g})", ev.c.gain,
                              cx.o.holdout_margin, ev.c.gain_se);
  else
    ev.c.reason = "passes";
  return ev;
}

/// Whether cause `c` still passes the significance test (both forms, as in evaluate) once the
/// columns of `with` join the model: what `c` explains beyond `with`.
bool passesBeyond(const Context& cx, const Model& m, const Evaluated& with, const Evaluated& c) {
  Eigen::MatrixXd X(m.X.rows(), m.X.cols() + with.Jw.cols());
  X << m.X, with.Jw;
  const Span sx = spanOf(X);
  const Principal pr = principal(sx.Q, c.sc.Q, cx.exact_rad);
  const int k = static_cast<int>(pr.A.cols());
  if (k == 0) return false;
  const Eigen::VectorXd r = cx.yw - sx.Q * (sx.Q.transpose() * cx.yw);
  const double delta = (pr.A.transpose() * r).squaredNorm();
  const int dof_ext = static_cast<int>(cx.yw.size()) - sx.rank() - k;
  if (dof_ext <= 0) return false;
  const double chi2_ext = std::max(r.squaredNorm() - delta, 0.0);
  const double f = chi2_ext > 0 ? (delta / k) / (chi2_ext / dof_ext) : std::numeric_limits<double>::infinity();
  return std::max(chiSquareSurvival(delta, k), fSurvival(f, k, dof_ext)) < cx.thr;
}

// One entry per cause and partner; a later step's evaluation replaces an earlier one: the model
// has grown since, and `signal` must say whether the shared signal is still unexplained by the
// final model (a cause accepted later may have taken it), as the verdict does.
void addConfounded(std::vector<JudgeConfounded>* list, JudgeConfounded e) {
  for (auto& x : *list)
    if (x.cause == e.cause && x.with_model == e.with_model && (x.with_model || x.with == e.with)) {
      x = std::move(e);
      return;
    }
  list->push_back(std::move(e));
}

/// Exact confounding of a cause with the model: its smallest-angle direction, named.
JudgeConfounded modelConfounded(const Context& cx, const Model& m, const Evaluated& ev, size_t ci) {
  const JudgeCause& cause = cx.pb.causes[ci];
  JudgeConfounded e;
  e.cause = cause.name;
  e.with_model = true;
  e.angle_deg = deg(ev.pr.angle[0]);
  const Eigen::VectorXd a = ev.sc.coef * ev.pr.V.col(0);  // cause coefficients
  const Eigen::VectorXd b = m.span.coef.cols() ? Eigen::VectorXd(m.span.coef * ev.pr.W.col(0))
                                               : Eigen::VectorXd::Zero(m.X.cols());
  const double scale = leadScale(a, ev.Jw);
  e.cause_terms = terms(a, ev.Jw, cause.parameters, scale);
  e.with_terms = terms(b, m.X, m.names, scale);
  for (const auto& t : e.with_terms) e.with.push_back(t.name);
  if (ev.sc.rank() < ev.c.k) {
    e.why = fmt::format("{}'s own columns are dependent on this plan", cause.name);
    return e;
  }
  e.why = fmt::format("on this plan {} moves the data exactly as the model's {} do (principal angle {:.2g} deg): {} is "
                      "read as {}",
                      cause.name, namesText(e.with), e.angle_deg, termsText(e.cause_terms), termsText(e.with_terms));
  // Every other direction of the cause the model absorbs as exactly: each is an error the data
  // cannot show and the model's parameters take in full (lobing +X/-X read as dx_AY, say).
  for (Eigen::Index d = 1; d < ev.pr.angle.size() && d < ev.pr.V.cols() && ev.pr.angle[d] < cx.exact_rad; ++d) {
    const Eigen::VectorXd ad = ev.sc.coef * ev.pr.V.col(d);
    const Eigen::VectorXd bd = m.span.coef.cols() ? Eigen::VectorXd(m.span.coef * ev.pr.W.col(d))
                                                  : Eigen::VectorXd::Zero(m.X.cols());
    const Eigen::VectorXd cd = ad.cwiseAbs().cwiseProduct(ev.Jw.colwise().norm().transpose());
    Eigen::Index ld = 0;
    cd.maxCoeff(&ld);
    const double sd = ad[ld] != 0 ? 1.0 / ad[ld] : 1.0;
    const auto wt = terms(bd, m.X, m.names, sd);
    for (const auto& t : wt)
      if (std::find(e.with.begin(), e.with.end(), t.name) == e.with.end()) e.with.push_back(t.name);
    e.why += fmt::format("; and {} is read as {}", termsText(terms(ad, ev.Jw, cause.parameters, sd)), termsText(wt));
  }
  return e;
}

/// Smallest principal angle between two causes once the model is projected out.
struct PairAngle {
  double angle = kPi / 2;
  Eigen::VectorXd u, v;  // coordinates in each cause's A
};

PairAngle pairAngle(const Evaluated& a, const Evaluated& b) {
  PairAngle p;
  if (a.pr.A.cols() == 0 || b.pr.A.cols() == 0) return p;
  const Eigen::MatrixXd M = a.pr.A.transpose() * b.pr.A;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd vb = svd.matrixV().col(0);
  const Eigen::VectorXd ua = M * vb;  // = s0 u0
  const double sn = (b.pr.A * vb - a.pr.A * ua).norm();
  p.angle = std::atan2(sn, ua.norm());
  p.u = svd.matrixU().col(0);
  p.v = vb;
  return p;
}

JudgeConfounded pairConfounded(const Context& cx, const Evaluated& a, size_t ia, const Evaluated& b, size_t ib,
                               const PairAngle& p) {
  const JudgeCause& ca = cx.pb.causes[ia];
  const JudgeCause& cb = cx.pb.causes[ib];
  JudgeConfounded e;
  e.cause = ca.name;
  e.with = {cb.name};
  e.with_model = false;
  e.angle_deg = deg(p.angle);
  // A coordinates -> Qc coordinates -> the cause's own coefficients. A_a u ~ A_b v (cos ~ 1).
  const Eigen::VectorXd ka = a.sc.coef * (a.pr.Acoord * p.u);
  const Eigen::VectorXd kb = b.sc.coef * (b.pr.Acoord * p.v);
  const double scale = leadScale(ka, a.Jw);
  e.cause_terms = terms(ka, a.Jw, ca.parameters, scale);
  e.with_terms = terms(kb, b.Jw, cb.parameters, scale);
  e.why = fmt::format("beyond the model, {} and {} move the data alike on this plan (principal angle {:.2g} deg): {} "
                      "is read as {}",
                      ca.name, cb.name, e.angle_deg, termsText(e.cause_terms), termsText(e.with_terms));
  return e;
}

void validateProblem(const JudgeProblem& pb) {
  const Eigen::Index n = pb.y.size();
  if (n == 0) bad("no observations");
  if (pb.covariance.size()) {
    if (pb.covariance.rows() != n || pb.covariance.cols() != n)
      bad(fmt::format("covariance: expected {} x {}, got {} x {}", n, n, pb.covariance.rows(), pb.covariance.cols()));
    if (!pb.covariance.allFinite()) bad("covariance has a non-finite entry");
    for (Eigen::Index i = 0; i < n; ++i)
      if (!(pb.covariance(i, i) > 0)) bad(fmt::format("covariance({0}, {0}) = {1} must be > 0", i, pb.covariance(i, i)));
    if (pb.null_draws.size() && pb.null_draws.rows() != n)
      bad(fmt::format("null_draws: expected {} rows, got {}", n, pb.null_draws.rows()));
    if (!pb.null_draws.allFinite()) bad("null_draws has a non-finite entry");
  } else {
    if (pb.null_draws.size()) bad("null_draws without a covariance: draws are read through its whitening");
    if (pb.sigma.size() != n) bad(fmt::format("sigma: expected {} entries, got {}", n, pb.sigma.size()));
    for (Eigen::Index i = 0; i < n; ++i)
      if (!(pb.sigma[i] > 0) || !std::isfinite(pb.sigma[i]))
        bad(fmt::format("sigma[{}] = {} must be > 0 and finite", i, pb.sigma[i]));
  }
  if (!pb.y.allFinite()) bad("y has a non-finite entry");
  if (pb.J0.rows() != n) bad(fmt::format("J0: expected {} rows, got {}", n, pb.J0.rows()));
  if (!pb.J0.allFinite()) bad("J0 has a non-finite entry");
  if (pb.baseline_parameters.size() != static_cast<size_t>(pb.J0.cols()))
    bad(fmt::format("baseline_parameters: expected {} names (J0's columns), got {}", pb.J0.cols(),
                    pb.baseline_parameters.size()));
  std::set<std::string> names;
  for (const auto& c : pb.causes) {
    if (c.name.empty()) bad("a cause without a name");
    if (!names.insert(c.name).second) bad("cause '" + c.name + "' given twice");
    if (c.J.rows() != n) bad(fmt::format("cause '{}': expected {} rows, got {}", c.name, n, c.J.rows()));
    if (c.J.cols() == 0) bad(fmt::format("cause '{}' has no parameters", c.name));
    if (!c.J.allFinite()) bad(fmt::format("cause '{}' has a non-finite Jacobian entry", c.name));
    if (c.parameters.size() != static_cast<size_t>(c.J.cols()))
      bad(fmt::format("cause '{}': expected {} parameter names, got {}", c.name, c.J.cols(), c.parameters.size()));
  }
  if (!pb.groups.empty() && pb.groups.size() != static_cast<size_t>(n))
    bad(fmt::format("groups: expected {} labels, got {}", n, pb.groups.size()));
  for (const auto& f : pb.factors) {
    if (f.levels.empty() == f.values.empty())
      bad(fmt::format("factor '{}': give either levels or values", f.name));
    const size_t sz = f.levels.empty() ? f.values.size() : f.levels.size();
    if (sz != static_cast<size_t>(n)) bad(fmt::format("factor '{}': expected {} labels, got {}", f.name, n, sz));
    for (double v : f.values)
      if (!std::isfinite(v)) bad(fmt::format("factor '{}' has a non-finite value", f.name));
  }
}

std::string adequacyClause(const JudgeAdequacy& a) {
  if (a.null_draws == 0) return fmt::format("chi2 {:.1f} on {} dof, p {:.2g}", a.chi2, a.dof, a.p_value);
  return fmt::format("chi2 {:.1f} on {} dof, p {:.2g} against {:.3f} x chi2({:.1f}) from {} draws of the declared machine",
                     a.chi2, a.dof, a.p_value, a.null_scale, a.null_dof, a.null_draws);
}

}  // namespace

bool JudgeOptions::validate(std::string* why) const {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (!(alpha > 0 && alpha < 0.5)) return fail(fmt::format("alpha = {} must be in (0, 0.5)", alpha));
  if (!(holdout_margin >= 0) || !std::isfinite(holdout_margin))
    return fail(fmt::format("holdout_margin = {} must be >= 0 and finite", holdout_margin));
  if (!(exact_angle_deg > 0 && exact_angle_deg < partial_angle_deg))
    return fail(fmt::format("exact_angle_deg = {} must be > 0 and below partial_angle_deg = {}", exact_angle_deg,
                            partial_angle_deg));
  if (!(partial_angle_deg < 90)) return fail(fmt::format("partial_angle_deg = {} must be below 90", partial_angle_deg));
  if (max_causes < 1) return fail(fmt::format("max_causes = {} must be >= 1", max_causes));
  return true;
}

const char* judgeVerdictName(JudgeVerdict v) {
  switch (v) {
    case JudgeVerdict::EffectFound: return "effect_found";
    case JudgeVerdict::ModelInadequate: return "model_inadequate";
    case JudgeVerdict::NoSignificantEffect: return "no_significant_effect";
  }
  return "?";
}

const JudgeEstimate* JudgeFinding::parameter(std::string_view name) const {
  for (const auto& p : parameters)
    if (p.name == name) return &p;
  return nullptr;
}

std::string JudgeFinding::label() const {
  std::string l = cause;
  for (const auto& c : confounded_with) l += " or " + c;
  return l;
}

const JudgeFinding* JudgeSummary::finding(std::string_view cause) const {
  for (const auto& f : findings)
    if (f.cause == cause) return &f;
  return nullptr;
}

JudgeSummary judge(const JudgeProblem& pb, const JudgeOptions& o) {
  requireValid(o, "judge options");
  validateProblem(pb);
  const Eigen::Index n = pb.y.size();
  const size_t m_causes = pb.causes.size();

  Context cx{pb, o, {}, {}, {}, {}, {}, {}, {}, {}, 0, 0, 0};
  if (pb.covariance.size()) {
    cx.sigma = pb.covariance.diagonal().cwiseSqrt();
    squareRoots(pb.covariance, &cx.W, &cx.W_inv);
    if (pb.null_draws.cols() >= kMinNullDraws) cx.null_w = cx.W * pb.null_draws;
  } else {
    cx.sigma = pb.sigma;
  }
  cx.inv_sigma = cx.sigma.cwiseInverse();
  cx.yw = cx.whiten(pb.y);
  cx.exact_rad = o.exact_angle_deg * kPi / 180.0;
  cx.partial_rad = o.partial_angle_deg * kPi / 180.0;
  cx.thr = o.alpha / static_cast<double>(m_causes + 1);
  {
    std::map<int, size_t> gi;
    for (Eigen::Index i = 0; i < n; ++i) {
      const int g = pb.groups.empty() ? static_cast<int>(i) : pb.groups[static_cast<size_t>(i)];
      auto it = gi.emplace(g, cx.members.size()).first;
      if (it->second == cx.members.size()) cx.members.emplace_back();
      cx.members[it->second].push_back(static_cast<int>(i));
    }
  }
  for (const auto& f : pb.factors) cx.factor_cols.push_back(cx.whiten(factorColumns(f, Eigen::VectorXd::Ones(n))));

  JudgeSummary s;
  s.unit = pb.unit;
  s.group_name = pb.group_name;
  s.observations = static_cast<int>(n);
  s.groups = static_cast<int>(cx.members.size());
  s.candidates = static_cast<int>(m_causes);
  s.alpha = o.alpha;
  s.per_test_alpha = cx.thr;
  s.holdout_margin = o.holdout_margin;
  s.exact_angle_deg = o.exact_angle_deg;
  s.partial_angle_deg = o.partial_angle_deg;
  s.declared_sigma_rms = std::sqrt(cx.sigma.squaredNorm() / static_cast<double>(n));
  s.declaration = pb.declaration;
  s.correlated = pb.covariance.size() > 0;

  Model model;
  model.X = cx.whiten(pb.J0);
  model.names = pb.baseline_parameters;
  if (cx.W.size()) {
    // The held-out errors in y's unit: sqrt(diag) would scale them by what the model absorbs (a
    // set-up of 120 um), so every observation takes the declared scatter the baseline leaves.
    const double left = declaredResidualRms(cx, spanOf(model.X));
    cx.sigma = Eigen::VectorXd::Constant(n, left > 0 ? left : std::sqrt(pb.covariance.diagonal().mean()));
  }
  refresh(cx, &model);
  s.baseline_rank = model.span.rank();
  // With shared errors, sqrt(diag Sigma) counts what the model absorbs (a set-up of 120 um in Z);
  // the figure beside the residual is the declared scatter the model leaves in it.
  if (cx.W.size()) s.declared_sigma_rms = declaredResidualRms(cx, model.span);
  s.baseline = adequacy(cx, model.span);
  s.baseline_holdout_rms = holdoutRms(model.ho, model.ho.valid);
  s.baseline_estimates = estimates(cx, model.X, model.span, model.names, 1.0);
  for (const auto& e : s.baseline_estimates)
    if (!e.identifiable) s.unidentifiable.push_back(e.name);

  std::vector<char> used(m_causes, 0);
  std::vector<size_t> accepted;
  std::vector<JudgeCandidate> accepted_tests;
  std::vector<std::vector<std::string>> accepted_partners;
  std::vector<std::vector<JudgeConfounded>> accepted_carried;
  bool unresolved = false;
  std::vector<std::string> unresolved_causes;
  for (int step = 0;; ++step) {
    std::vector<Evaluated> ev(m_causes);
    std::vector<size_t> live;
    for (size_t c = 0; c < m_causes; ++c)
      if (!used[c]) {
        ev[c] = evaluate(cx, model, c, step);
        live.push_back(c);
      }
    if (live.empty()) break;
    // Exact confounding with the model: named, never accepted.
    std::vector<char> blocked(m_causes, 0), ambiguous(m_causes, 0);
    unresolved = false;
    unresolved_causes.clear();
    for (size_t c : live)
      if (!ev[c].eligible) {
        blocked[c] = 1;
        JudgeConfounded e = modelConfounded(cx, model, ev[c], c);
        e.signal = ev[c].passes();
        if (e.signal) {
          unresolved = true;
          unresolved_causes.push_back(pb.causes[c].name);
        }
        addConfounded(&s.confounded, e);
        if (ev[c].passes())
          ev[c].c.reason = "its identifiable part passes, but its parameters are not identifiable on this plan";
        else if (ev[c].c.reason == "passes")
          ev[c].c.reason = "confounded with the model";
      }
    // Partial confounding with the model: what the cause is partly read as.
    for (size_t c : live)
      if (ev[c].eligible && ev[c].c.k_eff > 0 && ev[c].pr.angle.minCoeff() < cx.partial_rad)
        for (const auto& t : modelConfounded(cx, model, ev[c], c).with_terms) ev[c].c.overlaps.push_back(t.name);
    // Between causes, with the model projected out.
    struct Pair {
      size_t a, b;
      double angle;
    };
    std::vector<Pair> pairs;
    std::vector<std::pair<Pair, JudgeConfounded>> shared;  // exactly confounded, both passing
    for (size_t i = 0; i < live.size(); ++i)
      for (size_t j = i + 1; j < live.size(); ++j) {
        const size_t a = live[i], b = live[j];
        const PairAngle p = pairAngle(ev[a], ev[b]);
        pairs.push_back({a, b, p.angle});
        if (p.angle >= cx.exact_rad) continue;
        JudgeConfounded e = pairConfounded(cx, ev[a], a, ev[b], b, p);
        e.signal = ev[a].passes() && ev[b].passes();
        if (e.signal) {
          ambiguous[a] = ambiguous[b] = 1;
          shared.push_back({pairs.back(), e});
        }
        addConfounded(&s.confounded, e);
      }
    // A significant signal along causes the plan cannot tell apart is one finding: the cause with
    // the largest held-out gain stands for the causes it is exactly confounded with (its
    // partners), which are not candidates of their own at this step. A partner is named only when
    // it explains the signal as well: with the partner in the model, nothing of the cause passes
    // (an X scale is not "scale or frame temperature" because its isotropic part is; such a pair
    // stays withheld). Causes confounded with the model itself (blocked) stand for nothing.
    std::vector<int> rep(m_causes, -1);  // an ambiguous cause's representative (itself for one)
    {
      std::vector<size_t> order;
      for (size_t c : live)
        if (ambiguous[c] && !blocked[c]) order.push_back(c);
      std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) { return ev[x].c.gain > ev[y].c.gain; });
      for (size_t c : order) {
        if (rep[c] >= 0) continue;
        std::vector<size_t> partners;
        bool all = true;
        for (const auto& pe : shared) {
          const Pair& p = pe.first;
          const size_t other = p.a == c ? p.b : p.b == c ? p.a : m_causes;
          if (other == m_causes) continue;
          all = all && rep[other] < 0 && !blocked[other] && !passesBeyond(cx, model, ev[other], ev[c]);
          partners.push_back(other);
        }
        if (!all) continue;
        rep[c] = static_cast<int>(c);
        for (size_t other : partners) rep[other] = static_cast<int>(c);
      }
    }
    auto oneFinding = [&](size_t a, size_t b) { return rep[a] >= 0 && rep[a] == rep[b]; };
    // Separability and overlaps count the passing causes a finding does not name.
    for (const Pair& p : pairs) {
      if (oneFinding(p.a, p.b)) continue;
      const double sn = std::sin(p.angle);
      if (ev[p.b].passes()) ev[p.a].c.separability = std::min(ev[p.a].c.separability, sn);
      if (ev[p.a].passes()) ev[p.b].c.separability = std::min(ev[p.b].c.separability, sn);
      if (p.angle < cx.partial_rad && ev[p.b].passes()) ev[p.a].c.overlaps.push_back(pb.causes[p.b].name);
      if (p.angle < cx.partial_rad && ev[p.a].passes()) ev[p.b].c.overlaps.push_back(pb.causes[p.a].name);
    }
    for (const auto& [p, e] : shared) {
      const size_t r = rep[p.a] >= 0 && rep[p.a] == rep[p.b] ? static_cast<size_t>(rep[p.a]) : m_causes;
      for (const size_t c : {p.a, p.b}) {
        const size_t other = c == p.a ? p.b : p.a;
        if (r < m_causes && c != r)
          ev[c].c.reason = "passes, but " + pb.causes[r].name + " explains the same signal (this plan cannot tell them "
                           "apart: named in its finding)";
        else if (r == m_causes)
          ev[c].c.reason = "passes, but " + pb.causes[other].name + " explains the same signal";
      }
    }
    auto candidate = [&](size_t c) {
      return ev[c].passes() && !blocked[c] && (!ambiguous[c] || rep[c] == static_cast<int>(c));
    };
    // The best eligible cause by held-out gain.
    int best = -1;
    for (size_t c : live)
      if (candidate(c) && (best < 0 || ev[c].c.gain > ev[static_cast<size_t>(best)].c.gain)) best = static_cast<int>(c);
    const bool full = static_cast<int>(accepted.size()) >= o.max_causes;
    for (size_t c : live) {
      if (full && candidate(c))
        ev[c].c.reason = fmt::format("passes, but max_causes = {} are already accepted", o.max_causes);
      else if (!full && best >= 0 && c != static_cast<size_t>(best) && candidate(c))
        ev[c].c.reason = "passes, but " + pb.causes[static_cast<size_t>(best)].name + " predicts held-out data better";
    }
    // A shared signal the accepted cause's finding does not carry is left unresolved.
    const int taken = full ? -1 : best;
    std::vector<JudgeConfounded> carried;
    std::vector<std::string> partners;
    for (auto& [p, e] : shared) {
      if (taken >= 0 && rep[p.a] == taken && rep[p.b] == taken &&
          (p.a == static_cast<size_t>(taken) || p.b == static_cast<size_t>(taken))) {
        e.signal = false;
        e.finding = pb.causes[static_cast<size_t>(taken)].name;
        partners.push_back(pb.causes[p.a == static_cast<size_t>(taken) ? p.b : p.a].name);
        addConfounded(&s.confounded, e);
        carried.push_back(e);
        continue;
      }
      if (taken >= 0 && rep[p.a] == taken && rep[p.b] == taken) {  // two of the finding's partners
        e.signal = false;
        e.finding = pb.causes[static_cast<size_t>(taken)].name;
        addConfounded(&s.confounded, e);
        continue;
      }
      unresolved = true;
      unresolved_causes.push_back(pb.causes[p.a].name + " or " + pb.causes[p.b].name);
    }
    if (full || best < 0) {
      for (size_t c : live) s.candidate_tests.push_back(ev[c].c);
      break;
    }
    const size_t b = static_cast<size_t>(best);
    ev[b].c.accepted = true;
    ev[b].c.reason = "accepted";
    for (size_t c : live) s.candidate_tests.push_back(ev[c].c);
    accepted.push_back(b);
    accepted_tests.push_back(ev[b].c);
    accepted_partners.push_back(partners);
    accepted_carried.push_back(carried);
    used[b] = 1;
    const JudgeCause& cause = pb.causes[b];
    Eigen::MatrixXd X(n, model.X.cols() + cause.J.cols());
    X << model.X, ev[b].Jw;
    model.X = X;
    for (const auto& p : cause.parameters) model.names.push_back({cause.name + "." + p.name, p.unit});
    refresh(cx, &model);
  }

  s.final_model = accepted.empty() ? s.baseline : adequacy(cx, model.span);
  const double birge = s.final_model.passes || s.final_model.dof <= 0 ? 1.0 : std::sqrt(s.final_model.chi2 / s.final_model.dof);
  const auto all = estimates(cx, model.X, model.span, model.names, birge);
  s.final_estimates.assign(all.begin(), all.begin() + pb.J0.cols());
  size_t at = static_cast<size_t>(pb.J0.cols());
  for (size_t i = 0; i < accepted.size(); ++i) {
    const JudgeCause& cause = pb.causes[accepted[i]];
    const JudgeCandidate& t = accepted_tests[i];
    JudgeFinding f;
    f.cause = cause.name;
    f.description = cause.description;
    f.step = t.step;
    for (size_t k = 0; k < cause.parameters.size(); ++k) {
      JudgeEstimate e = all[at + k];
      e.name = cause.parameters[k].name;
      f.parameters.push_back(e);
    }
    at += cause.parameters.size();
    f.delta_chi2 = t.delta_chi2;
    f.p_value = t.p_value;
    f.holdout_rms_model = t.holdout_rms_model;
    f.holdout_rms_cause = t.holdout_rms_cause;
    f.gain = t.gain;
    f.gain_se = t.gain_se;
    f.separability = t.separability;
    f.overlaps = t.overlaps;
    f.confounded_with = accepted_partners[i];
    f.confounding = accepted_carried[i];
    const double partial_sin = std::sin(cx.partial_rad);
    const std::string partly =
        fmt::format("partly confounded with {} (separability {:.2f}, below sin {:g} deg = {:.2f}); its u is inflated up to "
                    "{:.1f}x by the overlap, and an error of those is partly read as this cause",
                    fmt::join(f.overlaps, ", "), f.separability, o.partial_angle_deg, partial_sin, 1.0 / f.separability);
    if (!f.confounded_with.empty()) {
      std::vector<std::string> whys;
      for (const auto& e : f.confounding) whys.push_back(e.why);
      f.confidence = fmt::format("one signal this plan cannot attribute: {} or {}; the parameters read it as {} ({})",
                                 f.cause, fmt::join(f.confounded_with, " or "), f.cause, fmt::join(whys, "; "));
      if (f.separability < partial_sin) f.confidence += "; and " + partly;
    } else {
      f.confidence = f.separability < partial_sin ? "lowered: " + partly : "full";
    }
    if (birge > 1.0)
      f.confidence += fmt::format("; u scaled by the Birge ratio {:.2f} (the final model misfits)", birge);
    s.findings.push_back(f);
  }

  // The verdict, and a sentence that is true whatever it is.
  const JudgeAdequacy& fin = s.final_model;
  std::vector<std::string> found;
  for (const auto& f : s.findings)
    found.push_back(f.confounded_with.empty() ? f.cause : f.label() + " (one signal: this plan cannot tell them apart)");
  auto where = [&](const JudgeAdequacy& a) {
    for (const auto& f : a.factors)
      if (f.dof > 0 && f.p_value < cx.thr)
        // "Most" only when it is most: a factor with a significant but small share is named as such.
        return fmt::format("; {} sits with {} ({:.0f} % of chi2: {})", f.share > 0.5 ? "most of it" : "a significant part",
                           f.factor, 100.0 * f.share, f.detail);
    return std::string("; no factor given carries it");
  };
  if (!fin.passes || unresolved) {
    s.verdict = JudgeVerdict::ModelInadequate;
    if (!fin.passes)
      s.message = fmt::format("the model does not explain the data: its residual exceeds the declared noise ({:.3g} {} "
                              "rms{}) by {:.3g} {} rms ({}){}",
                              s.declared_sigma_rms, pb.unit, pb.declaration.empty() ? "" : "; " + pb.declaration,
                              fin.excess_rms, pb.unit, adequacyClause(fin), where(fin));
    else
      s.message = fmt::format("the model passes the overall test ({}) but a targeted test finds a signal that this plan "
                              "cannot attribute",
                              adequacyClause(fin));
    if (!found.empty()) s.message += fmt::format("; found {}, which does not explain all of it", fmt::join(found, ", "));
    if (unresolved)
      s.message += fmt::format("; a significant signal is shared by {} (confounded: see below)",
                               fmt::join(unresolved_causes, "; "));
  } else if (!found.empty()) {
    s.verdict = JudgeVerdict::EffectFound;
    s.message = fmt::format("found {}; with it the model explains the data within the declared noise ({})",
                            fmt::join(found, ", "), adequacyClause(fin));
  } else {
    s.verdict = JudgeVerdict::NoSignificantEffect;
    // With shared contributors declared, what they leave in the residual (a linear axis's
    // squareness, a face's form) is the declaration's, not a cause: say which declaration it is.
    s.message = fmt::format("no catalogued cause passes; the model explains the data within the declared noise ({}){}",
                            adequacyClause(fin),
                            pb.declaration.empty() ? std::string()
                                                   : fmt::format(": consistent with what is declared ({})", pb.declaration));
  }
  return s;
}

namespace {

Json estimatesJson(const std::vector<JudgeEstimate>& es) {
  Json j = Json::object();
  for (const auto& e : es)
    j[e.name] = {{"value", e.value}, {"unit", e.unit}, {"u", e.identifiable ? Json(e.u) : Json(nullptr)},
                 {"identifiable", e.identifiable}};
  return j;
}

Json adequacyJson(const JudgeAdequacy& a) {
  Json f = Json::array();
  for (const auto& x : a.factors)
    f.push_back({{"factor", x.factor}, {"chi2", x.chi2}, {"dof", x.dof}, {"p_value", x.p_value}, {"share", x.share},
                 {"detail", x.detail}});
  return {{"chi2", a.chi2},           {"dof", a.dof},
          {"p_value", a.p_value},     {"threshold", a.threshold},
          {"passes", a.passes},       {"rms_residual", a.rms_residual},
          {"excess_rms", a.excess_rms}, {"null_draws", a.null_draws},
          {"null_scale", a.null_scale}, {"null_dof", a.null_dof},
          {"factors", f}};
}

Json termsJson(const std::vector<JudgeTerm>& t) {
  Json j = Json::array();
  for (const auto& x : t) j.push_back({{"parameter", x.name}, {"coefficient", x.coefficient}, {"unit", x.unit}});
  return j;
}

}  // namespace

Json confoundedJson(const JudgeSummary& s, const std::function<std::string(const JudgeConfounded&)>& separate_with) {
  Json out = Json::array();
  for (const auto& c : s.confounded) {
    std::vector<std::string> causes = {c.cause};
    causes.insert(causes.end(), c.with.begin(), c.with.end());
    out.push_back({{"causes", causes},
                   {"why", c.why},
                   {"separate_with", separate_with ? separate_with(c) : std::string()},
                   {"cause", c.cause},
                   {"with", c.with},
                   {"with_model", c.with_model},
                   {"angle_deg", c.angle_deg},
                   {"cause_terms", termsJson(c.cause_terms)},
                   {"with_terms", termsJson(c.with_terms)},
                   {"signal", c.signal}});
    if (!c.finding.empty()) out.back()["finding"] = c.finding;
  }
  return out;
}

std::string findingSeparateWith(const JudgeFinding& f,
                                const std::function<std::string(const JudgeConfounded&)>& separate_with) {
  std::vector<std::string> advice;
  if (separate_with)
    for (const auto& e : f.confounding) {
      const std::string a = separate_with(e);
      if (!a.empty() && std::find(advice.begin(), advice.end(), a) == advice.end()) advice.push_back(a);
    }
  return fmt::format("{}", fmt::join(advice, "; "));
}

void writeConfounded(Json& doc, const JudgeSummary& s,
                     const std::function<std::string(const JudgeConfounded&)>& separate_with) {
  doc["confounded"] = confoundedJson(s, separate_with);
  if (!doc.contains("findings") || !doc["findings"].is_array()) return;
  for (size_t k = 0; k < s.findings.size() && k < doc["findings"].size(); ++k) {
    const JudgeFinding& f = s.findings[k];
    if (f.confounded_with.empty()) continue;
    doc["findings"][k]["confounded_with"] = f.confounded_with;
    doc["findings"][k]["separate_with"] = findingSeparateWith(f, separate_with);
  }
}

Json judgeToJson(const JudgeSummary& s) {
  Json j;
  j["verdict"] = judgeVerdictName(s.verdict);
  j["message"] = s.message;
  j["explains_data"] = s.explainsData();
  j["unit"] = s.unit;
  j["rules"] = {{"alpha", s.alpha},
                {"per_test_alpha", s.per_test_alpha},
                {"holdout", fmt::format("leave one {} out ({} groups)", s.group_name, s.groups)},
                {"holdout_margin_se", s.holdout_margin},
                {"exact_angle_deg", s.exact_angle_deg},
                {"partial_angle_deg", s.partial_angle_deg}};
  j["observations"] = s.observations;
  j["declared_sigma_rms"] = s.declared_sigma_rms;
  if (!s.declaration.empty()) j["declaration"] = s.declaration;
  j["noise_correlated"] = s.correlated;
  j["baseline"] = {{"rank", s.baseline_rank},
                   {"adequacy", adequacyJson(s.baseline)},
                   {"holdout_rms", s.baseline_holdout_rms},
                   {"estimates", estimatesJson(s.baseline_estimates)},
                   {"unidentifiable", s.unidentifiable}};
  j["final_model"] = {{"adequacy", adequacyJson(s.final_model)}, {"estimates", estimatesJson(s.final_estimates)}};
  Json f = Json::array();
  for (const auto& x : s.findings) {
    f.push_back({{"cause", x.cause},
                 {"description", x.description},
                 {"step", x.step},
                 {"parameters", estimatesJson(x.parameters)},
                 {"delta_chi2", x.delta_chi2},
                 {"p_value", x.p_value},
                 {"holdout_rms_model", x.holdout_rms_model},
                 {"holdout_rms_cause", x.holdout_rms_cause},
                 {"gain", x.gain},
                 {"gain_se", x.gain_se},
                 {"separability", x.separability},
                 {"overlaps", x.overlaps},
                 {"confidence", x.confidence}});
    if (!x.confounded_with.empty()) {
      Json e = Json::array();
      for (const auto& c : x.confounding)
        e.push_back({{"cause", c.cause}, {"with", c.with}, {"angle_deg", c.angle_deg},
                     {"cause_terms", termsJson(c.cause_terms)}, {"with_terms", termsJson(c.with_terms)}, {"why", c.why}});
      f.back()["confounded_with"] = x.confounded_with;
      f.back()["confounding"] = e;
    }
  }
  j["findings"] = f;
  Json c = Json::array();
  for (const auto& x : s.candidate_tests)
    c.push_back({{"cause", x.cause},           {"step", x.step},
                 {"k", x.k},                   {"k_eff", x.k_eff},
                 {"delta_chi2", x.delta_chi2}, {"p_chi2", x.p_chi2},
                 {"f", x.f},                   {"p_f", x.p_f},
                 {"p_value", x.p_value},       {"threshold", x.threshold},
                 {"folds", x.folds},           {"holdout_rms_model", x.holdout_rms_model},
                 {"holdout_rms_cause", x.holdout_rms_cause}, {"gain", x.gain},
                 {"gain_se", x.gain_se},       {"angle_deg", x.angle_deg},
                 {"separability", x.separability}, {"overlaps", x.overlaps},
                 {"accepted", x.accepted},
                 {"reason", x.reason}});
  j["candidates"] = c;
  Json cf = Json::array();
  for (const auto& x : s.confounded)
    cf.push_back({{"cause", x.cause},
                  {"with", x.with},
                  {"with_model", x.with_model},
                  {"angle_deg", x.angle_deg},
                  {"cause_terms", termsJson(x.cause_terms)},
                  {"with_terms", termsJson(x.with_terms)},
                  {"signal", x.signal},
                  {"why", x.why}});
  for (size_t k = 0; k < s.confounded.size(); ++k)
    if (!s.confounded[k].finding.empty()) cf[k]["finding"] = s.confounded[k].finding;
  j["confounded"] = cf;
  return j;
}

std::string judgeText(const JudgeSummary& s, const std::function<std::string(const JudgeConfounded&)>& separate_with) {
  std::string t;
  t += fmt::format("verdict: {}: {}\n", judgeVerdictName(s.verdict), s.message);
  t += fmt::format("rules: alpha {:g} over {} tests (each at {:.3g}); held-out gain > {:g} SE, leave one {} out ({} "
                   "groups); exact confounding below {:g} deg, partial below {:g} deg\n",
                   s.alpha, s.candidates + 1, s.per_test_alpha, s.holdout_margin, s.group_name, s.groups,
                   s.exact_angle_deg, s.partial_angle_deg);
  auto adequacyText = [&](const char* name, const JudgeAdequacy& a) {
    t += fmt::format("{}: residual rms {:.3g} {} against declared {:.3g} {}; chi2 {:.1f} on {} dof, p {:.2g}: {}\n", name,
                     a.rms_residual, s.unit, s.declared_sigma_rms, s.unit, a.chi2, a.dof, a.p_value,
                     a.passes ? "within the declared noise"
                              : fmt::format("misfit beyond the noise {:.3g} {} rms", a.excess_rms, s.unit));
    for (const auto& f : a.factors)
      if (f.dof > 0)
        t += fmt::format("  {:<12} chi2 {:>9.1f} on {:>3} dof  p {:<9.2g} {:>4.0f} %  {}\n", f.factor, f.chi2, f.dof,
                         f.p_value, 100.0 * f.share, f.detail);
  };
  adequacyText("baseline", s.baseline);
  if (!s.unidentifiable.empty())
    t += fmt::format("  not identifiable from J0 (rank {}): {}\n", s.baseline_rank, fmt::join(s.unidentifiable, ", "));
  t += "candidate causes:\n";
  for (const auto& c : s.candidate_tests)
    t += fmt::format("  [{}] {:<22} k {}/{}  dchi2 {:>8.1f}  p {:<8.2g} held-out {:.3g} -> {:.3g} {} (gain {:.3g} +- {:.2g})  "
                     "angle {:.2g} deg: {}\n",
                     c.step, c.cause, c.k_eff, c.k, c.delta_chi2, c.p_value, c.holdout_rms_model, c.holdout_rms_cause,
                     s.unit, c.gain, c.gain_se, c.angle_deg, c.reason);
  for (const auto& f : s.findings) {
    if (f.confounded_with.empty()) {
      t += fmt::format("FOUND {}: {}\n", f.cause, f.description);
    } else {
      const std::string how = findingSeparateWith(f, separate_with);
      t += fmt::format("FOUND {}: the plan cannot tell them apart; {}\n  read as {}: {}\n", f.label(),
                       how.empty() ? "see the confounded entries below" : how, f.cause, f.description);
    }
    for (const auto& p : f.parameters) t += fmt::format("  {} = {:.4g} +- {:.2g} {}\n", p.name, p.value, p.u, p.unit);
    t += fmt::format("  confidence: {}\n", f.confidence);
  }
  if (!s.findings.empty()) adequacyText("with the findings", s.final_model);
  for (const auto& c : s.confounded)
    t += fmt::format("confounded{}: {}\n",
                     c.signal             ? " (with a significant signal)"
                     : c.finding.empty()  ? ""
                                          : " (its signal is the finding " + c.finding + ")",
                     c.why);
  return t;
}

}  // namespace rotacal
