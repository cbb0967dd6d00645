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

// How KLU picks its pivots at a fresh factorisation (docs/benchmarks.md, section 10,
// "Diagonal pivots on nested dissection from 3000 rows").
enum class KluPivoting {
  // KLU's partial pivoting (threshold 1e-3: the diagonal while it is at least 1e-3 of its
  // column's largest entry) on its AMD ordering.
  partial,
  // From 3000 rows on (~1000 disks; below, as partial): the diagonal while it is at least 1e-6 of its
  // column's largest entry, on METIS's nested dissection of S + S^T, the pressure's row and
  // column last. On the probe's systems a third to half of partial pivoting's fill (at 2000
  // disks, 0.39 M entries in L instead of 1.30 M). Where its pivots grow (reciprocal pivot
  // growth below 1e-8) the factorisation is done again by partial pivoting. Solves with
  // these factors are less accurate by up to the pivots' growth: refine them.
  diagonal,
};

class KluFactor {
 public:
  explicit KluFactor(KluPivoting pivoting = KluPivoting::diagonal);
  ~KluFactor();
  KluFactor(const KluFactor&) = delete;
  KluFactor& operator=(const KluFactor&) = delete;

  // Factorises S (compressed; the pattern of every call is that of the first). With
  // reuse_pivots the previous pivot order is tried first. False where KLU fails (singular).
  bool factorize(Eigen::SparseMatrix<double>& S, bool reuse_pivots = true);
  // B <- S^-1 B, all columns in one pass over the factors.
  void solve_in_place(Eigen::MatrixXd& B);
  void solve_in_place(Eigen::VectorXd& b);
  // Factorisations done afresh (not refactorised) so far, the diagonal's attempts included.
  int fresh() const;
  // The present factors have the diagonal's pivots (KluPivoting::diagonal, not fallen back).
  bool diagonal_pivots() const;
  // Entries of L + U (the diagonal counted once in each) of the present factors; 0 before the first.
  double factor_nonzeros() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unjam
