#include "unjam/ensemble/hit_and_run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <coin/ClpSimplex.hpp>

#include "unjam/core/error.hpp"
#include "unjam/lp/rank.hpp"

namespace unjam {

namespace {

// The affine set { y : A y = rhs } of the walked columns (A: m x n, sparse), as the walk
// needs it: the dimension of its direction space null(A), a uniformly random unit direction
// in that space, and the projection of a point back onto the set.
class AffineSet {
 public:
  virtual ~AffineSet() = default;
  int dimension() const { return dimension_; }
  // dir: uniform on the unit sphere of null(A), from standard normal numbers of `normal`.
  virtual void direction(std::mt19937_64& rng, std::normal_distribution<double>& normal,
                         Eigen::VectorXd& dir) const = 0;
  // Moves y to the nearest point of A y = rhs (minimal-norm correction in the row space).
  virtual void project(Eigen::VectorXd& y) const = 0;

 protected:
  int dimension_ = 0;
};

// Up to max_dense_columns: an orthonormal null-space basis B from the dense column-pivoting
// QR of A^T (A^T P = Q R; the first `rank` columns of Q span the row space, the rest the null
// space), and dir = B z / |z| with z standard normal in R^d.
class DenseAffineSet : public AffineSet {
 public:
  DenseAffineSet(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& rhs)
      : A_(A), rhs_(rhs) {
    qr_.setThreshold(1e-10);
    qr_.compute(A_.transpose());
    rank_ = static_cast<int>(qr_.rank());
    dimension_ = static_cast<int>(A_.cols()) - rank_;
    const Eigen::MatrixXd Q = qr_.householderQ();
    B_ = Q.rightCols(dimension_);
  }
  void direction(std::mt19937_64& rng, std::normal_distribution<double>& normal,
                 Eigen::VectorXd& dir) const override {
    Eigen::VectorXd z(dimension_);
    for (int i = 0; i < dimension_; ++i) z[i] = normal(rng);
    dir.noalias() = B_ * (z / z.norm());
  }
  void project(Eigen::VectorXd& y) const override {
    const Eigen::VectorXd r = qr_.colsPermutation().transpose() * (rhs_ - A_ * y);
    const auto R = qr_.matrixR().topLeftCorner(rank_, rank_);
    const Eigen::VectorXd z = R.transpose().triangularView<Eigen::Lower>().solve(r.head(rank_));
    Eigen::VectorXd full = Eigen::VectorXd::Zero(y.size());
    full.head(rank_) = z;
    y += qr_.householderQ() * full;
  }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd rhs_;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr_;
  Eigen::MatrixXd B_;  // n x d
  int rank_ = 0;
};

// Beyond max_dense_columns: the orthogonal projector onto null(A),
//     P r = r - A^T x,   (A A^T) x = A r,
// with one sparse LDLT of A A^T + delta I (RegularisedGram of A^T, lp/rank.hpp:
// the dependent rows of A make A A^T singular) and two steps of iterative refinement against
// A A^T, which remove the regularisation's error. dir = P r / |P r| with r standard normal in
// R^n: P r is an isotropic Gaussian in null(A), so dir is uniform on its sphere, as in the
// dense case. The dimension is n - rank(A) by numerical_rank, on the same factorisation
// when A^T is tall (as for a packing: more cone columns than rows).
class SparseAffineSet : public AffineSet {
 public:
  SparseAffineSet(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& rhs)
      : A_(A), At_(A.transpose()), rhs_(rhs), AAt_(At_) {
    const int rank = At_.rows() >= At_.cols() ? numerical_rank(At_, AAt_) : numerical_rank(A_);
    dimension_ = static_cast<int>(A_.cols()) - rank;
  }
  void direction(std::mt19937_64& rng, std::normal_distribution<double>& normal,
                 Eigen::VectorXd& dir) const override {
    Eigen::VectorXd r(A_.cols());
    for (Eigen::Index i = 0; i < r.size(); ++i) r[i] = normal(rng);
    dir = r - At_ * row_space_solve(A_ * r);
    dir /= dir.norm();
  }
  void project(Eigen::VectorXd& y) const override {
    y += At_ * row_space_solve(rhs_ - A_ * y);
  }

 private:
  // x with (A A^T) x = b for b in the range of A.
  Eigen::VectorXd row_space_solve(const Eigen::VectorXd& b) const {
    Eigen::VectorXd x = AAt_.ldlt.solve(b);
    for (int refine = 0; refine < 2; ++refine) x += AAt_.ldlt.solve(b - AAt_.G * x);
    return x;
  }

  Eigen::SparseMatrix<double> A_, At_;
  Eigen::VectorXd rhs_;
  RegularisedGram AAt_;  // G = A A^T and its regularised LDLT
};

// Chebyshev-like centre: max s subject to A y = rhs, y_i >= s. Returns y and sets depth = s.
Eigen::VectorXd interior_point(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& rhs,
                               double& depth) {
  const int m = static_cast<int>(A.rows()), n = static_cast<int>(A.cols());
  // Columns y_0 .. y_n-1, s; rows: the m equalities, then y_i - s >= 0.
  std::vector<CoinBigIndex> start{0};
  std::vector<int> index;
  std::vector<double> value;
  for (int j = 0; j < n; ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it)
      if (it.value() != 0.0) {
        index.push_back(static_cast<int>(it.row()));
        value.push_back(it.value());
      }
    index.push_back(m + j);
    value.push_back(1.0);
    start.push_back(static_cast<CoinBigIndex>(index.size()));
  }
  for (int j = 0; j < n; ++j) {
    index.push_back(m + j);
    value.push_back(-1.0);
  }
  start.push_back(static_cast<CoinBigIndex>(index.size()));
  std::vector<double> col_lb(n + 1, 0.0), col_ub(n + 1, COIN_DBL_MAX), obj(n + 1, 0.0);
  col_lb[n] = -COIN_DBL_MAX;
  obj[n] = -1.0;  // minimise -s
  std::vector<double> row_lb(m + n, 0.0), row_ub(m + n, COIN_DBL_MAX);
  for (int i = 0; i < m; ++i) row_lb[i] = row_ub[i] = rhs[i];
  ClpSimplex model;
  model.setLogLevel(0);
  model.loadProblem(n + 1, m + n, start.data(), index.data(), value.data(), col_lb.data(),
                    col_ub.data(), obj.data(), row_lb.data(), row_ub.data());
  model.dual();
  if (model.status() != 0)
    throw Error("hit-and-run: the centre LP failed (CLP status " +
                std::to_string(model.status()) + ")");
  const double* x = model.primalColumnSolution();
  depth = x[n];
  return Eigen::Map<const Eigen::VectorXd>(x, n);
}

}  // namespace

HitAndRunResult sample_hit_and_run(const EquilibriumSystem& system, const ForceBounds& bounds,
                                   const HitAndRunOptions& options) {
  const int Nc = system.num_contacts();
  const int per = cone_columns_per_contact(system.mu);
  if (options.samples < 1) throw Error("hit-and-run: the number of samples must be >= 1");
  if (bounds.fn_max.size() != Nc) throw Error("hit-and-run: bounds do not match the system");

  // Walked columns: the cone coordinates of every contact that is not open in every network.
  HitAndRunResult result;
  std::vector<int> free_cols;
  for (int k = 0; k < Nc; ++k) {
    if (bounds.fn_max[k] <= options.fixed_tol * system.F0) {
      ++result.fixed_open;
      continue;
    }
    for (int j = 0; j < per; ++j) free_cols.push_back(per * k + j);
  }
  const int n = static_cast<int>(free_cols.size());
  const Eigen::SparseMatrix<double> Ay = cone_matrix(system);
  Eigen::SparseMatrix<double> A(Ay.rows(), n);
  {
    std::vector<Eigen::Triplet<double>> entries;
    for (int j = 0; j < n; ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(Ay, free_cols[j]); it; ++it)
        entries.emplace_back(static_cast<int>(it.row()), j, it.value());
    A.setFromTriplets(entries.begin(), entries.end());
  }
  std::unique_ptr<AffineSet> set;
  if (n <= options.max_dense_columns)
    set = std::make_unique<DenseAffineSet>(A, system.rhs);
  else
    set = std::make_unique<SparseAffineSet>(A, system.rhs);
  const int d = set->dimension();
  result.dimension = d;

  Eigen::VectorXd y = interior_point(A, system.rhs, result.start_depth);
  set->project(y);
  if (d > 0 && result.start_depth <= options.fixed_tol * system.F0)
    throw Error("hit-and-run: the admissible set has no interior in its affine hull (centre "
                "depth " + std::to_string(result.start_depth) + "): some contact slides or "
                "stays open in every network; the sampler needs those fixed first");

  const int thin = options.thin > 0 ? options.thin : std::max(1, d);
  const long long burn_in = options.burn_in > 0 ? options.burn_in : 100LL * std::max(1, d);
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Eigen::VectorXd dir(n), y_full = Eigen::VectorXd::Zero(per * Nc);
  constexpr long long kProjectEvery = 1000;

  auto step = [&]() {
    if (d == 0) return;
    set->direction(rng, normal, dir);
    // Chord {t : y + t dir >= 0}.
    double t_min = -std::numeric_limits<double>::infinity();
    double t_max = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i) {
      if (dir[i] > 0.0)
        t_min = std::max(t_min, -y[i] / dir[i]);
      else if (dir[i] < 0.0)
        t_max = std::min(t_max, -y[i] / dir[i]);
    }
    if (!(t_min <= t_max) || !std::isfinite(t_min) || !std::isfinite(t_max))
      throw Error("hit-and-run: unbounded or empty chord (the admissible set is not a "
                  "bounded polytope)");
    y += (t_min + (t_max - t_min) * uniform(rng)) * dir;
    if (++result.steps % kProjectEvery == 0) set->project(y);
  };

  for (long long s = 0; s < burn_in; ++s) step();

  // Welford running mean and variance of fn per contact.
  SampledForcesAccumulator stats(Nc);
  ForceNetwork net;
  for (int s = 0; s < options.samples; ++s) {
    for (int t = 0; t < thin; ++t) step();
    for (int j = 0; j < n; ++j) y_full[free_cols[j]] = y[j];
    cone_to_forces(system, y_full, net.fn, net.ft);
    stats.add(net.fn);
    if (options.on_sample) options.on_sample(net);
  }
  result.samples = options.samples;
  static_cast<SampledForces&>(result) = stats.result();
  return result;
}

}  // namespace unjam
