// The barrier driver of the force-bound LPs: its nested-dissection ordering of the normal
// equations (used by default from kNestedDissectionMinRows rows on) against CLP's own.
#include <gtest/gtest.h>

#include <coin/ClpSimplex.hpp>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/ensemble/lp_barrier.hpp"
#include "unjam/packing/packing_io.hpp"

namespace {

std::string fixture_dir(const char* name) { return std::string(UNJAM_FIXTURES_DIR) + "/" + name; }

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

TEST(BarrierSolver, NestedDissectionOrderingGivesTheSameOptima) {
  // p50 (136 rows; the pressure row is dense, one entry per cone column) ordered by nested
  // dissection, forced by a threshold of 0 rows, against CLP's minimum degree: every minimum
  // and maximum must agree to the LP accuracy.
  const unjam::Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p);
  ASSERT_LT(sys.A.rows(), unjam::kNestedDissectionMinRows);
  const double F0 = p.force_unit();
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
