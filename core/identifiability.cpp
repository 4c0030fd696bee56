#include "core/identifiability.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "core/units.hpp"

namespace rotacal {

namespace {

double toReport(ParamKind kind, double v) { return kind == ParamKind::Length ? mmToUm(v) : radToMdeg(v); }

// Reduced row echelon form of the rows of A, taking pivots in the columns' given order.
// Returns the pivot column of each row.
std::vector<int> rref(Eigen::MatrixXd& A, const std::vector<int>& column_order) {
  std::vector<int> pivots;
  Eigen::Index row = 0;
  for (int col : column_order) {
    if (row >= A.rows()) break;
    Eigen::Index best = row;
    for (Eigen::Index r = row; r < A.rows(); ++r)
      if (std::abs(A(r, col)) > std::abs(A(best, col))) best = r;
    if (std::abs(A(best, col)) < 1e-10) continue;
    A.row(row).swap(A.row(best));
    A.row(row) /= A(row, col);
    for (Eigen::Index r = 0; r < A.rows(); ++r)
      if (r != row) A.row(r) -= A(r, col) * A.row(row);
    pivots.push_back(col);
    ++row;
  }
  return pivots;
}

}  // namespace

Identifiability identifiability(const Eigen::MatrixXd& J, const std::vector<IdentifiabilityParameter>& params,
                                const std::vector<int>& hold_first, double rank_tolerance) {
  const Eigen::Index n = J.cols();
  if (static_cast<Eigen::Index>(params.size()) != n)
    throw std::invalid_argument(fmt::format("identifiability: {} parameter names for {} columns", params.size(), n));
  Identifiability out;
  out.held.assign(n, false);
  out.separable.assign(n, true);
  out.u_report = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd s(n);
  for (Eigen::Index j = 0; j < n; ++j) s[j] = J.col(j).norm() > 0 ? J.col(j).norm() : 1.0;
  const Eigen::MatrixXd Js = J * s.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeFullV);
  svd.setThreshold(rank_tolerance);
  out.rank = static_cast<int>(svd.rank());
  // The null space in the scaled parameters (orthonormal rows: a well-conditioned elimination),
  // one direction per row, brought to echelon form so that each row holds one parameter.
  Eigen::MatrixXd N(n - out.rank, n);
  for (Eigen::Index k = out.rank; k < n; ++k) N.row(k - out.rank) = svd.matrixV().col(k).transpose();
  std::vector<int> order;
  for (int j : hold_first)
    if (j >= 0 && j < n) order.push_back(j);
  for (Eigen::Index j = n; j-- > 0;)
    if (std::find(order.begin(), order.end(), static_cast<int>(j)) == order.end()) order.push_back(static_cast<int>(j));
  const std::vector<int> pivots = rref(N, order);
  for (size_t r = 0; r < pivots.size(); ++r) {
    const auto row = static_cast<Eigen::Index>(r);
    UnseparableCombination c;
    c.held = pivots[r];
    out.held[c.held] = true;
    // In report units, the held parameter moving by 1: "1 um of this with c um of that".
    const auto report = [&](Eigen::Index j) -> double { return toReport(params[j].kind, N(row, j) / s[j]); };
    const double held_report = report(c.held);
    std::string with;
    for (Eigen::Index j = 0; j < n; ++j) {
      if (std::abs(N(row, j)) <= 1e-9) continue;
      const double v = report(j) / held_report;
      out.separable[j] = false;
      c.terms.emplace_back(static_cast<int>(j), v);
      if (j == c.held) continue;
      with += fmt::format("{}{} {:+.4g} {}", with.empty() ? "" : ", ", params[j].name, v, reportUnit(params[j].kind));
    }
    c.text = with.empty() ? fmt::format("{} changes no reading", params[c.held].name)
                          : fmt::format("{} +1 {} with {} changes no reading", params[c.held].name,
                                        reportUnit(params[c.held].kind), with);
    out.combinations.push_back(std::move(c));
  }
  // u of the others with the held ones fixed: (J_f^T J_f)^-1 on the scaled columns.
  std::vector<Eigen::Index> free;
  for (Eigen::Index j = 0; j < n; ++j)
    if (!out.held[j]) free.push_back(j);
  if (!free.empty()) {
    Eigen::MatrixXd Jf(J.rows(), static_cast<Eigen::Index>(free.size()));
    for (size_t k = 0; k < free.size(); ++k) Jf.col(static_cast<Eigen::Index>(k)) = Js.col(free[k]);
    const Eigen::MatrixXd cov = (Jf.transpose() * Jf).inverse();
    for (size_t k = 0; k < free.size(); ++k) {
      const Eigen::Index j = free[k];
      const auto kk = static_cast<Eigen::Index>(k);
      out.u_report[j] = toReport(params[j].kind, std::sqrt(cov(kk, kk)) / s[j]);
    }
  }
  return out;
}

}  // namespace rotacal
