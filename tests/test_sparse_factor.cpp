// The sparse factorisations' building blocks: METIS's nested dissection with dense rows last
// (core/nested_dissection) and KLU with diagonal or partial pivoting (solver/klu_factor).
#include <algorithm>
#include <csignal>
#include <cstdint>
#include <numeric>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/SparseCore>

#include "unjam/core/nested_dissection.hpp"
#include "unjam/solver/klu_factor.hpp"

namespace {

using Sparse = Eigen::SparseMatrix<double>;

// The 5-point operator of a side x side grid, made non-symmetric (east and west couplings
// differ), with a border row and column coupled to every node (as the pressure degree of
// freedom of the probe's systems), the border last. Diagonally dominant: no pivoting needed.
Sparse grid_with_border(int side) {
  const int n = side * side;
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const int r = i * side + j;
      t.emplace_back(r, r, 4.5);
      if (j > 0) t.emplace_back(r, r - 1, -1.2);
      if (j + 1 < side) t.emplace_back(r, r + 1, -0.8);
      if (i > 0) t.emplace_back(r, r - side, -1.0);
      if (i + 1 < side) t.emplace_back(r, r + side, -1.0);
      t.emplace_back(r, n, 1e-3);
      t.emplace_back(n, r, -1e-3);
    }
  t.emplace_back(n, n, 1.0);
  Sparse S(n + 1, n + 1);
  S.setFromTriplets(t.begin(), t.end());
  S.makeCompressed();
  return S;
}

double relative_residual(const Sparse& S, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  return (S * x - b).norm() / b.norm();
}

TEST(NestedDissection, DenseRowsByTheirCount) {
  // 200 rows of 4 entries and one of 300: the mean is ~5.5, so the threshold is 100.
  std::vector<int> count(200, 4);
  count.push_back(300);
  const std::vector<bool> dense = unjam::dense_rows(count);
  EXPECT_EQ(std::count(dense.begin(), dense.end(), true), 1);
  EXPECT_TRUE(dense.back());
  // 100 entries is not dense however small the mean; above 100, more than 10x the mean is.
  std::vector<int> few(100, 1);
  few[0] = 100;
  EXPECT_FALSE(unjam::dense_rows(few)[0]);
  few[0] = 101;
  EXPECT_TRUE(unjam::dense_rows(few)[0]);
  EXPECT_FALSE(unjam::dense_rows({150, 150, 150, 150})[0]);  // 150 is the mean
  EXPECT_FALSE(unjam::dense_rows({300, 20, 20, 20})[0]);     // 300 < 10 x 90
}

// The pattern of grid_with_border(side) as nested_dissection_order reads it, its border row
// marked dense.
struct GridPattern {
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> P;
  std::vector<bool> dense;
  explicit GridPattern(int side) : P(grid_with_border(side)), dense(static_cast<std::size_t>(P.rows()), false) {
    dense.back() = true;
  }
};

TEST(NestedDissection, APermutationWithTheDenseRowLast) {
  const GridPattern grid(30);
  const auto& P = grid.P;
  const auto& dense = grid.dense;
  const std::vector<int> order = unjam::nested_dissection_order(P, dense);
  ASSERT_EQ(order.size(), static_cast<std::size_t>(P.rows()));
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (int i = 0; i < static_cast<int>(sorted.size()); ++i) ASSERT_EQ(sorted[static_cast<std::size_t>(i)], i);
  EXPECT_EQ(order.back(), P.rows() - 1);
  // Nested dissection orders a separator last: not the grid's natural order.
  std::vector<int> natural(order.size());
  std::iota(natural.begin(), natural.end(), 0);
  EXPECT_NE(order, natural);
  EXPECT_EQ(unjam::nested_dissection_order(P, dense), order);  // deterministic
}

extern "C" void count_signal(int) {}

// METIS swaps the process's SIGTERM and SIGABRT handlers during each call and puts back the
// one it found from a per-thread record: two threads calling it at once would leave its own
// handler installed, and the next SIGTERM would jump into a finished call (a crash of a
// 2-thread campaign at 1000 disks). The orderings are made one at a time and every call puts
// the process's handlers back: after many calls from two threads they are still ours, and
// every ordering is the one of a single thread.
TEST(NestedDissection, CallsFromTwoThreadsLeaveTheSignalHandlersAsTheyWere) {
  struct sigaction ours {}, term_before {}, abrt_before {};
  ours.sa_handler = count_signal;
  sigemptyset(&ours.sa_mask);
  ASSERT_EQ(::sigaction(SIGTERM, &ours, &term_before), 0);
  ASSERT_EQ(::sigaction(SIGABRT, &ours, &abrt_before), 0);
  const GridPattern grid(24);
  const auto& P = grid.P;
  const auto& dense = grid.dense;
  const std::vector<int> expected = unjam::nested_dissection_order(P, dense);
  ASSERT_EQ(expected.size(), static_cast<std::size_t>(P.rows()));
  std::vector<int> same(2, 0);
  const auto work = [&](int t) {
    for (int i = 0; i < 200; ++i) same[static_cast<std::size_t>(t)] += unjam::nested_dissection_order(P, dense) == expected;
  };
  std::thread a(work, 0), b(work, 1);
  a.join();
  b.join();
  EXPECT_EQ(same[0], 200);
  EXPECT_EQ(same[1], 200);
  struct sigaction term {}, abrt {};
  ASSERT_EQ(::sigaction(SIGTERM, &term_before, &term), 0);
  ASSERT_EQ(::sigaction(SIGABRT, &abrt_before, &abrt), 0);
  EXPECT_EQ(term.sa_handler, &count_signal);
  EXPECT_EQ(abrt.sa_handler, &count_signal);
}

TEST(KluFactor, DiagonalPivotingSolvesAsPartialWithNoMoreFill) {
  // 4901 rows: above the size (3000) from which diagonal pivoting applies.
  Sparse S = grid_with_border(70);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(S.rows(), -1.0, 2.0);
  unjam::KluFactor partial(unjam::KluPivoting::partial), diagonal(unjam::KluPivoting::diagonal);
  ASSERT_TRUE(partial.factorize(S));
  ASSERT_TRUE(diagonal.factorize(S));
  EXPECT_EQ(diagonal.fresh(), 1);
  EXPECT_TRUE(diagonal.diagonal_pivots());
  EXPECT_FALSE(partial.diagonal_pivots());
  Eigen::VectorXd xp = b, xd = b;
  partial.solve_in_place(xp);
  diagonal.solve_in_place(xd);
  EXPECT_LT(relative_residual(S, xp, b), 1e-13);
  EXPECT_LT(relative_residual(S, xd, b), 1e-13);
  EXPECT_LT((xd - xp).norm(), 1e-12 * xp.norm());
  // On a 2D grid nested dissection leaves less fill than the minimum-degree ordering.
  EXPECT_LT(diagonal.factor_nonzeros(), partial.factor_nonzeros());
  EXPECT_GT(diagonal.factor_nonzeros(), static_cast<double>(S.nonZeros()));
}

TEST(KluFactor, DiagonalPivotingFallsBackWhereThePivotsWouldGrow) {
  // An 8 x 8 block with a diagonal of 2e-6 (it passes the diagonal's tolerance of 1e-6) and
  // a third of its other entries in [-1, 1], drawn by a fixed linear congruential sequence,
  // beside the identity, 4096 rows in all (diagonal pivoting applies from 3000 rows). On the
  // diagonal the block's pivots grow by ~1e11 (reciprocal growth 1.4e-11) and the solve's
  // residual is ~1e-6; partial pivoting keeps it at rounding. So the diagonal's attempt is
  // dropped for partial pivoting: two fresh factorisations, and an accurate solve.
  const int block = 8, n = 4096;
  std::uint64_t state = 11;
  const auto next = [&state] {  // in [0, 1)
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < block; ++i) {
    t.emplace_back(i, i, 2e-6);
    for (int j = 0; j < block; ++j) {
      const double draw = next(), value = 2.0 * next() - 1.0;
      if (i != j && draw < 0.35) t.emplace_back(i, j, value);
    }
  }
  for (int i = block; i < n; ++i) t.emplace_back(i, i, 1.0);
  Sparse S(n, n);
  S.setFromTriplets(t.begin(), t.end());
  S.makeCompressed();
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1.0, 3.0);
  unjam::KluFactor diagonal(unjam::KluPivoting::diagonal);
  ASSERT_TRUE(diagonal.factorize(S));
  EXPECT_EQ(diagonal.fresh(), 2);
  EXPECT_FALSE(diagonal.diagonal_pivots());
  Eigen::VectorXd x = b;
  diagonal.solve_in_place(x);
  EXPECT_LT(relative_residual(S, x, b), 1e-13);
  // Below 3000 rows the block alone is factorised by partial pivoting from the start.
  Sparse B = S.topLeftCorner(block, block);
  B.makeCompressed();
  unjam::KluFactor small(unjam::KluPivoting::diagonal);
  ASSERT_TRUE(small.factorize(B));
  EXPECT_EQ(small.fresh(), 1);
  EXPECT_FALSE(small.diagonal_pivots());
}

TEST(KluFactor, RefactorisationKeepsThePivotsWhileStable) {
  Sparse S = grid_with_border(70);
  unjam::KluFactor diagonal(unjam::KluPivoting::diagonal);
  ASSERT_TRUE(diagonal.factorize(S));
  for (Eigen::Index e = 0; e < S.nonZeros(); ++e) S.valuePtr()[e] *= 1.5;
  ASSERT_TRUE(diagonal.factorize(S));  // refactorised with the same pivots
  EXPECT_EQ(diagonal.fresh(), 1);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(S.rows());
  Eigen::VectorXd x = b;
  diagonal.solve_in_place(x);
  EXPECT_LT(relative_residual(S, x, b), 1e-13);
}

}  // namespace
