#include "unjam/lp/lp_barrier.hpp"

#include <coin/ClpEventHandler.hpp>
#include <coin/ClpInterior.hpp>
#include <coin/ClpSimplex.hpp>

#include "unjam/lp/normal_equations.hpp"

namespace unjam {

namespace {

// CLP's own limit for models of more than 10^4 rows and columns (ClpSolve).
constexpr int kMaxBarrierIterations = 1000;

}  // namespace

BarrierSolver::BarrierSolver(int nested_dissection_rows)
    : nested_dissection_rows_(nested_dissection_rows) {}

BarrierSolver::BarrierSolver(const BarrierSolver& other)
    : nested_dissection_rows_(other.nested_dissection_rows_),
      analysed_(other.analysed_ ? other.analysed_->clone() : nullptr) {}

BarrierSolver::~BarrierSolver() = default;

bool BarrierSolver::nested_dissection() const {
  return analysed_ && static_cast<const NormalEquationsCholesky&>(*analysed_).nested_dissection();
}

void BarrierSolver::solve_once(ClpSimplex& model) {
  // As ClpSolve's barrier path: borrow the model's arrays, no event handler, no scaling.
  ClpInterior barrier;
  barrier.borrowModel(model);
  barrier.eventHandler()->setSimplex(nullptr);
  barrier.setCholesky(analysed_ ? analysed_->clone()
                                : new NormalEquationsCholesky(&analysed_, nested_dissection_rows_));
  barrier.setMaximumBarrierIterations(kMaxBarrierIterations);
  barrier.scaling(0);
  barrier.primalDual();
  barrier.returnModel(model);
}

BarrierEnd BarrierSolver::solve(ClpSimplex& model) {
  solve_once(model);
  if (model.status() == 0) return BarrierEnd::optimal;
  const double primal_tol = model.primalTolerance(), dual_tol = model.dualTolerance();
  int iterations = model.numberIterations();
  BarrierEnd end = BarrierEnd::failed;
  for (const double looser : {10.0, 100.0}) {
    model.setPrimalTolerance(looser * primal_tol);
    model.setDualTolerance(looser * dual_tol);
    solve_once(model);
    iterations += model.numberIterations();
    if (model.status() == 0) {
      end = BarrierEnd::optimal_loosened;
      break;
    }
  }
  model.setPrimalTolerance(primal_tol);
  model.setDualTolerance(dual_tol);
  model.setNumberIterations(iterations);
  return end;
}

}  // namespace unjam
