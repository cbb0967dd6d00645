#pragma once
// The normal equations of CLP's interior-point method for the force-bound LPs: at every
// barrier iteration, (A D A^T + S + delta^2 I) dy = r with A the m x n constraint matrix (fixed
// for a sequence of LPs), D > 0 and S >= 0 diagonal (columns' and slacks' scaling, changing
// every iteration; S = 0 for our equality rows). CLP's sparse LDL^T (ClpCholeskyBase) solves
// them. This subclass changes four things, measured on the packings of docs/benchmarks.md
// (the optima agree with CLP's own path to its accuracy, 4e-8 relative over the 2000-disk
// bounds):
//   - ordering and symbolic analysis are done once, on the first LP, and shared by copies
//     (CLP repeats them for every LP): ~3 % per LP;
//   - the factor switches to dense storage only when the trailing block is kGoDense = 95 %
//     full (CLP: 70 %): the packings' separators are sparse and the dense kernel wastes work
//     on their zeros. 0.235 -> 0.195 s per LP at 2000 disks, 2.51 -> 2.02 s at 8000;
//   - A D A^T is formed by a scatter precomputed from A and the factor's pattern: every pair
//     (p, q) of entries of a column c adds A_pc A_qc d_c to one fixed slot of the factor's
//     storage. CLP forms it row by row through a dense work vector and gathers it into the
//     pattern, ~17 % of a 2000-disk LP; the scatter takes ~5 %. Per LP 0.183 -> 0.160 s at
//     2000 disks (max and min LPs of 60 contacts), 1.63 -> 1.45 s at 8000 (4 contacts), the
//     optima equal to 4e-11;
//   - from `nested_dissection_rows` rows of A on, the rows are ordered by METIS's nested
//     dissection (dense rows, as the pressure row, last) instead of CLP's minimum degree.
//     A packing's contact graph is nearly planar, where nested dissection needs the fewest
//     operations as it grows: per LP 0.72 -> 0.63 s at 4000 disks (10 939 rows), 2.36 ->
//     1.89 s at 8000 (21 829 rows); at 2000 disks (5410 rows) it is 2-12 % slower, at 500
//     and 1000 within 10 % (BarrierSolver's default threshold, kNestedDissectionMinRows).
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
