#pragma once
// The normal equations of CLP's interior-point method for the force-bound LPs: at every
// barrier iteration, (A D A^T + S + delta^2 I) dy = r with A the m x n constraint matrix (fixed
// for a sequence of LPs), D > 0 and S >= 0 diagonal (columns' and slacks' scaling, changing
// every iteration; S = 0 for our equality rows). CLP's sparse LDL^T (ClpCholeskyBase) solves
// them. This subclass changes four things (each measured, with the optima equal to CLP's own
// path to its accuracy, in docs/ensemble.md, "Bounds of a 2000-disk packing (measured)", and
// docs/benchmarks.md, section 7):
//   - ordering and symbolic analysis are done once, on the first LP, and shared by copies
//     (CLP repeats them for every LP);
//   - the factor switches to dense storage only when the trailing block is kGoDense = 95 %
//     full (CLP: 70 %): the packings' separators are sparse and the dense kernel wastes work
//     on their zeros;
//   - A D A^T is formed by a scatter precomputed from A and the factor's pattern: every pair
//     (p, q) of entries of a column c adds A_pc A_qc d_c to one fixed slot of the factor's
//     storage (CLP forms it row by row through a dense work vector and gathers it into the
//     pattern);
//   - from `nested_dissection_rows` rows of A on, the rows are ordered by METIS's nested
//     dissection (dense rows, as the pressure row, last) instead of CLP's minimum degree.
//     A packing's contact graph is nearly planar, where nested dissection needs the fewest
//     operations as it grows; below BarrierSolver's default threshold
//     (kNestedDissectionMinRows) it is not measurably faster than CLP's ordering.
// Everything else (which rows are dropped for small pivots, the perturbation of the diagonal,
// the factorisation itself and the solves) is CLP's.
#include <memory>
#include <vector>

#include <coin/ClpCholeskyBase.hpp>

namespace unjam {

class NormalEquationsCholesky : public ClpCholeskyBase {
 public:
  // Fill fraction of the factor's trailing block from which it is stored dense (see above).
  static constexpr double kGoDense = 0.95;

  // The first solve's analysis is handed, as a copy, to `*keep` (see BarrierSolver).
  NormalEquationsCholesky(std::unique_ptr<ClpCholeskyBase>* keep, int nested_dissection_rows);
  NormalEquationsCholesky(const NormalEquationsCholesky&) = default;
  ClpCholeskyBase* clone() const override { return new NormalEquationsCholesky(*this); }

  // The first call orders (CLP's minimum degree, or nested dissection) and analyses; on an
  // analysed object they only learn the new interior model.
  int order(ClpInterior* model) override;
  int symbolic() override;
  // CLP's factorize with A D A^T formed by the scatter. CLP's own path is taken where the
  // scatter does not apply: KKT form, dense columns, rows dropped for good (empty rows of A),
  // or 2000 iterations and more (CLP then keeps dropped rows out).
  int factorize(const CoinWorkDouble* diagonal, int* rowsDropped) override;

  bool nested_dissection() const { return nested_dissection_; }
  // Whether factorize forms A D A^T by the scatter (built by the analysis).
  bool scatter_assembly() const { return scatter_ != nullptr; }

 private:
  // The A D A^T scatter: the pairs of column c are [start[c], start[c+1]); slot >= 0 is an
  // index of sparseFactor_ (row i, column j > i of the permuted matrix), slot < 0 the
  // diagonal entry -1 - slot; coef = A_pc A_qc.
  struct Scatter {
    std::vector<int> start;
    std::vector<CoinBigIndex> slot;
    std::vector<double> coef;
  };
  // The scatter of the analysed pattern, or null if some entry of A D A^T has no slot in it
  // or A has an empty row.
  std::shared_ptr<const Scatter> make_scatter() const;

  std::unique_ptr<ClpCholeskyBase>* keep_;  // where the first analysis goes (null after)
  int nested_dissection_rows_;
  bool nested_dissection_ = false;
  bool analysed_ = false;
  std::shared_ptr<const Scatter> scatter_;  // shared by all copies (A is the same)
};

}  // namespace unjam
