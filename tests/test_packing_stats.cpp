#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "unjam/analysis/packing_stats.hpp"
#include "unjam/core/units.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam {
namespace {

const std::filesystem::path kFixtures = UNJAM_FIXTURES_DIR;

// Two disks (R_a = 1, R_b = 0.5) along x in a 10 x 10 cell, overlapping by 0.01, with a
// contact force fn = 2, ft = 0.5 and P_ext = 1 (F0 = 2 * 0.75 * 1 = 1.5).
Packing two_disks() {
  Packing p;
  p.cell = {10.0, 10.0};
  p.particles.resize(2);
  p.particles.x = {2.0, 3.49};
  p.particles.y = {5.0, 5.0};
  p.particles.radius = {1.0, 0.5};
  p.meta.contact.P_ext = 1.0;
  p.meta.contact.mu = 0.5;
  Contact c;
  c.a = 0;
  c.b = 1;
  c.l = {1.49, 0.0};
  c.n = {1.0, 0.0};
  c.gap = -0.01;
  c.fn = 2.0;
  c.ft = 0.5;
  p.contacts = {c};
  return p;
}

TEST(PackingStats, TwoDisksLoadsAndSigns) {
  const Packing p = two_disks();
  const GrainLoads loads = net_contact_loads(p);
  // Force on b: fn n + ft t = 2 (1, 0) + 0.5 (0, 1); on a the opposite.
  EXPECT_EQ(loads.force[1], Vec2(2.0, 0.5));
  EXPECT_EQ(loads.force[0], Vec2(-2.0, -0.5));
  // Torques T = -R ft: a positive ft turns both grains clockwise.
  EXPECT_EQ(loads.torque[0], -1.0 * 0.5);
  EXPECT_EQ(loads.torque[1], -0.5 * 0.5);

  const PackingStats s = compute_packing_stats(p);
  const double F0 = 2.0 * 0.75 * 1.0;
  EXPECT_DOUBLE_EQ(s.F0, F0);
  EXPECT_EQ(s.N, 2u);
  EXPECT_EQ(s.N_c, 1u);
  EXPECT_EQ(s.rattlers, 0u);
  EXPECT_EQ(s.N_prime, 2u);
  EXPECT_DOUBLE_EQ(s.z, 1.0);
  EXPECT_DOUBLE_EQ(s.phi, kPi * (1.0 + 0.25) / 100.0);
  EXPECT_DOUBLE_EQ(s.F_cont, 2.0 / F0);
  EXPECT_DOUBLE_EQ(s.max_overlap, 0.01);
  EXPECT_DOUBLE_EQ(s.mean_overlap, 0.01);
  EXPECT_DOUBLE_EQ(s.max_force_residual, std::hypot(2.0, 0.5) / F0);
  EXPECT_DOUBLE_EQ(s.mean_force_residual, std::hypot(2.0, 0.5) / F0);
  // |T_a| / (F0 R_a) = 0.5 / F0, |T_b| / (F0 R_b) = 0.25 / (0.5 F0) = 0.5 / F0.
  EXPECT_DOUBLE_EQ(s.max_torque_residual, 0.5 / F0);
  // P_in = fn |l| / (2 V) = 2 * 1.49 / 200.
  EXPECT_DOUBLE_EQ(s.P_in, 2.0 * 1.49 / 200.0);
  EXPECT_DOUBLE_EQ(s.pressure_ratio, s.P_in);
  EXPECT_EQ(s.max_coulomb_violation, 0.0);  // |ft| = 0.5 <= mu fn = 1
  EXPECT_EQ(s.max_tension, 0.0);
  EXPECT_FALSE(s.isostatic_excess);  // mu > 0
}

TEST(PackingStats, KineticPressureCoulombTensionAndRattlers) {
  Packing p = two_disks();
  p.particles.resize(3);  // a third grain, far away and moving
  p.particles.x[2] = 8.0;
  p.particles.y[2] = 1.0;
  p.particles.radius[2] = 1.0;
  p.particles.vx[2] = 0.3;
  p.particles.vy[2] = -0.4;
  p.meta.contact.mu = 0.0;
  p.contacts[0].fn = 2.0;
  p.contacts[0].ft = 0.5;  // |ft| - mu fn = 0.5
  Contact tensile = p.contacts[0];
  tensile.a = 1;
  tensile.b = 2;
  tensile.fn = -0.3;
  tensile.ft = 0.0;
  tensile.gap = 0.2;
  p.contacts.push_back(tensile);

  const PackingStats s = compute_packing_stats(p);
  const double F0 = p.force_unit();
  EXPECT_EQ(s.contacts, 2u);
  EXPECT_EQ(s.N_c, 1u);
  EXPECT_EQ(s.rattlers, 1u);  // grain 2: its only contact pulls
  EXPECT_EQ(s.N_prime, 2u);
  EXPECT_DOUBLE_EQ(s.F_mean_listed, (2.0 - 0.3) / 2.0 / F0);
  EXPECT_DOUBLE_EQ(s.mean_overlap, 0.005);
  EXPECT_DOUBLE_EQ(s.max_coulomb_violation, 0.5 / F0);
  EXPECT_DOUBLE_EQ(s.max_tension, 0.3 / F0);
  // P_in = [2 * 1.49 - 0.3 * 1.49 + pi * 0.25] / 200.
  EXPECT_DOUBLE_EQ(s.P_in, (2.0 * 1.49 - 0.3 * 1.49 + kPi * 0.25) / 200.0);
  ASSERT_TRUE(s.isostatic_excess);
  EXPECT_EQ(*s.isostatic_excess, 1 - (2 * 2 - 1));
}

TEST(PackingStats, FixtureP50MatchesItsReadme) {
  const PackingStats s = compute_packing_stats(read_packing(kFixtures / "p50-mu0.1"));
  EXPECT_EQ(s.N, 50u);
  EXPECT_EQ(s.contacts, 82u);
  EXPECT_EQ(s.N_c, 81u);
  EXPECT_EQ(s.rattlers, 6u);
  EXPECT_NEAR(s.phi, 0.829, 5e-4);
  EXPECT_NEAR(s.z, 3.68, 5e-3);
  EXPECT_DOUBLE_EQ(s.z, 2.0 * 81 / 44);
  // The README quotes 2.5e-12, the largest Cartesian component; |F_i| is up to sqrt(2) more.
  EXPECT_GT(s.max_force_residual, 2.4e-12);
  EXPECT_LT(s.max_force_residual, 3.6e-12);
  EXPECT_NEAR(s.max_overlap, 4.6e-6, 5e-8);
  EXPECT_NEAR(s.pressure_ratio, 1.0, 1e-6);
  EXPECT_LT(s.max_torque_residual, 1e-10);
  EXPECT_LT(s.max_coulomb_violation, 1e-10);
  EXPECT_EQ(s.max_tension, 0.0);
}

TEST(PackingStats, FixtureLattice16IsExact) {
  const Packing p = read_packing(kFixtures / "lattice16");
  const PackingStats s = compute_packing_stats(p);
  EXPECT_EQ(s.contacts, 48u);
  EXPECT_EQ(s.N_c, 48u);
  EXPECT_EQ(s.rattlers, 0u);
  EXPECT_DOUBLE_EQ(s.z, 6.0);
  EXPECT_DOUBLE_EQ(s.phi, 16.0 * kPi / (8.0 * 6.928203230275509));
  EXPECT_DOUBLE_EQ(s.F_cont, 1.1547005383792515 / 2.0);  // F0 = 2 R P_ext = 2
  EXPECT_NEAR(s.pressure_ratio, 1.0, 1e-12);              // 48 * 1.1547 * 2 / (2 * 8 * 6.928)
  EXPECT_LT(s.max_force_residual, 1e-14);
  EXPECT_LT(s.max_overlap, 1e-12);
  EXPECT_TRUE(missing_contacts(p, 1e-9).empty());
}

TEST(PackingStats, MissingContactsFindsUnlistedOverlaps) {
  Packing p = read_packing(kFixtures / "p50-mu0.1");
  EXPECT_TRUE(missing_contacts(p, 1e-9).empty());
  const Contact dropped = p.contacts[5];
  p.contacts.erase(p.contacts.begin() + 5);
  const auto missing = missing_contacts(p, 1e-9);
  ASSERT_EQ(missing.size(), 1u);
  EXPECT_EQ(missing[0], std::make_pair(std::min(dropped.a, dropped.b), std::max(dropped.a, dropped.b)));
}

TEST(PackingStats, MissingContactsAgreesWithAllPairs) {
  // Random overlapping disks, across the periodic boundary too.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Packing p;
  p.cell = {23.0, 17.0};
  p.particles.resize(400);
  for (std::size_t i = 0; i < 400; ++i) {
    p.particles.x[i] = p.cell.Lx * u(rng);
    p.particles.y[i] = p.cell.Ly * u(rng);
    p.particles.radius[i] = 0.5 + 0.5 * u(rng);
  }
  std::vector<std::pair<int, int>> expected;
  for (int i = 0; i < 400; ++i)
    for (int j = i + 1; j < 400; ++j) {
      const Vec2 l = p.cell.min_image(p.particles.position(j) - p.particles.position(i));
      if (l.norm() - p.particles.radius[i] - p.particles.radius[j] < -1e-3) expected.emplace_back(i, j);
    }
  ASSERT_GT(expected.size(), 100u);
  EXPECT_EQ(missing_contacts(p, 1e-3), expected);
  // Listing the first pair removes it.
  Contact c;
  c.a = expected[0].second;  // either order
  c.b = expected[0].first;
  p.contacts.push_back(c);
  expected.erase(expected.begin());
  EXPECT_EQ(missing_contacts(p, 1e-3), expected);
}

TEST(PackingStats, MissingContactsInATinyCell) {
  // Fewer than three bins per side: each pair still counted once.
  Packing p;
  p.cell = {3.0, 3.0};
  p.particles.resize(2);
  p.particles.x = {0.2, 2.8};
  p.particles.y = {1.0, 1.0};
  p.particles.radius = {1.0, 1.0};  // distance 0.4 through the boundary
  EXPECT_EQ(missing_contacts(p, 0.0), (std::vector<std::pair<int, int>>{{0, 1}}));
}

}  // namespace
}  // namespace unjam
