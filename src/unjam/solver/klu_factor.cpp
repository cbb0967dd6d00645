#include "unjam/solver/klu_factor.hpp"

#include <Eigen/SparseCore>

#include <klu.h>

namespace unjam {

namespace {
constexpr double kMinGrowth = 1e-8;  // reciprocal pivot growth below which KLU factorises afresh
}  // namespace

struct KluFactor::Impl {
  klu_common common;
  klu_symbolic* symbolic = nullptr;
  klu_numeric* numeric = nullptr;
  int fresh = 0;
  Impl() { klu_defaults(&common); }
  ~Impl() {
    if (numeric) klu_free_numeric(&numeric, &common);
    if (symbolic) klu_free_symbolic(&symbolic, &common);
  }
};

KluFactor::KluFactor() : impl_(std::make_unique<Impl>()) {}
KluFactor::~KluFactor() = default;

bool KluFactor::factorize(Eigen::SparseMatrix<double>& S, bool reuse_pivots) {
  Impl& k = *impl_;
  const int n = static_cast<int>(S.rows());
  if (!k.symbolic) k.symbolic = klu_analyze(n, S.outerIndexPtr(), S.innerIndexPtr(), &k.common);
  if (!k.symbolic) return false;
  if (k.numeric && reuse_pivots &&
      klu_refactor(S.outerIndexPtr(), S.innerIndexPtr(), S.valuePtr(), k.symbolic, k.numeric, &k.common) &&
      klu_rgrowth(S.outerIndexPtr(), S.innerIndexPtr(), S.valuePtr(), k.symbolic, k.numeric, &k.common) &&
      k.common.rgrowth > kMinGrowth)
    return true;
  if (k.numeric) klu_free_numeric(&k.numeric, &k.common);
  k.numeric = klu_factor(S.outerIndexPtr(), S.innerIndexPtr(), S.valuePtr(), k.symbolic, &k.common);
  ++k.fresh;
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

}  // namespace unjam
