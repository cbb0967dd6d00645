#pragma once
// CLP's interior-point method (primal-dual predictor-corrector, no crossover) for a sequence
// of linear programs that share one constraint matrix A, as the force-bound LPs do (only the
// objective changes). Each iteration factorises the normal equations A D A^T (D > 0
// diagonal, changing every iteration) by sparse Cholesky; their pattern depends on A alone,
// so the ordering and symbolic analysis are done once, on the first solve, and reused.
//
// The factorisation is NormalEquationsCholesky (normal_equations.hpp), CLP's own with four
// settings changed: shared analysis, a higher dense threshold, A D A^T by a precomputed
// scatter, and METIS's nested dissection from kNestedDissectionMinRows rows on.
//
// CLP ends a solve optimal (status 0: the primal and dual objectives agree to the dual
// tolerance, absolute) or leaves its loop without a verdict when the complementarity gap stops
// decreasing. The second happens near the accuracy limit of the factorisation: 1 of 140 LPs
// sampled at 8000 disks, 10 of 4507 in all the bounds of a 2000-disk packing, with the
// objectives equal to ~2e-9 relative. Its point is not always that close (a case on p50 at
// tolerance 1e-12 was 2e-6 off, relative, with CLP's objectives equal to 2e-11), so it is not
// accepted: the LP is solved again with the tolerances 10x and then 100x looser, which ends
// optimal (the 8000-disk case: 39 iterations at 1e-8, within 3e-9 of the simplex vertex),
// where primal simplex from the barrier's point takes minutes against seconds
// (docs/benchmarks.md, section 7).
#include <memory>

class ClpCholeskyBase;
class ClpSimplex;

namespace unjam {

// How a barrier solve ended (see above).
enum class BarrierEnd {
  optimal,            // at the model's own tolerances
  optimal_loosened,   // after a stall, at 10x or 100x looser tolerances
  failed,             // no optimum at 100x either (the caller decides what next)
};

// Rows of A from which the normal equations are ordered by METIS's nested dissection instead
// of CLP's minimum degree (see above).
constexpr int kNestedDissectionMinRows = 8000;

class BarrierSolver {
 public:
  // `nested_dissection_rows`: the ordering is nested dissection for A with at least this
  // many rows, CLP's own below.
  explicit BarrierSolver(int nested_dissection_rows = kNestedDissectionMinRows);
  // A copy keeps the analysis (one solver per thread; the matrix must stay the same).
  BarrierSolver(const BarrierSolver& other);
  BarrierSolver& operator=(const BarrierSolver&) = delete;
  ~BarrierSolver();

  // Solves `model` from scratch (its objective, bounds and sense as set) and leaves the
  // solution, status and iteration count (of all attempts) in it, as ClpSimplex::initialSolve
  // does; its tolerances are restored after a retry. Every model passed to one solver (and
  // its copies) must have the same constraint matrix.
  BarrierEnd solve(ClpSimplex& model);

  // Whether the ordering of the analysis made by the first solve is nested dissection.
  bool nested_dissection() const;

 private:
  void solve_once(ClpSimplex& model);

  int nested_dissection_rows_;
  // The factorisation right after its ordering and symbolic analysis (null until the first
  // solve has made them); each solve starts from a clone.
  std::unique_ptr<ClpCholeskyBase> analysed_;
};

}  // namespace unjam
