#pragma once
// Least-norm solution of an underdetermined sparse linear system in a diagonal metric:
//     x = argmin x^T D^{-1} x  subject to  B x = d   =>   x = D B^T (B D B^T)^{-1} d.
// Used for the polish of a static network (D = 1: the smallest force change that restores
// balance) and for the kinematic probe (D = M^{-1}: the displacement of least kinetic
// energy compatible with the contact constraints). B D B^T is singular when rows of B are
// dependent (self-stresses, floppy modes); it is regularised by eps I, eps = 1e-14 times
// its mean diagonal, and the solution refined, which converges to the least-norm solution
// when d lies in the range of B.
#include <optional>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace unjam {

// Empty when the factorisation fails. `refinements`: iterative refinement steps.
std::optional<Eigen::VectorXd> least_norm_solution(const Eigen::SparseMatrix<double>& B,
                                                   const Eigen::VectorXd& D,
                                                   const Eigen::VectorXd& d,
                                                   int refinements = 3);

}  // namespace unjam
