#pragma once
// CLP's interior-point method (primal-dual predictor-corrector, no crossover) for a sequence
// of linear programs that share one constraint matrix A, as the force-bound LPs do (only the
// objective changes). Each iteration factorises the normal equations A D A^T (D > 0
// diagonal, changing every iteration) by sparse Cholesky; their pattern depends on A alone,
// so the ordering and symbolic analysis are done once, on the first solve, and reused.
//
// Two settings differ from CLP's defaults, measured on the 2000- and 8000-disk packings of
// docs/benchmarks.md (the optima agree with CLP's own path to its accuracy, 4e-8 relative
// over the 2000-disk bounds):
//   - the symbolic analysis is shared (CLP repeats it for every LP): ~3 % per LP;
//   - the factor switches to dense storage only when the trailing block is 95 % full
//     (CLP: 70 %): the packings' separators are sparse and the dense kernel wastes work
//     on their zeros. 0.235 -> 0.195 s per LP at 2000 disks, 2.51 -> 2.02 s at 8000.
#include <memory>

class ClpCholeskyBase;
class ClpSimplex;

namespace unjam {

class BarrierSolver {
 public:
  BarrierSolver();
  // A copy keeps the analysis (one solver per thread; the matrix must stay the same).
  BarrierSolver(const BarrierSolver& other);
  BarrierSolver& operator=(const BarrierSolver&) = delete;
  ~BarrierSolver();

  // Solves `model` from scratch (its objective, bounds and sense as set) and leaves the
  // solution, status and iteration count in it, as ClpSimplex::initialSolve does. Every
  // model passed to one solver (and its copies) must have the same constraint matrix.
  void solve(ClpSimplex& model);

 private:
  // The factorisation right after its ordering and symbolic analysis (null until the first
  // solve has made them); each solve starts from a clone.
  std::unique_ptr<ClpCholeskyBase> analysed_;
};

}  // namespace unjam
