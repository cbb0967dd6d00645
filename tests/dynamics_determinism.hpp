#pragma once
// Thread-count determinism of the contact dynamics, shared by the physics tests
// (test_dynamics.cpp, a few steps) and the validation runs (test_validation.cpp, 30 steps):
// a dense, compressing 1200-disk state advanced with 1 and with 2 threads must give
// bit-identical positions, velocities and contact forces.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "physics_test_util.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/solver/coloring.hpp"
#include "unjam/solver/time_step.hpp"

namespace unjam::testing {

// A dense, compressing state of 1200 disks: a gas scaled to phi 0.82 (overlaps allowed,
// never corrected), random velocities, bath on.
inline Packing dense_state() {
  GasSettings gs;
  gs.N = 1200;
  gs.phi = 0.45;
  gs.seed = 5;
  Packing p = make_gas(gs);
  const double s = std::sqrt(0.45 / 0.82);
  p.cell.Lx *= s;
  p.cell.Ly *= s;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.particles.x[i] *= s;
    p.particles.y[i] *= s;
  }
  p.meta.contact.mu = 0.3;
  randomize_velocities(p.particles, 0.5, 0.5, 6);
  return p;
}

inline Packing run_dense(int threads, int steps, int max_sweeps, std::vector<int>* blocks_per_color = nullptr) {
  omp_set_num_threads(threads);
  Packing p = dense_state();
  DynamicsSettings ds;
  ds.nlgs.seed = 3;
  ds.nlgs.max_sweeps = max_sweeps;
  ds.nlgs.threading = Threading::kParallel;  // with 2 threads: the parallel path, always
  for (int s = 0; s < steps; ++s) {
    if (blocks_per_color && s == steps - 1) {
      // The solver's colouring of the last step (advance() mixes the seed with the step).
      Packing q = p;
      advance(q, ds);
      const std::uint64_t seed = ds.nlgs.seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(p.state.step);
      const Coloring col = color_contacts(q.contacts, static_cast<int>(q.size()), seed);
      for (int c = 0; c < col.num_colors(); ++c)
        blocks_per_color->push_back((col.color_start[c + 1] - col.color_start[c] + 127) / 128);
    }
    advance(p, ds);
  }
  return p;
}

inline void compare_one_and_two_threads(int steps, int max_sweeps) {
  const int saved = omp_get_max_threads();
  std::vector<int> blocks;
  const auto t0 = std::chrono::steady_clock::now();
  const Packing one = run_dense(1, steps, max_sweeps);
  const auto t1 = std::chrono::steady_clock::now();
  const Packing two = run_dense(2, steps, max_sweeps, &blocks);
  const auto t2 = std::chrono::steady_clock::now();
  omp_set_num_threads(saved);
  // Precondition: the solver really ran in parallel (more than 2 blocks of 128 contacts
  // per colour on average).
  int total = 0;
  for (int b : blocks) total += b;
  std::printf("[ determinism ] %d steps of <= %d sweeps: 1 thread %.2f s, 2 threads %.2f s; "
              "%zu contacts, %zu colours, %d blocks\n",
              steps, max_sweeps, std::chrono::duration<double>(t1 - t0).count(),
              std::chrono::duration<double>(t2 - t1).count(), two.contacts.size(), blocks.size(), total);
  ASSERT_GT(total, 2 * static_cast<int>(blocks.size())) << "not enough contacts for the parallel path";
  ASSERT_EQ(one.contacts.size(), two.contacts.size());
  EXPECT_EQ(one.cell.Lx, two.cell.Lx);
  EXPECT_EQ(one.state.lambda, two.state.lambda);
  EXPECT_EQ(one.particles.x, two.particles.x);
  EXPECT_EQ(one.particles.y, two.particles.y);
  EXPECT_EQ(one.particles.vx, two.particles.vx);
  EXPECT_EQ(one.particles.vy, two.particles.vy);
  EXPECT_EQ(one.particles.omega, two.particles.omega);
  int diff = 0;
  for (std::size_t k = 0; k < one.contacts.size(); ++k)
    diff += one.contacts[k].fn != two.contacts[k].fn || one.contacts[k].ft != two.contacts[k].ft ||
            one.contacts[k].a != two.contacts[k].a || one.contacts[k].b != two.contacts[k].b;
  EXPECT_EQ(diff, 0);
  // It is a loaded state.
  EXPECT_GT(std::count_if(one.contacts.begin(), one.contacts.end(), [](const Contact& c) { return c.fn > 0; }), 300);
}

}  // namespace unjam::testing
