#pragma once
// The dimension of the admissible force networks of one contact geometry (docs/ensemble.md,
// "The admissible force networks"): the numerical rank of the balance rows in Coulomb-cone
// coordinates (contact/equilibrium_matrix.hpp, cone_matrix), and the regularised Gram matrix
// behind it, shared with the hit-and-run projector (ensemble/hit_and_run).
#include <Eigen/Core>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "unjam/contact/equilibrium_matrix.hpp"

namespace unjam {

// Dimension of the affine set { A_y y = rhs }: columns of A_y minus its rank. This is the
// dimension of the admissible polytope when it has an interior in that set (no contact is
// forced open or forced to slide by the inequalities); for mu > 0 it is 2 N_c - rank(A).
struct RankInfo {
  int rows = 0;        // equality rows (3 N_g + 1)
  int columns = 0;     // cone columns (2 N_c for mu > 0, N_c for mu = 0)
  int rank = 0;        // rank of A_y
  int dimension = 0;   // columns - rank
  double threshold = 0.0;  // singular values <= threshold * largest row norm count as zero
};

// Numerical rank of A_y: singular values at or below `relative_threshold` times the largest
// row norm of A_y (column norm when A_y is tall) count as zero. Found by subspace inverse
// iteration for the null space with one sparse LDLT (its cost, against Eigen's SparseQR,
// in docs/ensemble.md).
RankInfo equilibrium_rank(const EquilibriumSystem& system, double relative_threshold = 1e-10);

// The same numerical rank for any sparse matrix (e.g. a subset of the columns of A_y).
int numerical_rank(const Eigen::SparseMatrix<double>& A, double relative_threshold = 1e-10);

// G = B^T B of a sparse B, with the sparse LDLT (AMD ordering) of G + delta I, delta = 1e-13
// max G_ii: B's dependent columns make G singular, and delta keeps the factorisation defined
// (a solve amplifies a null direction of B by 1/delta). The factorisation behind
// numerical_rank, shared with the hit-and-run projector (ensemble/hit_and_run), which solves
// with it for A A^T (B = A^T). Throws unjam::Error if the factorisation fails.
struct RegularisedGram {
  explicit RegularisedGram(const Eigen::SparseMatrix<double>& B);
  Eigen::SparseMatrix<double> G;  // B^T B, without delta
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt;
};

// Numerical rank of a tall B (rows >= columns) given gram = RegularisedGram(B): columns of B
// minus the dimension of its null space.
int numerical_rank(const Eigen::SparseMatrix<double>& B, const RegularisedGram& gram,
                   double relative_threshold = 1e-10);

}  // namespace unjam
