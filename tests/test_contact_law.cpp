// The contact law of one contact-dynamics step (docs/method.md, "One time step"), checked on a
// single pair with solve_nlgs against impulses computed by hand: open, closing with a gap,
// sticking, sliding, the torque signs and the minimum image.
#include <gtest/gtest.h>

#include <cmath>

#include "physics_test_util.hpp"
#include "unjam/solver/nlgs.hpp"
#include "unjam/solver/step_problem.hpp"
#include "unjam/solver/time_step.hpp"

namespace unjam {
namespace {

using testing::two_disks;

// The contact of the pair (0, 1), geometry computed here from the positions.
Contact pair_contact(const Packing& p) {
  Contact c;
  c.a = 0;
  c.b = 1;
  c.l = p.cell.min_image(p.particles.position(1) - p.particles.position(0));
  c.n = c.l / c.l.norm();
  c.gap = c.l.norm() - p.particles.radius[0] - p.particles.radius[1];
  return c;
}

struct PairSolve {
  Contact c;
  NlgsResult res;
};

// One step of the pair's contact problem: bath off, lambda_t = 0, g_eff = max(gap, 0).
PairSolve solve_pair(Packing& p, double dt, double mu) {
  Contacts contacts{pair_contact(p)};
  StepProblem pb;
  pb.cell = p.cell;
  pb.dt = dt;
  pb.mu = mu;
  pb.bath.enabled = false;
  pb.lambda_t = 0.0;
  pb.g_eff = positive_gaps(contacts);
  NlgsSettings set;
  set.tol = 1e-14;
  set.max_sweeps = 50;
  NlgsThreading threading;
  const NlgsResult res = solve_nlgs(pb, set, contacts, p.particles, threading);
  return {contacts.at(0), res};
}

// The hand solution of the law for the pair (0, 1) of p with no other contact (U* = free U).
struct HandLaw {
  double Rn, Rt;       // forces
  double Usn, Ust;     // U*
  double mn, mt;       // effective masses
  bool sliding;
};

HandLaw hand_law(const Packing& p, double dt, double mu) {
  const Particles& P = p.particles;
  const Contact c = pair_contact(p);
  const Vec2 t = tangent(c.n);
  const double ma = P.mass(0), mb = P.mass(1), Ia = P.inertia(0), Ib = P.inertia(1);
  const double Ra = P.radius[0], Rb = P.radius[1];
  HandLaw h{};
  h.mn = 1.0 / (1.0 / ma + 1.0 / mb);
  h.mt = 1.0 / (1.0 / ma + 1.0 / mb + Ra * Ra / Ia + Rb * Rb / Ib);
  const Vec2 dv = P.velocity(1) - P.velocity(0);
  h.Usn = dv.dot(c.n);
  h.Ust = dv.dot(t) - (P.omega[0] * Ra + P.omega[1] * Rb);
  const double g = std::max(c.gap, 0.0);
  if (g + dt * h.Usn > 0.0) return h;  // open
  h.Rn = -h.mn * (g / dt + h.Usn) / dt;
  h.Rt = -h.mt * h.Ust / dt;
  if (std::abs(h.Rt) > mu * h.Rn) {
    h.Rt = mu * h.Rn * (h.Rt > 0 ? 1.0 : -1.0);
    h.sliding = true;
  }
  return h;
}

// Relative velocity of the contact points after the step, (U_n, U_t).
std::pair<double, double> contact_velocity(const Packing& p, const Contact& c) {
  const Particles& P = p.particles;
  const Vec2 dv = P.velocity(1) - P.velocity(0);
  return {dv.dot(c.n), dv.dot(tangent(c.n)) - (P.omega[0] * P.radius[0] + P.omega[1] * P.radius[1])};
}

double rel(double got, double want) { return std::abs(got - want) / std::abs(want); }

TEST(ContactLaw, SeparatingPairIsOpen) {
  // b moves away from a (normal along +x); also a tangential velocity and spins.
  Packing p = two_disks(20.0, {5.0, 5.0}, 1.0, {-0.2, 0.3}, 0.7, {6.7, 5.0}, 0.8, {0.5, -0.4}, -1.1, 0.5);
  const Particles before = p.particles;
  const auto [c, res] = solve_pair(p, 0.01, 0.5);
  EXPECT_LT(c.gap, 0.0);  // even an overlapping pair opens when it separates
  EXPECT_EQ(c.fn, 0.0);
  EXPECT_EQ(c.ft, 0.0);
  EXPECT_EQ(p.particles.vx, before.vx);
  EXPECT_EQ(p.particles.vy, before.vy);
  EXPECT_EQ(p.particles.omega, before.omega);

  // Approaching, but not enough to close the gap within the step: g + dt U*_n > 0.
  Packing q = two_disks(20.0, {5.0, 5.0}, 1.0, {0.5, 0.0}, 0.0, {7.0, 5.0}, 0.8, {-0.5, 0.0}, 0.0, 0.5);
  const auto [c2, res2] = solve_pair(q, 0.01, 0.5);
  ASSERT_GT(c2.gap + 0.01 * (-1.0), 0.0);
  EXPECT_EQ(c2.fn, 0.0);
  EXPECT_EQ(c2.ft, 0.0);
  EXPECT_EQ(q.particles.vx[0], 0.5);
  EXPECT_EQ(q.particles.vx[1], -0.5);
}

TEST(ContactLaw, ClosingWithAGapClosesExactly) {
  const double dt = 0.01;
  // gap 0.005, approach speed 1: dt U*_n = -0.01 < -g, the contact closes in the step.
  Packing p = two_disks(20.0, {5.0, 5.0}, 1.0, {0.25, 0.0}, 0.0, {6.805, 5.0}, 0.8, {-0.75, 0.0}, 0.0, 0.5);
  const HandLaw h = hand_law(p, dt, 0.5);
  const double g = pair_contact(p).gap;
  ASSERT_GT(g, 0.0);
  ASSERT_LE(g + dt * h.Usn, 0.0);
  const double mn = 1.0 / (1.0 / p.particles.mass(0) + 1.0 / p.particles.mass(1));
  const double Rn_hand = -mn * (g / dt + h.Usn) / dt;
  const auto [c, res] = solve_pair(p, dt, 0.5);
  EXPECT_TRUE(res.converged);
  EXPECT_LT(rel(c.fn, Rn_hand), 1e-12) << c.fn << " vs " << Rn_hand;
  EXPECT_EQ(c.ft, 0.0);  // no tangential velocity, no tangential force
  // After the step the gap closes exactly: dt U_n = -g.
  const auto [Un, Ut] = contact_velocity(p, c);
  EXPECT_NEAR(dt * Un, -g, 1e-14);
  EXPECT_NEAR(Ut, 0.0, 1e-14);
  // Velocities: v_a -= dt Rn n / m_a, v_b += dt Rn n / m_b.
  EXPECT_LT(rel(p.particles.vx[0], 0.25 - dt * Rn_hand / p.particles.mass(0)), 1e-12);
  EXPECT_LT(rel(p.particles.vx[1], -0.75 + dt * Rn_hand / p.particles.mass(1)), 1e-12);
  EXPECT_EQ(p.particles.omega[0], 0.0);
  EXPECT_EQ(p.particles.omega[1], 0.0);
}

TEST(ContactLaw, StickingCancelsTheTangentialVelocity) {
  const double dt = 0.01, mu = 0.5;
  // Oblique normal, small tangential velocity of b relative to a.
  const Vec2 n = Vec2(3.0, 4.0) / 5.0;
  const Vec2 t = tangent(n);
  const Vec2 ra{5.0, 5.0};
  const Vec2 rb = ra + (1.8 + 0.002) * n;
  const Vec2 vb = -1.0 * n + 0.05 * t;
  Packing p = two_disks(20.0, ra, 1.0, {0.0, 0.0}, 0.1, rb, 0.8, vb, -0.05, mu);
  const HandLaw h = hand_law(p, dt, mu);
  ASSERT_GT(h.Rn, 0.0);
  ASSERT_FALSE(h.sliding);
  // 1/m_t = 1/m_a + 1/m_b + R_a^2/I_a + R_b^2/I_b.
  const Particles& P = p.particles;
  const double inv_mt = 1.0 / P.mass(0) + 1.0 / P.mass(1) + 1.0 / P.inertia(0) + 0.64 / P.inertia(1);
  const double Rt_hand = -h.Ust / inv_mt / dt;
  const auto [c, res] = solve_pair(p, dt, mu);
  EXPECT_TRUE(res.converged);
  EXPECT_LT(rel(c.fn, h.Rn), 1e-12);
  EXPECT_LT(rel(c.ft, Rt_hand), 1e-12) << c.ft << " vs " << Rt_hand;
  EXPECT_LE(std::abs(c.ft), mu * c.fn);
  const auto [Un, Ut] = contact_velocity(p, c);
  EXPECT_NEAR(Ut, 0.0, 1e-13);
  EXPECT_NEAR(dt * Un, -std::max(c.gap, 0.0), 1e-14);
}

TEST(ContactLaw, SlidingSaturatesCoulombAgainstTheSlip) {
  const double dt = 0.01, mu = 0.3;
  const Vec2 n = Vec2(-5.0, 12.0) / 13.0;
  const Vec2 t = tangent(n);
  const Vec2 ra{5.0, 5.0};
  const Vec2 rb = ra + 1.6 * n;  // touching, gap ~ 0
  for (const double slip : {+2.0, -2.0}) {
    const Vec2 vb = -0.5 * n + slip * t;
    Packing p = two_disks(20.0, ra, 0.9, {0.0, 0.0}, 0.0, rb, 0.7, vb, 0.0, mu);
    const HandLaw h = hand_law(p, dt, mu);
    ASSERT_TRUE(h.sliding);
    const auto [c, res] = solve_pair(p, dt, mu);
    EXPECT_TRUE(res.converged);
    EXPECT_LT(rel(c.fn, h.Rn), 1e-12);
    EXPECT_LT(rel(std::abs(c.ft), mu * c.fn), 1e-14);
    // The tangential force on b opposes b's slip relative to a.
    EXPECT_LT(c.ft * h.Ust, 0.0) << "slip " << slip << " ft " << c.ft;
    EXPECT_LT(rel(c.ft, h.Rt), 1e-12);
    // The pair still slips in the same direction after the step (only slowed down).
    const auto [Un, Ut] = contact_velocity(p, c);
    EXPECT_GT(Ut * h.Ust, 0.0);
    EXPECT_LT(std::abs(Ut), std::abs(h.Ust));
    const double inv_mt = 1.0 / h.mt;
    EXPECT_NEAR(Ut, h.Ust + dt * c.ft * inv_mt, 1e-12);
  }
}

TEST(ContactLaw, TorqueSignsAfterAnObliqueCollision) {
  const double dt = 0.01, mu = 0.4;
  // a left of b, normal +x, t = +y. b moves up relative to a: friction on b points down
  // (ft < 0), so T_a = -R_a ft > 0 and T_b = -R_b ft > 0: both spin counter-clockwise.
  for (const double slip : {0.05, 3.0, -0.05, -3.0}) {  // sticking and sliding, both ways
    Packing p = two_disks(20.0, {5.0, 5.0}, 1.0, {0.6, 0.0}, 0.0, {6.75, 5.0}, 0.75,
                          {-0.6, slip}, 0.0, mu);
    const HandLaw h = hand_law(p, dt, mu);
    const auto [c, res] = solve_pair(p, dt, mu);
    ASSERT_GT(c.fn, 0.0);
    EXPECT_LT(c.ft * slip, 0.0);
    const Particles& P = p.particles;
    // The right-hand rule: friction on b at b's left side, on a at a's right side.
    EXPECT_GT(P.omega[0] * slip, 0.0) << "slip " << slip;
    EXPECT_GT(P.omega[1] * slip, 0.0) << "slip " << slip;
    EXPECT_LT(rel(P.omega[0], -dt * P.radius[0] * h.Rt / P.inertia(0)), 1e-12);
    EXPECT_LT(rel(P.omega[1], -dt * P.radius[1] * h.Rt / P.inertia(1)), 1e-12);
    // The tangential impulse also moves the centres: v_b,y += dt ft / m_b.
    EXPECT_LT(rel(P.vy[1], slip + dt * h.Rt / P.mass(1)), 1e-12);
    EXPECT_LT(rel(P.vy[0], -dt * h.Rt / P.mass(0)), 1e-12);
  }
}

TEST(ContactLaw, MinimumImageAcrossBothBoundaries) {
  const double dt = 0.01, mu = 0.5;
  // Dyadic coordinates: the branch vector (1.25, 1.0) is exact both in the interior and
  // across the corner of the cell, so the two problems must agree bit for bit.
  const Vec2 va{0.5, 0.25}, vb{-0.5, -0.75};
  Packing inner = two_disks(10.0, {4.5, 4.75}, 1.0, va, 0.5, {5.75, 5.75}, 0.625, vb, -0.25, mu);
  Packing outer = two_disks(10.0, {9.5, 9.75}, 1.0, va, 0.5, {0.75, 0.75}, 0.625, vb, -0.25, mu);
  const auto [ci, ri] = solve_pair(inner, dt, mu);
  const auto [co, ro] = solve_pair(outer, dt, mu);
  ASSERT_GT(ci.fn, 0.0);
  EXPECT_EQ(co.l, ci.l);
  EXPECT_EQ(co.fn, ci.fn);
  EXPECT_EQ(co.ft, ci.ft);
  EXPECT_EQ(outer.particles.vx, inner.particles.vx);
  EXPECT_EQ(outer.particles.vy, inner.particles.vy);
  EXPECT_EQ(outer.particles.omega, inner.particles.omega);

  // A generic (non-dyadic) pair across the x boundary only and across y only: equal to
  // round-off of the branch vector.
  for (const Vec2 shift : {Vec2(7.3, 0.0), Vec2(0.0, 6.0), Vec2(7.3, 6.0)}) {
    const Vec2 a0{2.1, 3.3}, b0{3.37, 4.41};
    Packing p1 = two_disks(10.0, a0, 0.93, va, 0.1, b0, 0.76, vb, 0.2, mu);
    const Cell cell{10.0, 10.0};
    const Vec2 a1 = cell.wrap(a0 + shift), b1 = cell.wrap(b0 + shift);
    Packing p2 = two_disks(10.0, a1, 0.93, va, 0.1, b1, 0.76, vb, 0.2, mu);
    ASSERT_GT(std::abs(b1.x() - a1.x()) + std::abs(b1.y() - a1.y()), 5.0);  // really across
    const auto [c1, r1] = solve_pair(p1, dt, mu);
    const auto [c2, r2] = solve_pair(p2, dt, mu);
    ASSERT_GT(c1.fn, 0.0);
    EXPECT_NEAR(c2.fn, c1.fn, 1e-10 * c1.fn);
    EXPECT_NEAR(c2.ft, c1.ft, 1e-10 * c1.fn);
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(p2.particles.vx[i], p1.particles.vx[i], 1e-12);
      EXPECT_NEAR(p2.particles.vy[i], p1.particles.vy[i], 1e-12);
      EXPECT_NEAR(p2.particles.omega[i], p1.particles.omega[i], 1e-12);
    }
  }
}

TEST(ContactLaw, MinimumImageThroughAdvance) {
  // The same pair through advance() (detection, solve, position update), once in the
  // interior and once across the corner of the cell: identical forces and velocities.
  const double mu = 0.5;
  const Vec2 va{0.5, 0.25}, vb{-0.5, -0.75};
  Packing inner = two_disks(10.0, {4.5, 4.75}, 1.0, va, 0.5, {5.75, 5.75}, 0.625, vb, -0.25, mu);
  Packing outer = two_disks(10.0, {9.5, 9.75}, 1.0, va, 0.5, {0.75, 0.75}, 0.625, vb, -0.25, mu);
  DynamicsSettings ds;
  ds.bath.enabled = false;
  for (int step = 0; step < 5; ++step) {
    advance(inner, ds);
    advance(outer, ds);
    ASSERT_EQ(inner.contacts.size(), 1u);
    ASSERT_EQ(outer.contacts.size(), 1u);
    if (step == 0) EXPECT_GT(inner.contacts[0].fn, 0.0);
    EXPECT_EQ(outer.contacts[0].fn, inner.contacts[0].fn) << "step " << step;
    EXPECT_EQ(outer.contacts[0].ft, inner.contacts[0].ft) << "step " << step;
    EXPECT_EQ(outer.particles.vx, inner.particles.vx);
    EXPECT_EQ(outer.particles.vy, inner.particles.vy);
    EXPECT_EQ(outer.particles.omega, inner.particles.omega);
    for (int i = 0; i < 2; ++i) {
      const Vec2 d = outer.cell.min_image(outer.particles.position(i) - inner.particles.position(i) -
                                          Vec2(5.0, 5.0));
      EXPECT_LT(d.norm(), 1e-13);
    }
  }
}

TEST(ContactLaw, WarmStartDoesNotChangeTheSolution) {
  // The same problem solved from a wrong warm start converges to the same forces.
  const double dt = 0.01, mu = 0.3;
  Packing p = two_disks(20.0, {5.0, 5.0}, 1.0, {0.4, 0.1}, 0.0, {6.7, 5.2}, 0.75, {-0.4, 0.2}, 0.3, mu);
  const HandLaw h = hand_law(p, dt, mu);
  ASSERT_GT(h.Rn, 0.0);
  Contacts contacts{pair_contact(p)};
  contacts[0].fn = 7.0 * h.Rn;
  contacts[0].ft = -3.0 * h.Rn;
  StepProblem pb;
  pb.cell = p.cell;
  pb.dt = dt;
  pb.mu = mu;
  pb.bath.enabled = false;
  pb.g_eff = positive_gaps(contacts);
  NlgsSettings set;
  set.tol = 1e-14;
  NlgsThreading threading;
  const NlgsResult res = solve_nlgs(pb, set, contacts, p.particles, threading);
  EXPECT_TRUE(res.converged);
  EXPECT_LT(rel(contacts[0].fn, h.Rn), 1e-12);
  EXPECT_LT(std::abs(contacts[0].ft - h.Rt), 1e-12 * h.Rn);
}

}  // namespace
}  // namespace unjam
