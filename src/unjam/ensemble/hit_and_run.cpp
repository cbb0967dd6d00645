#include "unjam/ensemble/hit_and_run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <coin/ClpSimplex.hpp>

#include "unjam/core/error.hpp"

namespace unjam {

namespace {

// The equalities restricted to the walked columns, with the QR of their transpose:
// A^T P = Q R. The first `rank` columns of Q span the row space, the rest the null space.
struct AffineSet {
  Eigen::MatrixXd A;  // m x n
  Eigen::VectorXd rhs;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  int rank = 0;

  // Moves y to the nearest point of A y = rhs (minimal-norm correction in the row space).
  void project(Eigen::VectorXd& y) const {
    const Eigen::VectorXd r = qr.colsPermutation().transpose() * (rhs - A * y);
    const auto R = qr.matrixR().topLeftCorner(rank, rank);
    const Eigen::VectorXd z =
        R.transpose().triangularView<Eigen::Lower>().solve(r.head(rank));
    Eigen::VectorXd full = Eigen::VectorXd::Zero(y.size());
    full.head(rank) = z;
    y += qr.householderQ() * full;
  }
};

// Chebyshev-like centre: max s subject to A y = rhs, y_i >= s. Returns y and sets depth = s.
Eigen::VectorXd interior_point(const AffineSet& set, double& depth) {
  const int m = static_cast<int>(set.A.rows()), n = static_cast<int>(set.A.cols());
  // Columns y_0 .. y_n-1, s; rows: the m equalities, then y_i - s >= 0.
  std::vector<CoinBigIndex> start{0};
  std::vector<int> index;
  std::vector<double> value;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < m; ++i)
      if (set.A(i, j) != 0.0) {
        index.push_back(i);
        value.push_back(set.A(i, j));
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
  for (int i = 0; i < m; ++i) row_lb[i] = row_ub[i] = set.rhs[i];
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
  if (n > options.max_dense_columns)
    throw Error("hit-and-run: " + std::to_string(n) + " cone columns exceed the dense "
                "null-space limit of " + std::to_string(options.max_dense_columns) +
                " (about " + std::to_string(options.max_dense_columns / 2) + " contacts)");

  const Eigen::SparseMatrix<double> Ay = cone_matrix(system);
  AffineSet set;
  set.A.resize(Ay.rows(), n);
  for (int j = 0; j < n; ++j) set.A.col(j) = Ay.col(free_cols[j]);
  set.rhs = system.rhs;
  set.qr.setThreshold(1e-10);
  set.qr.compute(set.A.transpose());
  set.rank = static_cast<int>(set.qr.rank());
  const int d = n - set.rank;
  result.dimension = d;
  const Eigen::MatrixXd Q = set.qr.householderQ();
  const Eigen::MatrixXd B = Q.rightCols(d);  // orthonormal null-space basis, n x d

  Eigen::VectorXd y = interior_point(set, result.start_depth);
  set.project(y);
  if (d > 0 && result.start_depth <= options.fixed_tol * system.F0)
    throw Error("hit-and-run: the admissible set has no interior in its affine hull (centre "
                "depth " + std::to_string(result.start_depth) + "): some contact slides or "
                "stays open in every network; the sampler needs those fixed first");

  const int thin = options.thin > 0 ? options.thin : std::max(1, d);
  const long long burn_in = options.burn_in > 0 ? options.burn_in : 100LL * std::max(1, d);
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Eigen::VectorXd z(d), dir(n), y_full = Eigen::VectorXd::Zero(per * Nc);
  constexpr long long kProjectEvery = 1000;

  auto step = [&]() {
    if (d == 0) return;
    for (int i = 0; i < d; ++i) z[i] = normal(rng);
    dir.noalias() = B * (z / z.norm());
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
    if (++result.steps % kProjectEvery == 0) set.project(y);
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
