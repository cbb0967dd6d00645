#include "unjam/core/least_norm.hpp"

#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

namespace unjam {
namespace {

// A column of B with more than this many entries (and more than sqrt(rows)) is dense: it
// would fill B D B^T completely (the cell's strain couples to every contact).
bool is_dense(Eigen::Index nnz, Eigen::Index rows) {
  return nnz > 64 && static_cast<double>(nnz) * nnz > static_cast<double>(rows);
}

}  // namespace

std::optional<Eigen::VectorXd> least_norm_solution(const Eigen::SparseMatrix<double>& B,
                                                   const Eigen::VectorXd& D,
                                                   const Eigen::VectorXd& d, int refinements) {
  // W = B D B^T = W0 + U diag(D_u) U^T with U the dense columns of B: W0 is factorised
  // sparse, the dense part enters through the Woodbury identity
  //   W^-1 = W0^-1 - W0^-1 U (diag(D_u)^-1 + U^T W0^-1 U)^-1 U^T W0^-1.
  Eigen::SparseMatrix<double> B0 = B;
  std::vector<Eigen::Index> dense;
  for (Eigen::Index j = 0; j < B.cols(); ++j)
    if (is_dense(B.col(j).nonZeros(), B.rows())) dense.push_back(j);
  Eigen::MatrixXd U(B.rows(), static_cast<Eigen::Index>(dense.size()));
  Eigen::VectorXd D_u(static_cast<Eigen::Index>(dense.size()));
  for (std::size_t c = 0; c < dense.size(); ++c) {
    U.col(c) = Eigen::VectorXd(B.col(dense[c]));
    D_u[c] = D[dense[c]];
    B0.col(dense[c]) *= 0.0;
  }
  B0.prune(0.0);

  const Eigen::SparseMatrix<double> B0D = B0 * D.asDiagonal();
  Eigen::SparseMatrix<double> W0 = B0D * B0.transpose();
  const double eps = 1e-14 * (W0.rows() > 0 ? std::max(W0.diagonal().mean(), 1e-300) : 1.0);
  for (Eigen::Index i = 0; i < W0.rows(); ++i) W0.coeffRef(i, i) += eps;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(W0);
  if (ldlt.info() != Eigen::Success) return std::nullopt;

  // Capacitance matrix of the dense part (none without dense columns: U has 0 columns).
  Eigen::MatrixXd W0iU(B.rows(), 0);  // W0^-1 U
  Eigen::LDLT<Eigen::MatrixXd> cap_ldlt;
  if (!dense.empty()) {
    W0iU = ldlt.solve(U);
    Eigen::MatrixXd cap = U.transpose() * W0iU;
    for (Eigen::Index c = 0; c < cap.rows(); ++c) cap(c, c) += 1.0 / D_u[c];
    cap_ldlt.compute(cap);
  }
  const auto solve_W = [&](const Eigen::VectorXd& r) -> Eigen::VectorXd {
    Eigen::VectorXd z = ldlt.solve(r);
    if (!dense.empty()) z -= W0iU * cap_ldlt.solve(U.transpose() * z);
    return z;
  };

  const Eigen::SparseMatrix<double> BD = B * D.asDiagonal();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(B.cols());
  for (int i = 0; i <= refinements; ++i) x += BD.transpose() * solve_W(d - B * x);
  return x;
}

}  // namespace unjam
