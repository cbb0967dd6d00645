#include "unjam/ensemble/lp_barrier.hpp"

#include <algorithm>
#include <iostream>  // Eigen's MetisSupport reports METIS errors on std::cerr
#include <vector>

#include <Eigen/MetisSupport>
#include <Eigen/SparseCore>
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

// A fill-reducing ordering of A D A^T by METIS's nested dissection, as CLP stores it:
// permute[new] = old row. Dense rows of A (more than 10x the mean count and 100 entries, as
// the pressure row: its row of A D A^T is full) would make every separator large; they are
// left out of the graph and ordered last, as a minimum-degree ordering does. Empty if METIS
// fails (Eigen then reports on std::cerr and returns no permutation).
std::vector<int> nested_dissection_order(const ClpMatrixBase& A, int rows) {
  const int cols = A.getNumCols();
  const CoinBigIndex* start = A.getVectorStarts();
  const int* length = A.getVectorLengths();
  const int* row = A.getIndices();
  std::vector<int> count(rows, 0);
  for (int j = 0; j < cols; ++j)
    for (CoinBigIndex e = start[j]; e < start[j] + length[j]; ++e) ++count[row[e]];
  const double dense_count = std::max(100.0, 10.0 * A.getNumElements() / std::max(rows, 1));
  std::vector<int> sparse_index(rows, -1), sparse_rows, dense_rows;
  for (int i = 0; i < rows; ++i) {
    if (count[i] > dense_count) {
      dense_rows.push_back(i);
    } else {
      sparse_index[i] = static_cast<int>(sparse_rows.size());
      sparse_rows.push_back(i);
    }
  }
  // Pattern of B B^T, B = the sparse rows of A.
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int j = 0; j < cols; ++j)
    for (CoinBigIndex e = start[j]; e < start[j] + length[j]; ++e)
      if (sparse_index[row[e]] >= 0) entries.emplace_back(sparse_index[row[e]], j, 1.0);
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> B(static_cast<int>(sparse_rows.size()),
                                                      cols);
  B.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SparseMatrix<double, Eigen::ColMajor, int> BBt = B * B.transpose();
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P;
  Eigen::MetisOrdering<int>()(BBt, P);  // P.indices()[new] = old, as METIS's perm
  if (P.size() != static_cast<Eigen::Index>(sparse_rows.size())) return {};
  std::vector<int> permute;
  permute.reserve(rows);
  for (int i = 0; i < P.size(); ++i) permute.push_back(sparse_rows[P.indices()[i]]);
  permute.insert(permute.end(), dense_rows.begin(), dense_rows.end());
  return permute;
}

// CLP's sparse Cholesky with the ordering and symbolic analysis done once. The first solve
// runs CLP's own order() and symbolic() and hands a copy of the analysed state to `keep`;
// that copy, and every clone of it, skips both (it only learns the new interior model and
// clears the rows a previous factorisation dropped). Only the first object writes to
// `keep`; the analysed copies hold no pointer back to it.
class SharedAnalysisCholesky : public ClpCholeskyBase {
 public:
  SharedAnalysisCholesky(std::unique_ptr<ClpCholeskyBase>* keep, int nested_dissection_rows)
      : keep_(keep), nested_dissection_rows_(nested_dissection_rows) {
    goDense_ = kGoDense;
  }
  SharedAnalysisCholesky(const SharedAnalysisCholesky&) = default;
  ClpCholeskyBase* clone() const override { return new SharedAnalysisCholesky(*this); }

  int order(ClpInterior* model) override {
    if (!analysed_) {
      // CLP's order() also builds the row copy and sizes that symbolic() needs; for large
      // matrices its minimum-degree permutation is then replaced (kept if METIS fails).
      const int status = ClpCholeskyBase::order(model);
      if (status != 0 || numberRows_ < nested_dissection_rows_) return status;
      const std::vector<int> permute = nested_dissection_order(*model->clpMatrix(), numberRows_);
      if (permute.empty()) return 0;
      for (int i = 0; i < numberRows_; ++i) {
        permute_[i] = permute[i];
        permuteInverse_[permute[i]] = i;
      }
      nested_dissection_ = true;
      return 0;
    }
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

  bool nested_dissection() const { return nested_dissection_; }

 private:
  std::unique_ptr<ClpCholeskyBase>* keep_;  // where the first analysis goes (null after)
  int nested_dissection_rows_;              // BarrierSolver's threshold
  bool nested_dissection_ = false;          // the ordering is nested dissection
  bool analysed_ = false;
};

}  // namespace

BarrierSolver::BarrierSolver(int nested_dissection_rows)
    : nested_dissection_rows_(nested_dissection_rows) {}

BarrierSolver::BarrierSolver(const BarrierSolver& other)
    : nested_dissection_rows_(other.nested_dissection_rows_),
      analysed_(other.analysed_ ? other.analysed_->clone() : nullptr) {}

BarrierSolver::~BarrierSolver() = default;

bool BarrierSolver::nested_dissection() const {
  return analysed_ && static_cast<const SharedAnalysisCholesky&>(*analysed_).nested_dissection();
}

void BarrierSolver::solve_once(ClpSimplex& model) {
  // As ClpSolve's barrier path: borrow the model's arrays, no event handler, no scaling.
  ClpInterior barrier;
  barrier.borrowModel(model);
  barrier.eventHandler()->setSimplex(nullptr);
  barrier.setCholesky(analysed_ ? analysed_->clone()
                                : new SharedAnalysisCholesky(&analysed_, nested_dissection_rows_));
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
