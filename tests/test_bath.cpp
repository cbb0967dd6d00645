// The pressure bath (docs/method.md, "One time step"): the cell strain rate follows
// M_lambda dlambda/dt = P_in - P_ext; a gas under P_ext compresses until P_in = P_ext.
// Also the validation of the compaction settings and of the gas.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "physics_test_util.hpp"
#include "unjam/core/error.hpp"
#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/solver/time_step.hpp"

namespace unjam {
namespace {

Packing dilute_gas(int N, std::uint64_t seed, double phi = 0.05) {
  GasSettings gs;
  gs.N = N;
  gs.phi = phi;
  gs.seed = seed;
  return make_gas(gs);
}

TEST(Bath, FirstStepFromRestIsTheHandValue) {
  // A gas at rest, no contact force: P_in = 0, so lambda(dt) = -dt P_ext / M_lambda and
  // L(dt) = L (1 + lambda dt), every position scaled by the same factor.
  Packing p = dilute_gas(50, 4);
  const Packing gas = p;
  DynamicsSettings ds;
  ds.bath.P_ext = 2.0;
  ds.bath.M_lambda = 50.0;
  const StepReport rep = advance(p, ds);
  EXPECT_EQ(rep.P_in, 0.0);
  const double lambda = -ds.dt * 2.0 / 50.0;
  EXPECT_DOUBLE_EQ(p.state.lambda, lambda);
  const double scale = 1.0 + lambda * ds.dt;
  EXPECT_DOUBLE_EQ(p.cell.Lx, gas.cell.Lx * scale);
  EXPECT_DOUBLE_EQ(p.cell.Ly, gas.cell.Ly * scale);
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_NEAR(p.particles.x[i], gas.particles.x[i] * scale, 1e-12);
    EXPECT_NEAR(p.particles.y[i], gas.particles.y[i] * scale, 1e-12);
    EXPECT_EQ(p.particles.vx[i], 0.0);  // peculiar velocities stay zero
  }
  // Next step: lambda(2dt) = lambda(dt) - dt P_ext / M_lambda.
  advance(p, ds);
  EXPECT_DOUBLE_EQ(p.state.lambda, 2.0 * lambda);
}

TEST(Bath, KineticPressure) {
  // Free flight (dilute gas, velocities small enough that no pair closes in one step):
  // P_in = sum m v^2 / (2V) and lambda = lambda_t + dt (P_in - P_ext) / M_lambda.
  Packing p = dilute_gas(60, 8, 0.02);
  testing::randomize_velocities(p.particles, 0.3, 0.0, 3);
  double K = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) K += p.particles.mass(i) * p.particles.velocity(i).squaredNorm();
  const double V = p.cell.area();
  DynamicsSettings ds;
  p.state.lambda = 1e-3;
  const StepReport rep = advance(p, ds);
  for (const Contact& c : p.contacts) ASSERT_EQ(c.fn, 0.0);
  EXPECT_NEAR(rep.P_in, K / (2.0 * V), 1e-14);
  EXPECT_NEAR(p.state.lambda, 1e-3 + ds.dt * (K / (2.0 * V) - 1.0) / 100.0, 1e-15);
}

TEST(Bath, CellShrinksMonotonicallyUntilContactsForm) {
  Packing p = dilute_gas(100, 2, 0.3);
  DynamicsSettings ds;
  double L = p.cell.Lx;
  int steps = 0;
  for (; steps < 400; ++steps) {
    const StepReport rep = advance(p, ds);
    if (rep.P_in > 0.0) break;
    EXPECT_LT(p.cell.Lx, L);
    EXPECT_EQ(p.cell.Lx, p.cell.Ly);  // square stays square
    L = p.cell.Lx;
  }
  EXPECT_GT(steps, 10);
}

TEST(Bath, GasCompressesToAStaticPackingAtPext) {
  const testing::Compacted& c = testing::compacted(100, 0.1, 7);
  const Packing& p = c.packing;
  ASSERT_TRUE(c.result.is_static);
  EXPECT_TRUE(p.state.is_static);
  EXPECT_LT(p.cell.Lx, 0.7 * c.gas.cell.Lx);  // compressed from phi 0.3 to ~0.8
  EXPECT_EQ(p.cell.Lx, p.cell.Ly);
  double S = 0.0;
  for (const Contact& k : p.contacts) S += k.fn * k.l.norm();
  const double P_in = S / (2.0 * p.cell.area());  // velocities are zero
  std::printf("[ bath ] N 100 mu 0.1 seed 7: L %.6f -> %.6f, P_in / P_ext - 1 = %.3g, %.2f s\n",
              c.gas.cell.Lx, p.cell.Lx, P_in / p.meta.contact.P_ext - 1.0, c.seconds);
  EXPECT_NEAR(P_in / p.meta.contact.P_ext, 1.0, 1e-6);
}

// ---- bad input ----

TEST(BadInput, ValidateRejectsInvalidSettings) {
  const CompactionSettings ok;
  EXPECT_NO_THROW(validate(ok, 0.0));
  EXPECT_NO_THROW(validate(ok, 1.0));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(validate(ok, -0.1), Error);
  EXPECT_THROW(validate(ok, nan), Error);
  EXPECT_THROW(validate(ok, inf), Error);
  const auto bad = [&](auto change) {
    CompactionSettings s;
    change(s);
    EXPECT_THROW(validate(s, 0.1), Error);
  };
  bad([](CompactionSettings& s) { s.dynamics.bath.P_ext = 0.0; });
  bad([](CompactionSettings& s) { s.dynamics.bath.P_ext = -1.0; });
  bad([&](CompactionSettings& s) { s.dynamics.bath.P_ext = nan; });
  bad([](CompactionSettings& s) { s.dynamics.dt = 0.0; });
  bad([](CompactionSettings& s) { s.dynamics.dt = -0.01; });
  bad([&](CompactionSettings& s) { s.dynamics.dt = nan; });
  bad([](CompactionSettings& s) { s.dynamics.bath.M_lambda = 0.0; });
  bad([&](CompactionSettings& s) { s.dynamics.bath.M_lambda = nan; });
  bad([](CompactionSettings& s) { s.dynamics.nlgs.tol = 0.0; });
  bad([&](CompactionSettings& s) { s.dynamics.nlgs.tol = nan; });
  bad([](CompactionSettings& s) { s.dynamics.nlgs.max_sweeps = 0; });
  bad([](CompactionSettings& s) { s.final_solve.tol = -1.0; });
  bad([](CompactionSettings& s) { s.v_static = 0.0; });
  // compact() validates before touching the packing.
  Packing gas = dilute_gas(10, 1);
  gas.meta.contact.mu = -1.0;
  const Packing before = gas;
  EXPECT_THROW(compact(gas, CompactionSettings{}), Error);
  EXPECT_EQ(gas.cell.Lx, before.cell.Lx);
}

TEST(BadInput, MakeGasRejectsInvalidSettings) {
  const auto bad = [](auto change) {
    GasSettings s;
    s.N = 20;
    change(s);
    EXPECT_THROW(make_gas(s), Error);
  };
  bad([](GasSettings& s) { s.N = 1; });
  bad([](GasSettings& s) { s.N = 0; });
  bad([](GasSettings& s) { s.N = -5; });
  bad([](GasSettings& s) { s.R_min = 0.0; });
  bad([](GasSettings& s) { s.R_min = 1.5; });
  bad([](GasSettings& s) { s.phi = 0.0; });
  bad([](GasSettings& s) { s.phi = 0.6; });
  bad([](GasSettings& s) { s.phi = std::numeric_limits<double>::quiet_NaN(); });
  // Fewer than 8 disks of radii in [0.5, 1] cannot jam in a periodic cell (gas.hpp).
  bad([](GasSettings& s) { s.N = 7; });
  GasSettings eight;
  eight.N = 8;
  EXPECT_EQ(min_jamming_grains(eight), 8);
  EXPECT_NO_THROW(make_gas(eight));
}

TEST(BadInput, GasIsValid) {
  // make_gas: radii in [R_min, R_max], positions in the cell, no overlap, at rest, phi.
  GasSettings gs;
  gs.N = 300;
  gs.phi = 0.45;
  gs.seed = 9;
  const Packing g = make_gas(gs);
  ASSERT_EQ(g.size(), 300u);
  for (std::size_t i = 0; i < g.size(); ++i) {
    EXPECT_GE(g.particles.radius[i], 0.5);
    EXPECT_LE(g.particles.radius[i], 1.0);
    EXPECT_GE(g.particles.x[i], 0.0);
    EXPECT_LT(g.particles.x[i], g.cell.Lx);
    EXPECT_GE(g.particles.y[i], 0.0);
    EXPECT_LT(g.particles.y[i], g.cell.Ly);
    EXPECT_EQ(g.particles.vx[i], 0.0);
    EXPECT_EQ(g.particles.omega[i], 0.0);
  }
  EXPECT_TRUE(testing::brute_force_pairs(g.particles, g.cell, 0.0).empty());
  EXPECT_NEAR(testing::packing_fraction(g), 0.45, 1e-12);
  EXPECT_EQ(g.cell.Lx, g.cell.Ly);
}

}  // namespace
}  // namespace unjam
