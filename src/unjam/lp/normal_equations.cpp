#include "unjam/lp/normal_equations.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/SparseCore>
#include <coin/ClpInterior.hpp>

#include "unjam/core/nested_dissection.hpp"

namespace unjam {

namespace {

// A fill-reducing ordering of A D A^T by METIS's nested dissection (core/nested_dissection),
// as CLP stores it: permute[new] = old row. The dense rows of A (as the pressure row: its row
// of A D A^T is full) are ordered last. Empty if METIS fails.
std::vector<int> normal_equations_order(const ClpMatrixBase& A, int rows) {
  const int cols = A.getNumCols();
  const CoinBigIndex* start = A.getVectorStarts();
  const int* length = A.getVectorLengths();
  const int* row = A.getIndices();
  std::vector<int> count(rows, 0);
  for (int j = 0; j < cols; ++j)
    for (CoinBigIndex e = start[j]; e < start[j] + length[j]; ++e) ++count[row[e]];
  // Pattern of A A^T.
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int j = 0; j < cols; ++j)
    for (CoinBigIndex e = start[j]; e < start[j] + length[j]; ++e) entries.emplace_back(row[e], j, 1.0);
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> B(rows, cols);
  B.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SparseMatrix<double, Eigen::ColMajor, int> BBt = B * B.transpose();
  return nested_dissection_order(BBt, dense_rows(count));
}

}  // namespace

NormalEquationsCholesky::NormalEquationsCholesky(std::unique_ptr<ClpCholeskyBase>* keep,
                                                 int nested_dissection_rows)
    : keep_(keep), nested_dissection_rows_(nested_dissection_rows) {
  goDense_ = kGoDense;
}

int NormalEquationsCholesky::order(ClpInterior* model) {
  if (analysed_) {
    model_ = model;
    resetRowsDropped();
    return 0;
  }
  // CLP's order() also builds the row copy and sizes that symbolic() needs; for large
  // matrices its minimum-degree permutation is then replaced (kept if METIS fails).
  const int status = ClpCholeskyBase::order(model);
  if (status != 0 || numberRows_ < nested_dissection_rows_) return status;
  const std::vector<int> permute = normal_equations_order(*model->clpMatrix(), numberRows_);
  if (permute.empty()) return 0;
  for (int i = 0; i < numberRows_; ++i) {
    permute_[i] = permute[i];
    permuteInverse_[permute[i]] = i;
  }
  nested_dissection_ = true;
  return 0;
}

int NormalEquationsCholesky::symbolic() {
  if (analysed_) return 0;
  const int status = ClpCholeskyBase::symbolic();
  if (status == 0) {
    analysed_ = true;
    scatter_ = make_scatter();
    auto* analysed = new NormalEquationsCholesky(*this);
    analysed->keep_ = nullptr;
    keep_->reset(analysed);
  }
  return status;
}

std::shared_ptr<const NormalEquationsCholesky::Scatter> NormalEquationsCholesky::make_scatter()
    const {
  const ClpMatrixBase& A = *model_->clpMatrix();
  const int* row_length = rowCopy_->getVectorLengths();
  if (std::find(row_length, row_length + numberRows_, 0) != row_length + numberRows_)
    return nullptr;
  const int cols = A.getNumCols();
  const CoinBigIndex* start = A.getVectorStarts();
  const int* length = A.getVectorLengths();
  const int* row = A.getIndices();
  const double* value = A.getElements();
  auto scatter = std::make_shared<Scatter>();
  scatter->start.push_back(0);
  for (int c = 0; c < cols; ++c) {
    for (CoinBigIndex e = start[c]; e < start[c] + length[c]; ++e) {
      const int i = permuteInverse_[row[e]];
      for (CoinBigIndex f = start[c]; f < start[c] + length[c]; ++f) {
        const int j = permuteInverse_[row[f]];
        if (j < i) continue;
        if (j == i) {
          scatter->slot.push_back(-1 - i);
        } else {
          // Row i of the factor holds its columns j > i, sorted, from choleskyStart_[i].
          const int n = choleskyStart_[i + 1] - choleskyStart_[i];
          const CoinBigIndex* column = choleskyRow_ + indexStart_[i];
          const CoinBigIndex* at = std::lower_bound(column, column + n, j);
          if (at == column + n || *at != j) return nullptr;
          scatter->slot.push_back(choleskyStart_[i] + static_cast<CoinBigIndex>(at - column));
        }
        scatter->coef.push_back(value[e] * value[f]);
      }
    }
    scatter->start.push_back(static_cast<int>(scatter->slot.size()));
  }
  return scatter;
}

int NormalEquationsCholesky::factorize(const CoinWorkDouble* diagonal, int* rowsDropped) {
  if (!scatter_ || doKKT_ || whichDense_ || model_->numberIterations() >= 2000 ||
      std::any_of(rowsDropped_, rowsDropped_ + numberRows_, [](char c) { return c != 0; }))
    return ClpCholeskyBase::factorize(diagonal, rowsDropped);
  // A D A^T + S + delta^2 I into the factor's storage (the lower triangle of the permuted
  // matrix: diagonal_ and, row by row, sparseFactor_ up to choleskyStart_[numberRows_]).
  const int columns = model_->clpMatrix()->getNumCols();
  const CoinWorkDouble* slack = diagonal + columns;
  const CoinWorkDouble delta2 = model_->delta() * model_->delta();
  const CoinBigIndex lower_size = choleskyStart_[numberRows_];
  std::fill_n(sparseFactor_, lower_size, 0.0);
  for (int i = 0; i < numberRows_; ++i) diagonal_[i] = slack[permute_[i]] + delta2;
  const Scatter& s = *scatter_;
  for (int c = 0; c < columns; ++c) {
    const CoinWorkDouble d = diagonal[c];
    for (int e = s.start[c]; e < s.start[c + 1]; ++e) {
      const CoinBigIndex slot = s.slot[e];
      (slot >= 0 ? sparseFactor_[slot] : diagonal_[-1 - slot]) += s.coef[e] * d;
    }
  }
  // From here on as CLP: a row whose diagonal is below 1e-20 of the largest entry is dropped
  // before the factorisation, pivots below doubleParameters_[10] during it.
  CoinWorkDouble largest = 1.0e-20;
  for (CoinBigIndex k = 0; k < lower_size; ++k)
    largest = std::max<CoinWorkDouble>(largest, std::abs(sparseFactor_[k]));
  for (int i = 0; i < numberRows_; ++i)
    largest = std::max<CoinWorkDouble>(largest, std::abs(diagonal_[i]));
  const CoinWorkDouble drop_below = 1.0e-20 * largest;
  const CoinWorkDouble perturbation =
      std::min<CoinWorkDouble>(model_->diagonalPerturbation() * model_->diagonalNorm(), 1.0);
  int dropped_before = 0;
  for (int i = 0; i < numberRows_; ++i) {
    rowsDropped[i] = diagonal_[i] > drop_below ? 0 : 2;
    dropped_before += rowsDropped[i] != 0;
    diagonal_[i] += perturbation;
  }
  doubleParameters_[10] = std::max(1.0e-20, std::min<double>(drop_below, CHOL_SMALL_VALUE));
  integerParameters_[20] = 0;  // rows dropped by factorizePart2
  doubleParameters_[3] = 0.0;  // largest and smallest pivot
  doubleParameters_[4] = COIN_DBL_MAX;
  integerParameters_[34] = 0;  // every pivot must be positive
  factorizePart2(rowsDropped);
  choleskyCondition_ = doubleParameters_[3] / doubleParameters_[4];
  // CLP's return below 2000 iterations: 0, or -(2 + k) with the k rows dropped this time
  // listed first in rowsDropped; no row stays dropped for the next factorisation.
  int dropped = integerParameters_[20] + dropped_before;
  if (dropped || numberRowsDropped_) {
    dropped = 0;
    for (int i = 0; i < numberRows_; ++i) {
      rowsDropped_[i] = 0;
      if (rowsDropped[i] == 2) rowsDropped[dropped++] = i;
    }
    numberRowsDropped_ = dropped;
    dropped = -(2 + dropped);
  }
  status_ = 0;
  return dropped;
}

}  // namespace unjam
