// The barrier driver of the force-bound LPs: its normal equations, formed by the precomputed
// scatter, against CLP's own assembly; its nested-dissection ordering (used by default from
// kNestedDissectionMinRows rows on) against CLP's.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <coin/ClpInterior.hpp>
#include <coin/ClpSimplex.hpp>

#include "fixture_p50.hpp"
#include "unjam/lp/lp_barrier.hpp"
#include "unjam/lp/normal_equations.hpp"

namespace {

using unjam::testing::p50;

// The force-bound LP of a system with a zero objective, as ForceLP builds it.
ClpSimplex force_lp_model(const unjam::EquilibriumSystem& sys) {
  ClpSimplex model;
  unjam::load_admissible_set(model, unjam::cone_matrix(sys), sys.rhs, 1e-9);
  return model;
}

// fn_k = (y_2k + y_2k+1) / 2 at the optimum of min (sense +1) or max (-1) fn_k.
double optimal_fn(unjam::BarrierSolver& solver, ClpSimplex& model, int k, double sense) {
  for (int j = 0; j < model.numberColumns(); ++j)
    model.setObjectiveCoefficient(j, j / 2 == k ? 0.5 : 0.0);
  model.setOptimizationDirection(sense);
  EXPECT_EQ(solver.solve(model), unjam::BarrierEnd::optimal) << "contact " << k;
  const double* y = model.primalColumnSolution();
  return 0.5 * (y[2 * k] + y[2 * k + 1]);
}

TEST(NormalEquationsCholesky, ScatteredAssemblyFactorisesAsClpsOwn) {
  // On p50, for the minimum-degree and the nested-dissection ordering: A D A^T with D spread
  // over eight decades (as near a barrier optimum) is factorised once with the scatter and
  // once with CLP's own assembly (the base class's factorize); both factors must solve
  // (A D A^T) x = b to a residual at rounding level. A's rows are dependent (the grains'
  // force balances sum to zero), so b is taken in the range of A D A^T, and x is not unique:
  // the two x differ along the null space.
  const auto& sys = p50().sys;
  ClpSimplex model = force_lp_model(sys);
  const Eigen::MatrixXd A(unjam::cone_matrix(sys));
  const int rows = static_cast<int>(A.rows()), cols = static_cast<int>(A.cols());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> exponent(-6.0, 2.0);
  std::vector<double> diagonal(cols + rows, 0.0);  // slacks of the equality rows: 0
  for (int c = 0; c < cols; ++c) diagonal[c] = std::pow(10.0, exponent(rng));
  const Eigen::Map<const Eigen::VectorXd> d(diagonal.data(), cols);
  const Eigen::MatrixXd M = A * d.asDiagonal() * A.transpose();
  const Eigen::VectorXd b = M * Eigen::VectorXd::Random(rows);
  for (const int nested_dissection_rows : {unjam::kNestedDissectionMinRows, 0}) {
    ClpInterior interior;
    interior.borrowModel(model);
    std::unique_ptr<ClpCholeskyBase> keep;
    unjam::NormalEquationsCholesky cholesky(&keep, nested_dissection_rows);
    ASSERT_EQ(cholesky.order(&interior), 0);
    ASSERT_EQ(cholesky.symbolic(), 0);
    ASSERT_TRUE(cholesky.scatter_assembly());
    EXPECT_EQ(cholesky.nested_dissection(), nested_dissection_rows == 0);
    for (const bool scatter : {true, false}) {
      std::vector<int> rows_dropped(rows, 0);
      if (scatter)
        cholesky.factorize(diagonal.data(), rows_dropped.data());
      else
        cholesky.ClpCholeskyBase::factorize(diagonal.data(), rows_dropped.data());
      Eigen::VectorXd x = b;
      cholesky.solve(x.data());
      EXPECT_LT((M * x - b).norm(), 1e-10 * b.norm()) << (scatter ? "scatter" : "CLP's");
    }
    interior.returnModel(model);
  }
}

TEST(BarrierSolver, NestedDissectionOrderingGivesTheSameOptima) {
  // p50 (136 rows; the pressure row is dense, one entry per cone column) ordered by nested
  // dissection, forced by a threshold of 0 rows, against CLP's minimum degree: every minimum
  // and maximum must agree to the LP accuracy.
  const auto& sys = p50().sys;
  ASSERT_LT(sys.A.rows(), unjam::kNestedDissectionMinRows);
  const double F0 = p50().packing.force_unit();
  ClpSimplex model_clp = force_lp_model(sys), model_nd = force_lp_model(sys);
  unjam::BarrierSolver clp_order, nested(0);
  for (int k = 0; k < sys.num_contacts(); ++k) {
    for (const double sense : {1.0, -1.0}) {
      const double fn_nd = optimal_fn(nested, model_nd, k, sense);
      EXPECT_NEAR(fn_nd, optimal_fn(clp_order, model_clp, k, sense), 1e-8 * F0)
          << "contact " << k << (sense > 0 ? " min" : " max");
    }
  }
  EXPECT_TRUE(nested.nested_dissection());
  EXPECT_FALSE(clp_order.nested_dissection());
  // A copy (one per thread) carries the analysis and its ordering.
  const unjam::BarrierSolver copy(nested);
  EXPECT_TRUE(copy.nested_dissection());
}

}  // namespace
