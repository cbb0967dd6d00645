#include "unjam/ensemble/lp_barrier.hpp"

#include <coin/ClpCholeskyBase.hpp>
#include <coin/ClpEventHandler.hpp>
#include <coin/ClpInterior.hpp>
#include <coin/ClpSimplex.hpp>

namespace unjam {

namespace {

// Fill fraction of the trailing block above which the factor is stored dense (see header).
constexpr double kGoDense = 0.95;
// CLP's own limit for models of more than 10^4 rows and columns (ClpSolve).
constexpr int kMaxBarrierIterations = 1000;

// CLP's sparse Cholesky with the ordering and symbolic analysis done once. The first solve
// runs CLP's own order() and symbolic() and hands a copy of the analysed state to `keep`;
// that copy, and every clone of it, skips both (it only learns the new interior model and
// clears the rows a previous factorisation dropped). Only the first object writes to
// `keep`; the analysed copies hold no pointer back to it.
class SharedAnalysisCholesky : public ClpCholeskyBase {
 public:
  explicit SharedAnalysisCholesky(std::unique_ptr<ClpCholeskyBase>* keep) : keep_(keep) {
    goDense_ = kGoDense;
  }
  SharedAnalysisCholesky(const SharedAnalysisCholesky&) = default;
  ClpCholeskyBase* clone() const override { return new SharedAnalysisCholesky(*this); }

  int order(ClpInterior* model) override {
    if (!analysed_) return ClpCholeskyBase::order(model);
    model_ = model;
    resetRowsDropped();
    return 0;
  }
  int symbolic() override {
    if (analysed_) return 0;
    const int status = ClpCholeskyBase::symbolic();
    if (status == 0) {
      analysed_ = true;
      auto* analysed = new SharedAnalysisCholesky(*this);
      analysed->keep_ = nullptr;
      keep_->reset(analysed);
    }
    return status;
  }

 private:
  std::unique_ptr<ClpCholeskyBase>* keep_;  // where the first analysis goes (null after)
  bool analysed_ = false;
};

}  // namespace

BarrierSolver::BarrierSolver() = default;

BarrierSolver::BarrierSolver(const BarrierSolver& other)
    : analysed_(other.analysed_ ? other.analysed_->clone() : nullptr) {}

BarrierSolver::~BarrierSolver() = default;

void BarrierSolver::solve_once(ClpSimplex& model) {
  // As ClpSolve's barrier path: borrow the model's arrays, no event handler, no scaling.
  ClpInterior barrier;
  barrier.borrowModel(model);
  barrier.eventHandler()->setSimplex(nullptr);
  barrier.setCholesky(analysed_ ? analysed_->clone() : new SharedAnalysisCholesky(&analysed_));
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
