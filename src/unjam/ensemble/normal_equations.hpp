#pragma once
// The normal equations of CLP's interior-point method for the force-bound LPs: at every
// barrier iteration, (A D A^T + S + delta^2 I) dy = r with A the m x n constraint matrix (fixed
// for a sequence of LPs), D > 0 and S >= 0 diagonal (columns' and slacks' scaling, changing
// every iteration; S = 0 for our equality rows). CLP's sparse LDL^T (ClpCholeskyBase) solves
// them; this subclass changes three things, all measured in lp_barrier.hpp:
//   - ordering and symbolic analysis are done once, on the first LP, and shared by copies;
//   - from `nested_dissection_rows` rows of A on, the ordering is METIS's nested dissection;
//   - A D A^T is formed by a scatter precomputed from A and the factor's pattern: every pair
//     (p, q) of entries of a column c adds A_pc A_qc d_c to one fixed slot of the factor's
//     storage. CLP forms it row by row through a dense work vector and gathers it into the
//     pattern, ~17 % of a 2000-disk LP; the scatter takes ~5 %.
// Everything else (which rows are dropped for small pivots, the perturbation of the diagonal,
// the factorisation itself and the solves) is CLP's.
#include <memory>
#include <vector>

#include <coin/ClpCholeskyBase.hpp>

namespace unjam {

class NormalEquationsCholesky : public ClpCholeskyBase {
 public:
  // The first solve's analysis is handed, as a copy, to `*keep` (see BarrierSolver); the
  // factor is stored dense from where its trailing block is `go_dense` full.
  NormalEquationsCholesky(std::unique_ptr<ClpCholeskyBase>* keep, int nested_dissection_rows,
                          double go_dense);
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
