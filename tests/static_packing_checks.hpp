#pragma once
// The checks every static packing made by compact() must pass (docs/method.md, "Compaction";
// docs/analysis.md, "Static measurements of a packing"), shared by the physics tests
// (test_static_packing.cpp) and the validation runs (test_validation.cpp): force and torque
// balance of every grain computed from the contact list, Coulomb, no tension, the pressure,
// overlaps, completeness of the contact list, and packing fraction and coordination per mu.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "physics_test_util.hpp"

namespace unjam::testing {

struct Measured {
  double max_residual_F0 = 0.0;  // largest grain |force| or |torque| / R, / F0
  double max_overlap = 0.0;      // largest -gap over all pairs
  double P_ratio = 0.0;
  double phi = 0.0;
  int force_carrying = 0;        // contacts with fn > 1e-9 F0
  int non_rattlers = 0;          // grains with a force-carrying contact
  double z = 0.0;
};

// Every check that holds for any static packing; returns the measured values.
inline Measured check_static(const Compacted& c, double mu, const std::string& label) {
  const Packing& p = c.packing;
  const Particles& P = p.particles;
  Measured m;
  EXPECT_TRUE(c.result.is_static) << label;
  EXPECT_TRUE(p.state.is_static) << label;
  EXPECT_EQ(p.meta.contact.mu, mu);
  const double F0 = p.force_unit();
  EXPECT_DOUBLE_EQ(F0, 2.0 * p.mean_radius() * p.meta.contact.P_ext);
  // Velocities zero.
  for (std::size_t i = 0; i < P.size(); ++i) {
    EXPECT_EQ(P.vx[i], 0.0) << label;
    EXPECT_EQ(P.vy[i], 0.0) << label;
    EXPECT_EQ(P.omega[i], 0.0) << label;
  }
  EXPECT_EQ(p.state.lambda, 0.0) << label;
  // Contact geometry is the one of the final positions; Coulomb and no tension.
  for (const Contact& k : p.contacts) {
    EXPECT_LT(k.a, k.b);
    const Vec2 l = p.cell.min_image(P.position(k.b) - P.position(k.a));
    EXPECT_LT((k.l - l).norm(), 1e-12) << label << " contact " << k.a << "-" << k.b;
    EXPECT_NEAR(k.gap, l.norm() - P.radius[k.a] - P.radius[k.b], 1e-12);
    EXPECT_GE(k.fn, 0.0) << label << " tension at " << k.a << "-" << k.b;
    EXPECT_LE(std::abs(k.ft), mu * k.fn + 1e-12 * F0) << label << " Coulomb at " << k.a << "-" << k.b;
  }
  // Force and torque balance of every grain, from the contact forces.
  const GrainLoads loads = grain_loads(P, p.contacts);
  for (std::size_t i = 0; i < P.size(); ++i)
    m.max_residual_F0 = std::max({m.max_residual_F0, loads.force[i].norm() / F0,
                                  std::abs(loads.torque[i]) / P.radius[i] / F0});
  EXPECT_LT(m.max_residual_F0, 1e-8) << label;
  // Pressure: P_in = sum fn |l| / (2V) (no kinetic part).
  double S = 0.0;
  for (const Contact& k : p.contacts) S += k.fn * k.l.norm();
  m.P_ratio = S / (2.0 * p.cell.area()) / p.meta.contact.P_ext;
  EXPECT_NEAR(m.P_ratio, 1.0, 1e-8) << label;
  // Overlaps, and no overlapping pair missing from the contact list (brute force).
  std::set<std::pair<int, int>> listed;
  for (const Contact& k : p.contacts) listed.insert({k.a, k.b});
  for (const auto& [a, b] : brute_force_pairs(P, p.cell, 0.0)) {
    EXPECT_TRUE(listed.count({a, b})) << label << ": overlapping pair " << a << "-" << b << " not in the list";
    const double gap = p.cell.min_image(P.position(b) - P.position(a)).norm() - P.radius[a] - P.radius[b];
    m.max_overlap = std::max(m.max_overlap, -gap);
  }
  // Measured 1.6e-4 .. 5.8e-4 for N = 100 and 200, mu = 0, 0.1, 1 (dt = 0.01, default
  // compaction settings): the accumulated overlap that g+ never corrects.
  EXPECT_LT(m.max_overlap, 1e-3) << label;
  // Packing fraction and coordination.
  m.phi = packing_fraction(p);
  std::vector<int> deg(P.size(), 0);
  for (const Contact& k : p.contacts)
    if (k.fn > 1e-9 * F0) ++m.force_carrying, ++deg[k.a], ++deg[k.b];
  m.non_rattlers = static_cast<int>(std::count_if(deg.begin(), deg.end(), [](int d) { return d > 0; }));
  m.z = 2.0 * m.force_carrying / m.non_rattlers;
  // A non-rattler has at least 2 (collinear) force-carrying contacts; 3 unless mu = 0 ...
  for (std::size_t i = 0; i < P.size(); ++i) EXPECT_NE(deg[i], 1) << label << " grain " << i;
  std::printf("[ %s ] phi %.6f  z %.4f  Nc %d  N' %d  2N'-1 %d  residual %.2g F0  |P/Pext-1| %.2g  "
              "overlap %.2g  (%.1f s, %lld steps)\n",
              label.c_str(), m.phi, m.z, m.force_carrying, m.non_rattlers, 2 * m.non_rattlers - 1,
              m.max_residual_F0, std::abs(m.P_ratio - 1.0), m.max_overlap, c.seconds,
              static_cast<long long>(c.result.steps));
  return m;
}

inline void check_frictionless(int N, std::uint64_t seed) {
  const std::string label = "N " + std::to_string(N) + " mu 0 seed " + std::to_string(seed);
  const Measured m = check_static(compacted(N, 0.0, seed), 0.0, label);
  // Isostatic: force-carrying contacts = 2 N' - 1 (up to 2).
  EXPECT_NEAR(m.force_carrying, 2 * m.non_rattlers - 1, 2) << label;
  EXPECT_GE(m.phi, 0.82) << label;
  EXPECT_LE(m.phi, 0.86) << label;
  EXPECT_NEAR(m.z, 4.0, 0.1) << label;
  // No tangential force at all.
  for (const Contact& k : compacted(N, 0.0, seed).packing.contacts) EXPECT_EQ(k.ft, 0.0);
}

// A frictional packing's check_static plus its expected ranges of phi and z.
inline Measured check_frictional(int N, double mu, std::uint64_t seed, double phi_lo, double phi_hi,
                                 double z_lo, double z_hi, std::string& label) {
  std::ostringstream name;
  name << "N " << N << " mu " << mu << " seed " << seed;
  label = name.str();
  const Measured m = check_static(compacted(N, mu, seed), mu, label);
  EXPECT_GE(m.phi, phi_lo) << label;
  EXPECT_LE(m.phi, phi_hi) << label;
  EXPECT_GE(m.z, z_lo) << label;
  EXPECT_LE(m.z, z_hi) << label;
  return m;
}

inline void check_mu01(int N, std::uint64_t seed) {
  std::string label;
  check_frictional(N, 0.1, seed, 0.80, 0.845, 3.3, 3.85, label);
}

inline void check_mu1(int N, std::uint64_t seed) {
  std::string label;
  const Measured m = check_frictional(N, 1.0, seed, 0.77, 0.82, 2.9, 3.3, label);
  // Hypostatic with respect to the frictionless count, hyperstatic w.r.t. friction (3N'-1).
  EXPECT_LT(m.force_carrying, 2 * m.non_rattlers - 1) << label;
}

}  // namespace unjam::testing
