#pragma once
// SuiteSparse's KLU on a sparse matrix of fixed pattern, for the exact probe's reduced system
// (probe/cd_path) and the interior-point method's Newton system (solver/interior_point):
// analysed once at the first factorisation; then factorised afresh with partial pivoting or,
// while that stays stable, refactorised with the previous pivot order (several times cheaper).
// Stable means a reciprocal pivot growth (klu_rgrowth) above 1e-8; below it the factorisation
// is done afresh (docs/benchmarks.md, section 10).
#include <memory>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace unjam {

class KluFactor {
 public:
  KluFactor();
  ~KluFactor();
  KluFactor(const KluFactor&) = delete;
  KluFactor& operator=(const KluFactor&) = delete;

  // Factorises S (compressed; the pattern of every call is that of the first). With
  // reuse_pivots the previous pivot order is tried first. False where KLU fails (singular).
  bool factorize(Eigen::SparseMatrix<double>& S, bool reuse_pivots = true);
  // B <- S^-1 B, all columns in one pass over the factors.
  void solve_in_place(Eigen::MatrixXd& B);
  void solve_in_place(Eigen::VectorXd& b);
  // Factorisations done afresh (not refactorised) so far.
  int fresh() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unjam
