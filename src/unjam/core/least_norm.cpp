#include "unjam/core/least_norm.hpp"

#include <Eigen/SparseCholesky>

namespace unjam {

std::optional<Eigen::VectorXd> least_norm_solution(const Eigen::SparseMatrix<double>& B,
                                                   const Eigen::VectorXd& D,
                                                   const Eigen::VectorXd& d, int refinements) {
  const Eigen::SparseMatrix<double> BD = B * D.asDiagonal();
  Eigen::SparseMatrix<double> W = BD * B.transpose();
  const double eps = 1e-14 * (W.rows() > 0 ? W.diagonal().mean() : 1.0);
  for (int i = 0; i < W.rows(); ++i) W.coeffRef(i, i) += eps;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(W);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(B.cols());
  for (int i = 0; i <= refinements; ++i) x += BD.transpose() * ldlt.solve(d - B * x);
  return x;
}

}  // namespace unjam
