#pragma once
// Helpers shared by the physics tests of the contact-dynamics engine (test_contact_law,
// test_dynamics, test_bath, test_static_packing, test_detection). Everything here is
// computed independently of the engine, from the sign conventions of contact.hpp:
//   force on b = fn n + ft t, on a its negative; T_a = -R_a ft, T_b = -R_b ft.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "unjam/core/cell.hpp"
#include "unjam/core/units.hpp"
#include "unjam/core/vec2.hpp"
#include "unjam/packing/contact.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/packing/particles.hpp"

namespace unjam::testing {

// A packing of two disks in a square cell of side L (no contacts yet).
inline Packing two_disks(double L, Vec2 ra, double Ra, Vec2 va, double wa, Vec2 rb, double Rb,
                         Vec2 vb, double wb, double mu) {
  Packing p;
  p.cell = {L, L};
  p.particles.resize(2);
  auto& P = p.particles;
  P.x = {ra.x(), rb.x()};
  P.y = {ra.y(), rb.y()};
  P.radius = {Ra, Rb};
  P.vx = {va.x(), vb.x()};
  P.vy = {va.y(), vb.y()};
  P.omega = {wa, wb};
  p.meta.contact.mu = mu;
  return p;
}

// Net contact force and torque on every grain, from the contact list.
struct GrainLoads {
  std::vector<Vec2> force;
  std::vector<double> torque;
};

inline GrainLoads grain_loads(const Particles& P, const Contacts& contacts) {
  GrainLoads g{std::vector<Vec2>(P.size(), Vec2::Zero()), std::vector<double>(P.size(), 0.0)};
  for (const Contact& c : contacts) {
    const Vec2 t = tangent(c.n);
    const Vec2 F = c.fn * c.n + c.ft * t;
    g.force[c.b] += F;
    g.force[c.a] -= F;
    g.torque[c.a] += -P.radius[c.a] * c.ft;
    g.torque[c.b] += -P.radius[c.b] * c.ft;
  }
  return g;
}

inline Vec2 momentum(const Particles& P) {
  Vec2 m = Vec2::Zero();
  for (std::size_t i = 0; i < P.size(); ++i) m += P.mass(i) * P.velocity(i);
  return m;
}

// Sum of m |v| (the scale of the momentum round-off).
inline double momentum_scale(const Particles& P) {
  double s = 0.0;
  for (std::size_t i = 0; i < P.size(); ++i) s += P.mass(i) * P.velocity(i).norm();
  return s;
}

// Translational + rotational kinetic energy.
inline double kinetic_energy(const Particles& P) {
  double e = 0.0;
  for (std::size_t i = 0; i < P.size(); ++i)
    e += 0.5 * P.mass(i) * P.velocity(i).squaredNorm() + 0.5 * P.inertia(i) * P.omega[i] * P.omega[i];
  return e;
}

// All pairs (a < b) with gap |l| - R_a - R_b < max_gap, by brute force over all pairs.
inline std::vector<std::pair<int, int>> brute_force_pairs(const Particles& P, const Cell& cell,
                                                          double max_gap) {
  std::vector<std::pair<int, int>> out;
  const int n = static_cast<int>(P.size());
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const Vec2 l = cell.min_image(P.position(b) - P.position(a));
      if (l.norm() - P.radius[a] - P.radius[b] < max_gap) out.emplace_back(a, b);
    }
  return out;
}

inline double packing_fraction(const Packing& p) {
  double area = 0.0;
  for (const double R : p.particles.radius) area += disk_mass(R);
  return area / p.cell.area();
}

// Random velocities: components uniform in [-v, v], spins uniform in [-w, w].
inline void randomize_velocities(Particles& P, double v, double w, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t i = 0; i < P.size(); ++i) {
    P.vx[i] = v * u(rng);
    P.vy[i] = v * u(rng);
    P.omega[i] = w * u(rng);
  }
}

}  // namespace unjam::testing

// ---- compacted packings, shared by the tests of one run (compaction is the slow part) ----
#include <map>
#include <tuple>

#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"

namespace unjam::testing {

struct Compacted {
  Packing gas;       // the initial gas
  Packing packing;   // after compact()
  CompactionResult result;
  double seconds = 0.0;
};

// compact(make_gas(N, phi 0.3, seed)) at friction mu with the default settings; cached.
inline const Compacted& compacted(int N, double mu, std::uint64_t seed) {
  static std::map<std::tuple<int, double, std::uint64_t>, Compacted> cache;
  const auto key = std::make_tuple(N, mu, seed);
  auto it = cache.find(key);
  if (it == cache.end()) {
    Compacted c;
    GasSettings gs;
    gs.N = N;
    gs.phi = 0.3;
    gs.seed = seed;
    c.gas = make_gas(gs);
    c.gas.meta.contact.mu = mu;
    c.packing = c.gas;
    CompactionSettings cs;
    c.result = compact(c.packing, cs);
    c.seconds = c.result.wall_s;
    it = cache.emplace(key, std::move(c)).first;
  }
  return it->second;
}

}  // namespace unjam::testing
