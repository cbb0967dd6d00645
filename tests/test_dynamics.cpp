// Contact dynamics through advance(): two-body collisions against hand values, the
// conservation laws and dissipation of a many-body gas, and thread-count determinism over a
// few steps (dynamics_determinism.hpp; 30 steps: test_validation.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "dynamics_determinism.hpp"
#include "physics_test_util.hpp"
#include "unjam/contact/neighbor_grid.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/solver/time_step.hpp"

namespace unjam {
namespace {

using testing::kinetic_energy;
using testing::momentum;
using testing::two_disks;
using testing::compare_one_and_two_threads;

DynamicsSettings fixed_cell(double dt = 0.01) {
  DynamicsSettings ds;
  ds.dt = dt;
  ds.bath.enabled = false;
  ds.nlgs.tol = 1e-14;
  ds.nlgs.max_sweeps = 10000;
  return ds;
}

TEST(Dynamics, HeadOnCollisionIsPerfectlyInelastic) {
  // Radii 1 and 0.6, gap 0.4, closing speed 1.5 along x.
  Packing p = two_disks(20.0, {5.0, 10.0}, 1.0, {1.0, 0.0}, 0.0, {7.0, 10.0}, 0.6, {-0.5, 0.0}, 0.0, 0.3);
  const double ma = p.particles.mass(0), mb = p.particles.mass(1);
  const double m_red = ma * mb / (ma + mb);
  const Vec2 P0 = momentum(p.particles);
  const double E0 = kinetic_energy(p.particles);
  const DynamicsSettings ds = fixed_cell();
  bool touched = false;
  for (int step = 0; step < 100; ++step) {
    advance(p, ds);
    touched |= !p.contacts.empty() && p.contacts[0].fn > 0.0;
    const Vec2 P1 = momentum(p.particles);
    EXPECT_LT((P1 - P0).norm(), 1e-14 * P0.norm()) << "step " << step;
  }
  ASSERT_TRUE(touched);
  const Particles& P = p.particles;
  // After the collision both move with the centre-of-mass velocity.
  const double v_cm = (ma * 1.0 - mb * 0.5) / (ma + mb);
  EXPECT_NEAR(P.vx[1] - P.vx[0], 0.0, 1e-11);
  EXPECT_NEAR(P.vx[0], v_cm, 1e-11);
  EXPECT_EQ(P.vy[0], 0.0);
  EXPECT_EQ(P.vy[1], 0.0);
  EXPECT_EQ(P.omega[0], 0.0);
  EXPECT_EQ(P.omega[1], 0.0);
  // Energy lost: 1/2 m_red U_n^2.
  const double lost = E0 - kinetic_energy(P);
  const double hand = 0.5 * m_red * 1.5 * 1.5;
  EXPECT_NEAR(lost, hand, 1e-11 * hand);
  // The disks stay in contact without overlap.
  const Vec2 l = p.cell.min_image(P.position(1) - P.position(0));
  EXPECT_NEAR(l.norm(), 1.6, 1e-12);
}

struct Oblique {
  Vec2 va, vb;
  double wa, wb;
};

// A pair touching exactly at the start (gap 0, dyadic coordinates), normal +x, t = +y:
// the collision completes in one step. Returns the packing after one advance().
void check_oblique_collision(double mu, bool expect_sliding) {
  const Oblique o{{1.0, 0.3}, {-0.5, -0.2}, 0.2, -0.4};
  Packing p = two_disks(20.0, {5.0, 5.0}, 1.0, o.va, o.wa, {6.625, 5.0}, 0.625, o.vb, o.wb, mu);
  const Particles P0 = p.particles;
  const double ma = P0.mass(0), mb = P0.mass(1), Ia = P0.inertia(0), Ib = P0.inertia(1);
  const double Ra = 1.0, Rb = 0.625;
  const double mn = 1.0 / (1.0 / ma + 1.0 / mb);
  const double mt = 1.0 / (1.0 / ma + 1.0 / mb + Ra * Ra / Ia + Rb * Rb / Ib);
  const double Un0 = o.vb.x() - o.va.x();                                // -1.5
  const double Ut0 = o.vb.y() - o.va.y() - (o.wa * Ra + o.wb * Rb);     // -0.45
  const double Jn = -mn * Un0;                                          // impulses dt R
  double Jt = -mt * Ut0;
  const bool sliding = std::abs(Jt) > mu * Jn;
  ASSERT_EQ(sliding, expect_sliding);
  if (sliding) Jt = mu * Jn * (Jt > 0 ? 1.0 : -1.0);

  const DynamicsSettings ds = fixed_cell();
  advance(p, ds);
  const Particles& P = p.particles;
  ASSERT_EQ(p.contacts.size(), 1u);
  const Contact& c = p.contacts[0];
  EXPECT_NEAR(c.fn * ds.dt, Jn, 1e-12 * Jn);
  EXPECT_NEAR(c.ft * ds.dt, Jt, 1e-12 * Jn);
  EXPECT_LE(std::abs(c.ft), mu * c.fn * (1.0 + 1e-15));
  EXPECT_NEAR(P.vx[0], o.va.x() - Jn / ma, 1e-12);
  EXPECT_NEAR(P.vy[0], o.va.y() - Jt / ma, 1e-12);
  EXPECT_NEAR(P.vx[1], o.vb.x() + Jn / mb, 1e-12);
  EXPECT_NEAR(P.vy[1], o.vb.y() + Jt / mb, 1e-12);
  // Spins: T = -R ft on both grains.
  EXPECT_NEAR(P.omega[0], o.wa - Ra * Jt / Ia, 1e-12);
  EXPECT_NEAR(P.omega[1], o.wb - Rb * Jt / Ib, 1e-12);
  const double Ut = (P.vy[1] - P.vy[0]) - (P.omega[0] * Ra + P.omega[1] * Rb);
  if (sliding) {
    EXPECT_GT(Ut * Ut0, 0.0);  // still slipping the same way
  } else {
    EXPECT_NEAR(Ut, 0.0, 1e-12);
  }
  EXPECT_NEAR(P.vx[1] - P.vx[0], 0.0, 1e-12);
}

TEST(Dynamics, ObliqueCollisionSticking) { check_oblique_collision(0.5, false); }
TEST(Dynamics, ObliqueCollisionSliding) { check_oblique_collision(0.05, true); }

TEST(Dynamics, ObliqueCollisionFromAGapRespectsCoulombOverall) {
  // Starting from a gap the collision takes several steps; the summed tangential impulse
  // never exceeds mu times the summed normal impulse, and momentum is conserved.
  for (const double mu : {0.05, 0.5}) {
    Packing p = two_disks(20.0, {5.0, 5.0}, 1.0, {1.0, 0.6}, 0.5, {7.0, 5.4}, 0.7, {-0.5, -0.3}, -0.2, mu);
    const Vec2 P0 = momentum(p.particles);
    const double E0 = kinetic_energy(p.particles);
    const DynamicsSettings ds = fixed_cell();
    double Jn = 0.0, Jt_abs = 0.0;
    for (int step = 0; step < 80; ++step) {
      advance(p, ds);
      for (const Contact& c : p.contacts) {
        EXPECT_GE(c.fn, 0.0);
        EXPECT_LE(std::abs(c.ft), mu * c.fn * (1.0 + 1e-15));
        Jn += ds.dt * c.fn;
        Jt_abs += ds.dt * std::abs(c.ft);
      }
    }
    EXPECT_GT(Jn, 0.0);
    EXPECT_LE(Jt_abs, mu * Jn * (1.0 + 1e-14));
    EXPECT_LT((momentum(p.particles) - P0).norm(), 1e-14 * P0.norm());
    EXPECT_LT(kinetic_energy(p.particles), E0);
  }
}

// ---- many bodies ----

TEST(Dynamics, ManyBodyConservationDissipationAndForceConsistency) {
  GasSettings gs;
  gs.N = 200;
  gs.phi = 0.45;
  gs.seed = 11;
  Packing p = make_gas(gs);
  p.meta.contact.mu = 0.3;
  testing::randomize_velocities(p.particles, 1.0, 1.0, 21);
  DynamicsSettings ds = fixed_cell();
  ds.nlgs.tol = 1e-13;
  ds.nlgs.max_sweeps = 5000;
  const Particles& P = p.particles;
  const Vec2 P0 = momentum(P);
  const double scale = testing::momentum_scale(P);
  const double F_scale = scale / P.size() / ds.dt;  // a typical m v / dt
  double max_overlap = 0.0, max_force_err = 0.0, max_dE = -1.0;
  int steps_with_contacts = 0, unconverged = 0;
  for (int step = 0; step < 200; ++step) {
    const Particles before = P;
    const double E_before = kinetic_energy(P);
    const StepReport rep = advance(p, ds);
    unconverged += !rep.converged;
    // Momentum.
    EXPECT_LT((momentum(P) - P0).norm(), 1e-12 * scale) << "step " << step;
    // Energy never increases.
    const double dE = kinetic_energy(P) - E_before;
    max_dE = std::max(max_dE, dE / E_before);
    EXPECT_LE(dE, 1e-12 * E_before) << "step " << step;
    // The velocity change of every grain is exactly the net force of the returned
    // contact forces (action = reaction on every contact), and torques likewise.
    const testing::GrainLoads loads = testing::grain_loads(P, p.contacts);
    Vec2 net = Vec2::Zero();
    for (std::size_t i = 0; i < P.size(); ++i) {
      const Vec2 F = P.mass(i) * (P.velocity(i) - before.velocity(i)) / ds.dt;
      const double T = P.inertia(i) * (P.omega[i] - before.omega[i]) / ds.dt;
      max_force_err = std::max({max_force_err, (F - loads.force[i]).norm() / F_scale,
                                std::abs(T - loads.torque[i]) / P.radius[i] / F_scale});
      net += F;
    }
    EXPECT_LT(net.norm(), 1e-10 * F_scale * P.size()) << "step " << step;
    // Overlaps after the position update.
    bool any = false;
    for (const Contact& c : p.contacts) any |= c.fn > 0.0;
    steps_with_contacts += any;
    for (const auto& [a, b] : find_near_pairs(P, p.cell, 0.0)) {
      const double gap = p.cell.min_image(P.position(b) - P.position(a)).norm() - P.radius[a] - P.radius[b];
      max_overlap = std::max(max_overlap, -gap);
    }
  }
  std::printf("[ many-body gas ] max overlap %.3g, max force mismatch %.3g (m v/dt units), "
              "max relative dE %.3g, unconverged steps %d\n",
              max_overlap, max_force_err, max_dE, unconverged);
  EXPECT_GT(steps_with_contacts, 150);
  EXPECT_EQ(unconverged, 0);
  EXPECT_LT(max_force_err, 1e-9);
  // Measured: 0 (collisions are short; a small overlap could only come from the curvature
  // of sliding and rolling contacts, O(dt^2 U_t^2 / R), or an unconverged solve).
  EXPECT_LT(max_overlap, 1e-3);
  EXPECT_TRUE(std::isfinite(kinetic_energy(P)));
}

TEST(Dynamics, ManyBodyWithTheBathConservesPeculiarMomentum) {
  // The affine cell motion enters every contact symmetrically: the peculiar momentum is
  // conserved under the bath too, while the cell shrinks.
  GasSettings gs;
  gs.N = 200;
  gs.phi = 0.45;
  gs.seed = 12;
  Packing p = make_gas(gs);
  p.meta.contact.mu = 0.5;
  testing::randomize_velocities(p.particles, 0.5, 0.5, 22);
  DynamicsSettings ds;
  ds.bath.M_lambda = 1.0;  // a light cell: fast compression
  ds.bath.P_ext = 5.0;
  const Vec2 P0 = momentum(p.particles);
  const double scale = testing::momentum_scale(p.particles);
  const double L0 = p.cell.Lx;
  int loaded = 0;
  for (int step = 0; step < 200; ++step) {
    advance(p, ds);
    loaded += std::any_of(p.contacts.begin(), p.contacts.end(), [](const Contact& c) { return c.fn > 0; });
    EXPECT_LT((momentum(p.particles) - P0).norm(), 1e-12 * scale) << "step " << step;
    for (const Contact& c : p.contacts) {
      EXPECT_GE(c.fn, 0.0);
      EXPECT_LE(std::abs(c.ft), 0.5 * c.fn * (1.0 + 1e-15));
    }
  }
  EXPECT_GT(loaded, 100);
  EXPECT_LT(p.cell.Lx, L0);
}

// ---- determinism ----

// Few steps and sweeps in the default run: the parallel path has a few barriers per colour
// and sweep, which get very slow when the two cores are shared with other processes.
TEST(Determinism, OneAndTwoThreadsGiveBitIdenticalDynamics) { compare_one_and_two_threads(3, 30); }

// Threading::kAuto's choice (docs/method.md, "Threading of the sweeps") follows only the
// measurements of the caller's NlgsThreading: parallel first, then serial, then the faster
// mode with the other tried again every 32nd choice; another object starts afresh.
TEST(Determinism, AutoThreadingChoiceFollowsOnlyItsOwnMeasurements) {
  NlgsThreading a, b;
  EXPECT_TRUE(a.choose_parallel());
  a.record(true, 30.0);
  EXPECT_FALSE(a.choose_parallel());
  a.record(false, 10.0);
  EXPECT_TRUE(a.parallel_is_slow());
  int parallel = 0;
  for (int i = 0; i < 64; ++i) parallel += a.choose_parallel() ? 1 : 0;
  EXPECT_EQ(parallel, 2);  // the slower mode, on the 32nd and 64th choice
  a.record(true, 0.0);     // avg 0.7 * 30 = 21 ns: still slower than serial
  EXPECT_TRUE(a.parallel_is_slow());
  EXPECT_TRUE(b.choose_parallel());
  EXPECT_FALSE(b.parallel_is_slow());
}

}  // namespace
}  // namespace unjam
