#include "unjam/solver/klu_factor.hpp"

#include <vector>

#include <Eigen/SparseCore>

#include <klu.h>

#include "unjam/core/nested_dissection.hpp"

namespace unjam {

namespace {
constexpr double kMinGrowth = 1e-8;  // reciprocal pivot growth below which KLU factorises afresh
// KluPivoting::diagonal: its pivot tolerance, and the rows from which it applies (below,
// nested dissection leaves as much fill as AMD and partial pivoting stays on the diagonal).
constexpr double kDiagonalTolerance = 1e-6;
constexpr int kDiagonalMinRows = 3000;
constexpr double kPartialTolerance = 1e-3;  // KLU's default

// S + S^T's ordering by nested dissection, the pressure row and column last; empty if METIS fails.
std::vector<int> symmetric_order(const Eigen::SparseMatrix<double>& S) {
  const Eigen::SparseMatrix<double> P = S + Eigen::SparseMatrix<double>(S.transpose());
  std::vector<int> count(static_cast<std::size_t>(P.cols()));  // P is symmetric: its rows' counts
  for (int j = 0; j < P.outerSize(); ++j) count[static_cast<std::size_t>(j)] = static_cast<int>(P.innerVector(j).nonZeros());
  return nested_dissection_order(P, dense_rows(count));
}
}  // namespace

struct KluFactor::Impl {
  KluPivoting pivoting;
  klu_common common;
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  int fresh = 0;
  bool diagonal_pivots = false;  // the present factors are the diagonal's attempt
  explicit Impl(KluPivoting p) : pivoting(p) { klu_defaults(&common); }
  ~Impl() {
    if (numeric) klu_free_numeric(&numeric, &common);
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
};

KluFactor::KluFactor(KluPivoting pivoting) : impl_(std::make_unique<Impl>(pivoting)) {}
KluFactor::~KluFactor() = default;

bool KluFactor::factorize(Eigen::SparseMatrix<double>& S, bool reuse_pivots) {
  Impl& k = *impl_;
  const int n = static_cast<int>(S.rows());
  const bool diagonal = k.pivoting == KluPivoting::diagonal && n >= kDiagonalMinRows;
  if (!k.symbolic && diagonal) {
    std::vector<int> order = symmetric_order(S);
    if (!order.empty())
      k.symbolic = klu_analyze_given(n, S.outerIndexPtr(), S.innerIndexPtr(), order.data(), order.data(), &k.common);
  }
  if (!k.symbolic) k.symbolic = klu_analyze(n, S.outerIndexPtr(), S.innerIndexPtr(), &k.common);
  if (!k.symbolic) return false;
  const auto stable = [&] {
    return klu_rgrowth(S.outerIndexPtr(), S.innerIndexPtr(), S.valuePtr(), k.symbolic, k.numeric, &k.common) &&
           k.common.rgrowth > kMinGrowth;
  };
  if (k.numeric && reuse_pivots &&
      klu_refactor(S.outerIndexPtr(), S.innerIndexPtr(), S.valuePtr(), k.symbolic, k.numeric, &k.common) && stable())
    return true;
  const auto fresh = [&](double tol) {
    if (k.numeric) klu_free_numeric(&k.numeric, &k.common);
    k.common.tol = tol;
    k.numeric = klu_factor(S.outerIndexPtr(), S.innerIndexPtr(), S.valuePtr(), k.symbolic, &k.common);
    ++k.fresh;
    k.diagonal_pivots = false;
  };
  if (diagonal) {  // the diagonal's pivots, unless they grow more than a refactorisation may
    fresh(kDiagonalTolerance);
    k.diagonal_pivots = k.numeric && stable();
    if (k.diagonal_pivots) return true;
  }
  fresh(kPartialTolerance);
  return k.numeric != nullptr;
}

void KluFactor::solve_in_place(Eigen::MatrixXd& B) {
  klu_solve(impl_->symbolic, impl_->numeric, static_cast<int>(B.rows()), static_cast<int>(B.cols()), B.data(),
            &impl_->common);
}

void KluFactor::solve_in_place(Eigen::VectorXd& b) {
  klu_solve(impl_->symbolic, impl_->numeric, static_cast<int>(b.size()), 1, b.data(), &impl_->common);
}

int KluFactor::fresh() const { return impl_->fresh; }

bool KluFactor::diagonal_pivots() const { return impl_->diagonal_pivots; }

double KluFactor::factor_nonzeros() const {
  return impl_->numeric ? static_cast<double>(impl_->numeric->lnz + impl_->numeric->unz) : 0.0;
}

}  // namespace unjam
