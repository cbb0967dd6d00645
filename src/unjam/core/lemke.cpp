#include "unjam/core/lemke.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "unjam/core/error.hpp"

namespace unjam {

LemkeResult solve_lcp_lemke(const Eigen::MatrixXd& M, const Eigen::VectorXd& q,
                            const Eigen::VectorXd& d, int max_pivots) {
  const Eigen::Index n = q.size();
  if (M.rows() != n || M.cols() != n) throw Error("solve_lcp_lemke: M must be n x n with n = size of q");
  if (d.size() != 0 && (d.size() != n || !(d.minCoeff() > 0.0)))
    throw Error("solve_lcp_lemke: the covering vector must have n positive entries");
  LemkeResult res;
  if (n == 0 || q.minCoeff() >= 0.0) {
    res.z = Eigen::VectorXd::Zero(n);
    return res;
  }
  // Tableau of w - M z - z0 d = q with the basis inverse kept in the w columns:
  // columns [0, n) w, [n, 2n) z, 2n the artificial z0, 2n + 1 the right-hand side.
  const Eigen::Index c0 = 2 * n, rhs = 2 * n + 1;
  Eigen::MatrixXd T(n, 2 * n + 2);
  T.leftCols(n).setIdentity();
  T.middleCols(n, n) = -M;
  if (d.size() == 0) T.col(c0).setConstant(-1.0);
  else T.col(c0) = -d;
  T.col(rhs) = q;
  std::vector<Eigen::Index> basis(n);
  for (Eigen::Index i = 0; i < n; ++i) basis[i] = i;

  const auto pivot = [&](Eigen::Index r, Eigen::Index c) {
    T.row(r) /= T(r, c);
    const Eigen::VectorXd col = T.col(c);
    for (Eigen::Index i = 0; i < n; ++i)
      if (i != r && col[i] != 0.0) T.row(i) -= col[i] * T.row(r);
    basis[r] = c;
  };
  // Lexicographic minimum ratio over the rows where the entering column is positive:
  // (rhs, B^-1) / column, compared entry by entry (B^-1 is kept in the w columns).
  const auto leaving_row = [&](Eigen::Index c) -> Eigen::Index {
    const Eigen::VectorXd col = T.col(c);
    const double scale = col.cwiseAbs().maxCoeff();
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < n; ++i)
      if (col[i] > 1e-11 * scale) rows.push_back(i);
    if (rows.empty()) return -1;
    const auto ratio = [&](Eigen::Index i, Eigen::Index j) {
      return j < 0 ? std::max(T(i, rhs), 0.0) / col[i] : T(i, j) / col[i];
    };
    for (Eigen::Index j = -1; j < n && rows.size() > 1; ++j) {
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index i : rows) best = std::min(best, ratio(i, j));
      const double tol = 1e-12 * std::max(1.0, std::abs(best));
      std::vector<Eigen::Index> kept;
      for (Eigen::Index i : rows)
        if (ratio(i, j) <= best + tol) kept.push_back(i);
      rows.swap(kept);
    }
    // The artificial variable leaves whenever it may: the path then ends on a solution.
    for (Eigen::Index i : rows)
      if (basis[i] == c0) return i;
    return rows.front();
  };

  // The first pivot: z0 enters at the smallest q_i / d_i, where every w becomes >= 0.
  Eigen::Index r = 0;
  (d.size() == 0 ? q : Eigen::VectorXd(q.cwiseQuotient(d))).minCoeff(&r);
  Eigen::Index leaving = basis[r];
  pivot(r, c0);
  ++res.pivots;
  while (res.pivots < max_pivots) {
    const Eigen::Index entering = leaving < n ? leaving + n : leaving - n;  // the complement
    r = leaving_row(entering);
    if (r < 0) {
      res.ray = true;
      return res;
    }
    leaving = basis[r];
    pivot(r, entering);
    ++res.pivots;
    if (leaving == c0) {
      res.z = Eigen::VectorXd::Zero(n);
      for (Eigen::Index i = 0; i < n; ++i)
        if (basis[i] >= n && basis[i] < c0) res.z[basis[i] - n] = std::max(T(i, rhs), 0.0);
      return res;
    }
  }
  return res;
}

}  // namespace unjam
