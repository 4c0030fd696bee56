#include "core/declared_noise.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "core/contributor_draw.hpp"
#include "core/rng.hpp"
#include "core/statistics.hpp"

namespace rotacal {

namespace {

void requirePerRunIndex(const Eigen::MatrixXd& per_run, int i) {
  if (per_run.rows() != per_run.cols())
    throw std::invalid_argument(
        fmt::format("declared noise: the per-run part is {} x {}, not square", per_run.rows(), per_run.cols()));
  if (i < 0 || i >= per_run.rows())
    throw std::invalid_argument(fmt::format("declared noise: reading {} beyond the per-run part's {}", i, per_run.rows()));
}

/// The per-run part between the readings kept[] of one run (DeclaredNoise::covariance).
void addPerRun(const Eigen::MatrixXd& per_run_um2, const std::vector<std::pair<int, int>>& kept, Eigen::MatrixXd* C) {
  if (per_run_um2.size() == 0) return;
  const auto n = static_cast<Eigen::Index>(kept.size());
  for (Eigen::Index a = 0; a < n; ++a) {
    const auto& ka = kept[static_cast<size_t>(a)];
    requirePerRunIndex(per_run_um2, ka.second);
    for (Eigen::Index b = 0; b < n; ++b) {
      const auto& kb = kept[static_cast<size_t>(b)];
      if (kb.first == ka.first) (*C)(a, b) += per_run_um2(ka.second, kb.second);
    }
  }
}

/// The per-run part drawn afresh for each run of kept[] and each draw (DeclaredNoise::nullDraws).
void addPerRunDraws(const Eigen::MatrixXd& per_run_um2, const std::vector<std::pair<int, int>>& kept, std::uint64_t seed,
                    Eigen::MatrixXd* D) {
  if (per_run_um2.size() == 0 || D->cols() == 0) return;
  for (const auto& k : kept) requirePerRunIndex(per_run_um2, k.second);
  if (!per_run_um2.allFinite()) throw std::invalid_argument("declared noise: the per-run part has a non-finite entry");
  // Its symmetric root, negative rounding floored at 0: the part is singular (a zero reading
  // carries none of it, and one zero serves many readings), so no Cholesky factor.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (per_run_um2 + per_run_um2.transpose()));
  const Eigen::MatrixXd root =
      es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * es.eigenvectors().transpose();
  std::vector<int> runs;
  for (const auto& k : kept)
    if (std::find(runs.begin(), runs.end(), k.first) == runs.end()) runs.push_back(k.first);
  // A stream of its own: the white part's draws stay those of a declaration without this part.
  Rng rng(seed, 1);
  Eigen::VectorXd z(per_run_um2.rows());
  for (Eigen::Index d = 0; d < D->cols(); ++d)
    for (int run : runs) {
      for (Eigen::Index i = 0; i < z.size(); ++i) z[i] = rng.normal();
      const Eigen::VectorXd v = root * z;
      for (size_t a = 0; a < kept.size(); ++a)
        if (kept[a].first == run) (*D)(static_cast<Eigen::Index>(a), d) += v[kept[a].second];
    }
}

}  // namespace

Eigen::MatrixXd DeclaredNoise::covariance(const std::vector<std::pair<int, int>>& kept) const {
  const auto n = static_cast<Eigen::Index>(kept.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
  if (structured_um2.size() > 0) {
    for (Eigen::Index a = 0; a < n; ++a) {
      const int ia = kept[static_cast<size_t>(a)].second;
      if (ia < 0 || ia >= structured_um2.rows())
        throw std::invalid_argument(fmt::format("declared noise: reading {} beyond the plan's {}", ia, structured_um2.rows()));
      for (Eigen::Index b = 0; b < n; ++b) C(a, b) = structured_um2(ia, kept[static_cast<size_t>(b)].second);
    }
  }
  addPerRun(per_run_um2, kept, &C);
  C.diagonal().array() += white_um2;
  return C;
}

Eigen::MatrixXd DeclaredNoise::nullDraws(const std::vector<std::pair<int, int>>& kept, std::uint64_t seed) const {
  const auto n = static_cast<Eigen::Index>(kept.size());
  const Eigen::Index draws = structured_draws_um.cols();
  if (draws == 0) return Eigen::MatrixXd(n, 0);
  Eigen::MatrixXd D(n, draws);
  for (Eigen::Index a = 0; a < n; ++a) {
    const int ia = kept[static_cast<size_t>(a)].second;
    if (ia < 0 || ia >= structured_draws_um.rows())
      throw std::invalid_argument(fmt::format("declared noise: reading {} beyond the plan's {}", ia, structured_draws_um.rows()));
    D.row(a) = structured_draws_um.row(ia);
  }
  const double white = std::sqrt(white_um2);
  Rng rng(seed, 0);
  for (Eigen::Index d = 0; d < draws; ++d)
    for (Eigen::Index a = 0; a < n; ++a) D(a, d) += white * rng.normal();
  addPerRunDraws(per_run_um2, kept, seed, &D);
  return D;
}

double DeclaredNoise::rmsSigmaUm(int readings) const {
  if (readings <= 0) return std::sqrt(white_um2);
  double v = white_um2;
  for (const Eigen::MatrixXd* part : {&structured_um2, &per_run_um2})
    if (part->size() > 0) v += part->diagonal().head(std::min<Eigen::Index>(readings, part->rows())).mean();
  return std::sqrt(v);
}

DeclaredNoise repeatabilityOnly(double repeatability_um, const std::string& source) {
  DeclaredNoise d;
  d.white_um2 = repeatability_um * repeatability_um;
  d.declaration = fmt::format("declared: repeatability only ({:.3f} um, {})", repeatability_um, source);
  d.repeatability_only = true;
  return d;
}

DeclaredNoise perTouchDeclaration(const ContributorSet* declared, double machine_repeatability_um) {
  const Contributor* rep = declared ? declared->find("probe_repeatability") : nullptr;
  if (!rep) {
    DeclaredNoise d = repeatabilityOnly(machine_repeatability_um, "MACHINE.json probe.repeatability_um");
    if (declared)
      d.declaration = fmt::format("declared: repeatability only ({:.3f} um, MACHINE.json probe.repeatability_um; {} "
                                  "declares no probe_repeatability)",
                                  machine_repeatability_um, declared->file.empty() ? "the contributors" : declared->file);
    return d;
  }
  const double declared_um = rep->u[0] * 1000.0;
  if (std::abs(declared_um - machine_repeatability_um) > 0.01 * std::max(declared_um, machine_repeatability_um))
    throw std::invalid_argument(fmt::format(
        "contributors.probe_repeatability u = {:.4g} um contradicts MACHINE.json probe.repeatability_um = {:.4g} um "
        "(one quantity, two values: make them agree)",
        declared_um, machine_repeatability_um));
  DeclaredNoise d;
  std::string parts;
  for (const Contributor& c : declared->items) {
    if (c.info->kind != ContributorKind::ProbeRepeatability && c.info->kind != ContributorKind::SurfaceRoughness) continue;
    d.white_um2 += c.u[0] * c.u[0] * 1e6;
    parts += fmt::format("{}{} {:.3f} um", parts.empty() ? "" : " + ", c.info->id, c.u[0] * 1000.0);
  }
  const std::string from = declared->file.empty() ? "the machine's contributors" : declared->file;
  d.repeatability_only = std::none_of(declared->items.begin(), declared->items.end(), [](const Contributor& c) {
    return c.info->kind != ContributorKind::ProbeRepeatability && c.u.cwiseAbs().maxCoeff() > 0;
  });
  d.declaration = d.repeatability_only ? fmt::format("declared: repeatability only ({:.3f} um, {})", declared_um, from)
                                       : fmt::format("declared per touch: {} (from {})", parts, from);
  return d;
}

void addProbeAxesPart(const ContributorSet& declared, const std::vector<Eigen::Vector3d>& t,
                      const std::vector<Eigen::Vector3d>& u, const Eigen::VectorXd& scale, DeclaredNoise* noise) {
  const auto shared = [](const ContributorInfo& c) { return isProbeAxesContributor(c) && !isPerTouchContributor(c); };
  std::string ids;
  for (const Contributor& c : declared.items)
    if (shared(*c.info) && c.u.cwiseAbs().maxCoeff() > 0) ids += fmt::format("{}{}", ids.empty() ? "" : ", ", c.info->id);
  if (ids.empty()) return;
  Eigen::MatrixXd C = 1e6 * probeAxesCovariance(declared, shared, t, u);  // mm^2 -> um^2
  Eigen::MatrixXd D = 1e3 * probeAxesDraws(declared, shared, t, u, kDeclaredNullDraws, kDeclaredNullSeed);  // mm -> um
  if (scale.size()) {
    C = scale.asDiagonal() * C * scale.asDiagonal();
    D = scale.asDiagonal() * D;
  }
  noise->structured_um2 = C;
  noise->structured_draws_um = std::move(D);
  noise->repeatability_only = false;
  noise->declaration += fmt::format("; shared between touches, to first order: {} ({:.2f} um rms per touch)", ids,
                                    std::sqrt(C.diagonal().mean()));
}

namespace {

/// The last covariance whose roots were asked for, with its eigen-decomposition and the roots made
/// from it. The screen, the judge and the budget of one analysis, and every data set of a series
/// read against one declaration, ask again for the roots of the same matrix, and its
/// eigen-decomposition (order n^3) was the largest cost of a judgement. Per thread, keyed by the
/// matrix itself (compared entry by entry): the answer is the one a fresh decomposition gives.
struct RootsMemo {
  Eigen::MatrixXd S, V, inverse_root, root;
  Eigen::VectorXd r;
  bool has_inverse_root = false, has_root = false;
};

}  // namespace

void squareRoots(const Eigen::MatrixXd& S, Eigen::MatrixXd* inverse_root, Eigen::MatrixXd* root) {
  if (S.rows() != S.cols()) throw std::invalid_argument("declared noise: the covariance is not square");
  if (!S.allFinite()) throw std::invalid_argument("declared noise: the covariance has a non-finite entry");
  if (S.rows() == 0) {
    if (inverse_root) *inverse_root = S;
    if (root) *root = S;
    return;
  }
  if (!(S.diagonal().minCoeff() > 0)) throw std::invalid_argument("declared noise: a reading with no declared variance");
  thread_local RootsMemo memo;
  if (memo.S.rows() != S.rows() || memo.S != S) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (S + S.transpose()));
    const double top = es.eigenvalues().maxCoeff();
    memo.r = es.eigenvalues().cwiseMax(1e-12 * top).cwiseSqrt();
    memo.V = es.eigenvectors();
    memo.S = S;
    memo.has_inverse_root = memo.has_root = false;
  }
  if (inverse_root) {
    if (!memo.has_inverse_root) memo.inverse_root = memo.V * memo.r.cwiseInverse().asDiagonal() * memo.V.transpose();
    memo.has_inverse_root = true;
    *inverse_root = memo.inverse_root;
  }
  if (root) {
    if (!memo.has_root) memo.root = memo.V * memo.r.asDiagonal() * memo.V.transpose();
    memo.has_root = true;
    *root = memo.root;
  }
}

Eigen::MatrixXd inverseSquareRoot(const Eigen::MatrixXd& S) {
  Eigen::MatrixXd W;
  squareRoots(S, &W, nullptr);
  return W;
}

namespace {

/// The whitened problem: W = S^-1/2 and an orthonormal basis Q of W J's span.
struct Whitened {
  Eigen::MatrixXd W, Q;
};

Whitened whitened(const Eigen::VectorXd& residual, const Eigen::MatrixXd& J, const Eigen::MatrixXd& S) {
  const Eigen::Index n = residual.size();
  if (J.rows() != n || S.rows() != n || S.cols() != n)
    throw std::invalid_argument(fmt::format("declared noise: {} readings, J {} rows, covariance {} x {}", n, J.rows(),
                                            S.rows(), S.cols()));
  Whitened w;
  w.W = inverseSquareRoot(S);
  w.Q = Eigen::MatrixXd(n, 0);
  if (J.cols() > 0 && n > 0) {
    const Eigen::MatrixXd Xw = w.W * J;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Xw, Eigen::ComputeThinU);
    const Eigen::VectorXd& sv = svd.singularValues();
    Eigen::Index rank = 0;
    while (rank < sv.size() && sv[rank] > 1e-10 * sv[0]) ++rank;
    w.Q = svd.matrixU().leftCols(rank);
  }
  return w;
}

}  // namespace

DeclaredNoiseTest testAgainstDeclared(const Eigen::VectorXd& residual, const Eigen::MatrixXd& J, const Eigen::MatrixXd& S) {
  return testAgainstDeclared(residual, J, S, Eigen::MatrixXd(residual.size(), 0));
}

DeclaredNoiseTest testAgainstDeclared(const Eigen::VectorXd& residual, const Eigen::MatrixXd& J, const Eigen::MatrixXd& S,
                                      const Eigen::MatrixXd& null_draws) {
  const Whitened w = whitened(residual, J, S);
  if (null_draws.rows() != residual.size())
    throw std::invalid_argument(
        fmt::format("declared noise: {} readings, null draws of {}", residual.size(), null_draws.rows()));
  const Eigen::VectorXd yw = w.W * residual;
  DeclaredNoiseTest t;
  t.chi2 = (yw - w.Q * (w.Q.transpose() * yw)).squaredNorm();
  t.dof = static_cast<int>(residual.size() - w.Q.cols());
  t.null_dof = t.dof;
  t.p_value = t.dof > 0 ? chiSquareSurvival(t.chi2, t.dof) : 1.0;
  t.ratio = t.dof > 0 ? std::sqrt(t.chi2 / t.dof) : 0.0;
  if (t.dof > 0 && null_draws.cols() >= kMinNullDraws) {
    const Eigen::MatrixXd Dw = w.W * null_draws;
    const Eigen::VectorXd c = (Dw - w.Q * (w.Q.transpose() * Dw)).colwise().squaredNorm().transpose();
    const ScaledChiSquare null = scaledChiSquareFromDraws(std::vector<double>(c.data(), c.data() + c.size()));
    if (null.draws > 0) {
      t.null_draws = null.draws;
      t.null_scale = null.scale;
      t.null_dof = null.dof;
      t.p_value = chiSquareSurvival(t.chi2 / t.null_scale, t.null_dof);
    }
  }
  if (t.dof > 0) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinU);
    Eigen::Index rank = 0;
    while (rank < svd.singularValues().size() && svd.singularValues()[rank] > 1e-10 * svd.singularValues()[0]) ++rank;
    const Eigen::MatrixXd U = svd.matrixU().leftCols(rank);
    const double dof = static_cast<double>(residual.size() - rank);
    const Eigen::VectorXd r = residual - U * (U.transpose() * residual);
    t.residual_rms = std::sqrt(r.squaredNorm() / dof);
    t.declared_rms = std::sqrt(std::max(0.0, S.trace() - (U.transpose() * S * U).trace()) / dof);
  }
  return t;
}

namespace {

std::string nullText(const DeclaredNoiseTest& t) {
  if (t.null_draws == 0) return fmt::format("chi2({})", t.dof);
  return fmt::format("{:.3f} x chi2({:.1f}): the mean and variance of chi2 over {} draws of the declared machine",
                     t.null_scale, t.null_dof, t.null_draws);
}

}  // namespace

std::string offsetsHeldBack(const DeclaredNoise& noise, const DeclaredNoiseTest& test) {
  if (!(test.p_value < kOffsetsAdequacyAlpha)) return "";
  return fmt::format("the data exceed the declared noise: residual {:.2f} um rms where it leaves {:.2f} um; whitened, "
                     "{:.2f} x it (chi2 {:.1f} on {} dof, p {:.2g} < {:g} against {}; {}): the model does not explain "
                     "this machine (rotacal diagnose names what it misses)",
                     test.residual_rms, test.declared_rms, test.ratio, test.chi2, test.dof, test.p_value,
                     kOffsetsAdequacyAlpha, nullText(test), noise.declaration);
}

Json declaredNoiseJson(const DeclaredNoise& noise, const DeclaredNoiseTest& test) {
  const double white = std::sqrt(noise.white_um2);
  return {{"declaration", noise.declaration},
          {"repeatability_only", noise.repeatability_only},
          {"per_touch_um", std::round(white * 1e6) / 1e6},
          {"declared_residual_rms_um", std::round(test.declared_rms * 1e6) / 1e6},
          {"residual_rms_um", std::round(test.residual_rms * 1e6) / 1e6},
          {"test", "the fit's residual whitened by the declared covariance of the touches: chi2 on readings - rank"},
          {"null", nullText(test)},
          {"null_draws", test.null_draws},
          {"null_scale", std::round(test.null_scale * 1e4) / 1e4},
          {"null_dof", std::round(test.null_dof * 100) / 100},
          {"chi2", std::round(test.chi2 * 1e4) / 1e4},
          {"dof", test.dof},
          {"p_value", test.p_value},
          {"ratio", std::round(test.ratio * 1e4) / 1e4},
          {"summary", fmt::format("residual {:.2f} um rms where the declared noise leaves {:.2f} um; whitened, {:.2f} x "
                                  "the declared noise (chi2 {:.1f} on {} dof, p {:.2g})",
                                  test.residual_rms, test.declared_rms, test.ratio, test.chi2, test.dof, test.p_value)}};
}

Eigen::VectorXd deletionStatistics(const Eigen::VectorXd& residual, const Eigen::MatrixXd& J, const Eigen::MatrixXd& S) {
  return deletionStatisticsColumns(residual, J, S).col(0);
}

namespace {

/// The diagonal of P = W (I - Q Q^T) W and the pieces that made it.
struct DeletionProjector {
  Whitened w;
  Eigen::VectorXd Pdiag;
  /// P_ii below this share of the reading's own weight: the model takes the whole reading up.
  bool unseen(Eigen::Index i) const { return !(Pdiag[i] > 1e-14 * w.W(i, i) * w.W(i, i)); }
};

/// The last (J, S) whose projector was asked for, with it. A screen asks for the statistics, their
/// null draws' and the sensitivities of one fit in turn, and every step of a series read against
/// one declaration asks again: the whitening's SVD was the largest cost of a screen. Per thread,
/// keyed by both matrices (compared entry by entry): the answer is the one a fresh one gives.
struct ProjectorMemo {
  Eigen::MatrixXd J, S;
  DeletionProjector d;
  Eigen::MatrixXd P;  // W (I - Q Q^T) W, formed on the first call with many columns
  bool valid = false, has_P = false;
};

ProjectorMemo& deletionProjector(Eigen::Index n, const Eigen::MatrixXd& J, const Eigen::MatrixXd& S) {
  thread_local ProjectorMemo memo;
  const bool same = memo.valid && memo.J.rows() == J.rows() && memo.J.cols() == J.cols() && memo.S.rows() == S.rows() &&
                    memo.S.cols() == S.cols() && memo.J == J && memo.S == S && memo.d.Pdiag.size() == n;
  if (same) return memo;
  memo.valid = false;
  DeletionProjector& d = memo.d;
  d.w = whitened(Eigen::VectorXd::Zero(n), J, S);
  const Eigen::MatrixXd M = d.w.W - d.w.Q * (d.w.Q.transpose() * d.w.W);
  d.Pdiag = d.w.W.cwiseProduct(M).colwise().sum().transpose();
  memo.J = J;
  memo.S = S;
  memo.has_P = false;
  memo.valid = true;
  return memo;
}

}  // namespace

Eigen::MatrixXd deletionStatisticsColumns(const Eigen::MatrixXd& residuals, const Eigen::MatrixXd& J, const Eigen::MatrixXd& S) {
  const Eigen::Index n = residuals.rows();
  ProjectorMemo& memo = deletionProjector(n, J, S);
  const DeletionProjector& d = memo.d;
  const Eigen::MatrixXd& W = d.w.W;
  const Eigen::MatrixXd& Q = d.w.Q;
  // P = W (I - Q Q^T) W: the residual projector of the whitened fit brought back to readings.
  // Many columns (a screen's null draws): P formed once (n^3) and applied once (n^2 x columns),
  // where applying its factors costs two such products.
  Eigen::MatrixXd Py;
  if (residuals.cols() > n) {
    if (!memo.has_P) memo.P = W * (W - Q * (Q.transpose() * W));
    memo.has_P = true;
    Py.noalias() = memo.P * residuals;
  } else {
    const Eigen::MatrixXd yw = W * residuals;
    Py = W * (yw - Q * (Q.transpose() * yw));
  }
  Eigen::MatrixXd t(n, residuals.cols());
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!d.unseen(i)) t.row(i) = Py.row(i) / std::sqrt(d.Pdiag[i]);
    else t.row(i).setZero();
  }
  return t;
}

Eigen::VectorXd deletionSensitivity(const Eigen::MatrixXd& J, const Eigen::MatrixXd& S) {
  const DeletionProjector& d = deletionProjector(S.rows(), J, S).d;
  Eigen::VectorXd s(S.rows());
  for (Eigen::Index i = 0; i < s.size(); ++i) s[i] = d.unseen(i) ? 0.0 : std::sqrt(d.Pdiag[i]);
  return s;
}

}  // namespace rotacal
