// least_norm_solution against the dense formula x = D B^T (B D B^T)^-1 d, on random sparse
// systems with one dense column (the cell's strain in the probe), so the Woodbury path is
// exercised, and on one with a dependent row (a self-stress).
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <gtest/gtest.h>

#include "unjam/core/least_norm.hpp"

namespace {

using Sparse = Eigen::SparseMatrix<double>;

// rows x cols, a few random entries per row plus a full column 0 (dense: > 64 entries).
Sparse random_rows(int rows, int cols, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> column(1, cols - 1);
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < rows; ++i) {
    t.emplace_back(i, 0, value(rng));
    t.emplace_back(i, 1 + i % (cols - 1), 2.0 + value(rng));  // keeps the rows independent
    for (int k = 0; k < 4; ++k) t.emplace_back(i, column(rng), value(rng));
  }
  Sparse m(rows, cols);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

Eigen::VectorXd positive_weights(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> w(0.5, 2.0);
  Eigen::VectorXd D(n);
  for (int i = 0; i < n; ++i) D[i] = w(rng);
  return D;
}

Eigen::VectorXd dense_least_norm(const Sparse& B, const Eigen::VectorXd& D,
                                 const Eigen::VectorXd& d) {
  const Eigen::MatrixXd Bd(B);
  const Eigen::MatrixXd W = Bd * D.asDiagonal() * Bd.transpose();
  return D.asDiagonal() * Bd.transpose() * W.fullPivLu().solve(d);
}

TEST(LeastNorm, MatchesTheDenseFormulaWithADenseColumn) {
  std::mt19937_64 rng(7);
  const Sparse B = random_rows(100, 300, rng);
  const Eigen::VectorXd D = positive_weights(300, rng), d = Eigen::VectorXd::Random(100);
  const auto x = unjam::least_norm_solution(B, D, d);
  ASSERT_TRUE(x.has_value());
  const Eigen::VectorXd ref = dense_least_norm(B, D, d);
  EXPECT_LT((*x - ref).norm(), 1e-10 * ref.norm());
  EXPECT_LT((B * *x - d).norm(), 1e-10 * d.norm());
}


TEST(LeastNorm, SolvesASystemWithADependentRow) {
  // Row 2 = row 0 + row 1 (a self-stress): B D B^T is singular; with d consistent the
  // regularised, refined solve still meets B x = d and is the least-norm solution.
  std::mt19937_64 rng(3);
  Eigen::SparseMatrix<double, Eigen::RowMajor> B_rows = random_rows(80, 200, rng);
  B_rows.row(2) = B_rows.row(0) + B_rows.row(1);
  const Sparse B = B_rows;
  const Eigen::VectorXd D = positive_weights(200, rng);
  Eigen::VectorXd d = Eigen::VectorXd::Random(80);
  d[2] = d[0] + d[1];
  const auto x = unjam::least_norm_solution(B, D, d, 6);
  ASSERT_TRUE(x.has_value());
  EXPECT_LT((B * *x - d).norm(), 1e-8 * d.norm());
  // Least norm in the metric D^-1: x lies in the range of D B^T, i.e. D^-1 x is orthogonal
  // to the null space of B. Check against a perturbation along a null vector of B.
  const Eigen::MatrixXd Bd(B);
  const Eigen::MatrixXd N = Bd.fullPivLu().kernel();
  const Eigen::VectorXd w = D.cwiseInverse().asDiagonal() * *x;
  EXPECT_LT((N.transpose() * w).norm(), 1e-8 * w.norm() * std::sqrt(double(N.cols())));
}

TEST(LeastNorm, ActiveSetRoundsUntilNothingChanges) {
  // The least-norm x with a . x = 1 and x >= 0, by solve_active_set: the set holds x_i = 0
  // (a row e_i^T x = 0) for every component that came out negative. With a = (1, -1, 2, -2)
  // the first solve gives x = a / 10 (two negative components), the second x = (1, 0, 2, 0) / 5,
  // which needs no change.
  const Eigen::Vector4d a(1.0, -1.0, 2.0, -2.0);
  const auto run = [&](int max_rounds, Eigen::VectorXd& x) {
    std::vector<char> held(4, 0);
    const auto system = [&] {
      std::vector<Eigen::Triplet<double>> t;
      for (int i = 0; i < 4; ++i) t.emplace_back(0, i, a[i]);
      int rows = 1;
      for (int i = 0; i < 4; ++i)
        if (held[i]) t.emplace_back(rows++, i, 1.0);
      unjam::LeastNormSystem ls;
      ls.B.resize(rows, 4);
      ls.B.setFromTriplets(t.begin(), t.end());
      ls.D = Eigen::VectorXd::Ones(4);
      ls.d = Eigen::VectorXd::Zero(rows);
      ls.d[0] = 1.0;
      return ls;
    };
    const auto update = [&](const unjam::LeastNormSystem&, const Eigen::VectorXd& sol) {
      x = sol;
      int changes = 0;
      for (int i = 0; i < 4; ++i)
        if (!held[i] && x[i] < -1e-12) held[i] = 1, ++changes;
      return changes;
    };
    return unjam::solve_active_set(max_rounds, system, update);
  };
  Eigen::VectorXd x;
  const unjam::ActiveSetRounds settled = run(10, x);
  EXPECT_TRUE(settled.settled());
  EXPECT_EQ(settled.rounds, 2);
  EXPECT_LT((x - Eigen::Vector4d(0.2, 0.0, 0.4, 0.0)).norm(), 1e-12);

  const unjam::ActiveSetRounds cut = run(1, x);  // the round limit: one solve, changes left
  EXPECT_FALSE(cut.settled());
  EXPECT_TRUE(cut.factorised);
  EXPECT_EQ(cut.rounds, 1);
  EXPECT_EQ(cut.changes, 2);
  EXPECT_LT((x - a / 10.0).norm(), 1e-12);
}

}  // namespace
