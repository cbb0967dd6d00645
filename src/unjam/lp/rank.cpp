#include "unjam/lp/rank.hpp"

#include <algorithm>
#include <random>

#include <Eigen/Dense>

#include "unjam/core/error.hpp"

namespace unjam {

RegularisedGram::RegularisedGram(const Eigen::SparseMatrix<double>& B) : G(B.transpose() * B) {
  Eigen::SparseMatrix<double> M = G;
  const double delta = G.rows() > 0 ? 1e-13 * G.diagonal().maxCoeff() : 0.0;
  for (Eigen::Index j = 0; j < M.rows(); ++j) M.coeffRef(j, j) += delta;
  ldlt.compute(M);
  if (ldlt.info() != Eigen::Success) throw Error("sparse LDLT of B^T B failed");
}

int numerical_rank(const Eigen::SparseMatrix<double>& B, const RegularisedGram& gram,
                   double relative_threshold) {
  const int n = static_cast<int>(B.cols());
  if (n == 0) return 0;
  double max_norm = 0.0;
  for (int j = 0; j < n; ++j) max_norm = std::max(max_norm, B.col(j).norm());
  // Subspace inverse iteration on G + delta I: each solve multiplies a null direction of B by
  // 1/delta and one with singular value s by 1/(s^2 + delta), so with delta = 1e-13 max G_ii
  // a few solves leave the block spanning the null space and the smallest singular
  // directions. The count is then made on B itself: the singular values of B V (V
  // orthonormal), those <= relative_threshold * max_norm are null. Squaring enters only the
  // iteration, not the decision.
  constexpr int kSolves = 4;
  std::mt19937_64 rng(1);  // fixed: the rank does not depend on the run
  std::normal_distribution<double> normal;
  int nullity = 0;
  for (int block = std::min(8, n);; block = std::min(2 * block, n)) {
    Eigen::MatrixXd V(n, block);
    for (double& v : V.reshaped()) v = normal(rng);
    for (int i = 0; i < kSolves; ++i) {
      V = gram.ldlt.solve(V);
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(V);
      V = qr.householderQ() * Eigen::MatrixXd::Identity(n, block);  // orthonormal basis
    }
    const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(B * V).singularValues();
    nullity = static_cast<int>((s.array() <= relative_threshold * max_norm).count());
    // Accept when at most half the block is null: the block then holds the null space with
    // room for the next-smallest directions. Otherwise (or B is all null) a larger block.
    if (2 * nullity <= block || block == n) break;
  }
  return n - nullity;
}

int numerical_rank(const Eigen::SparseMatrix<double>& A, double relative_threshold) {
  // rank(A) = n - dim null(B), with B the tall one of A and A^T (n = its columns); the null
  // space is small (periodic translations, a few mechanisms), so it is found directly.
  const Eigen::SparseMatrix<double> B = A.rows() >= A.cols()
                                            ? Eigen::SparseMatrix<double>(A)
                                            : Eigen::SparseMatrix<double>(A.transpose());
  if (B.cols() == 0) return 0;
  return numerical_rank(B, RegularisedGram(B), relative_threshold);
}

RankInfo equilibrium_rank(const EquilibriumSystem& system, double relative_threshold) {
  const Eigen::SparseMatrix<double> Ay = cone_matrix(system);
  RankInfo info;
  info.rows = static_cast<int>(Ay.rows());
  info.columns = static_cast<int>(Ay.cols());
  info.threshold = relative_threshold;
  info.rank = numerical_rank(Ay, relative_threshold);
  info.dimension = info.columns - info.rank;
  return info;
}

}  // namespace unjam
