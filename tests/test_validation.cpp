// Validation runs, the test label `validation` (not in the default test preset; about a
// minute each here): the static-packing checks over more seeds and larger N, the uniqueness
// of the frictionless network, and thread-count determinism of compaction and of 30 steps of
// dynamics. Run them with `ctest --preset release -L validation` (README, "Tests").
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "dynamics_determinism.hpp"
#include "physics_test_util.hpp"
#include "static_packing_checks.hpp"
#include "unjam/analysis/packing_stats.hpp"
#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/lp/rank.hpp"
#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/solver/static_solve.hpp"

namespace unjam {
namespace {

using testing::check_frictionless;
using testing::check_mu01;
using testing::check_mu1;
using testing::compare_one_and_two_threads;

TEST(StaticPackingValidation, Frictionless) {
  for (std::uint64_t seed : {1, 4, 5, 6}) check_frictionless(100, seed);
  for (std::uint64_t seed : {1, 2, 3}) check_frictionless(200, seed);
}
TEST(StaticPackingValidation, Mu01) {
  for (std::uint64_t seed : {2, 3, 4}) check_mu01(100, seed);
  for (std::uint64_t seed : {2, 3}) check_mu01(200, seed);
}
TEST(StaticPackingValidation, Mu1) {
  for (std::uint64_t seed : {3, 4}) check_mu1(100, seed);
  for (std::uint64_t seed : {1, 2}) check_mu1(200, seed);
}

TEST(StaticPackingValidation, FrictionlessNetworkIsUniqueExactlyWhenIsostatic) {
  // mu = 0: the static network is unique when the packing is isostatic (force-carrying
  // contacts = 2N' - 1, docs/probe.md, "The probe"): a static solve from zero forces with another
  // seed must find the same forces. A packing with extra contacts (N = 200 seed 1 has one:
  // a pair overlapping by ~1e-4 counts as touching) has a family of networks instead: the
  // admissible set has dimension >= 1, and the solve may land anywhere in it.
  for (const auto& [N, seed] : {std::pair<int, std::uint64_t>{100, 2}, {100, 3}, {200, 1}}) {
    const Packing& p = testing::compacted(N, 0.0, seed).packing;
    const PackingStats stats = compute_packing_stats(p);
    ASSERT_TRUE(stats.isostatic_excess.has_value());
    if (*stats.isostatic_excess > 0) {
      const EquilibriumSystem sys = build_equilibrium_system(p, select_contacts(p, 1e-6));
      EXPECT_GE(equilibrium_rank(sys).dimension, 1) << "N " << N << " seed " << seed;
      continue;
    }
    Packing q = p;
    for (Contact& k : q.contacts) k.fn = k.ft = 0.0;
    StaticSolveSettings ss;
    ss.seed = 1234;
    const StaticSolveReport rep = solve_static(q, Bath{}, ss);
    ASSERT_TRUE(rep.converged);
    const double F0 = p.force_unit();
    double worst = 0.0;
    for (std::size_t k = 0; k < p.contacts.size(); ++k)
      worst = std::max(worst, std::abs(q.contacts[k].fn - p.contacts[k].fn) / F0);
    std::printf("[ uniqueness ] mu 0 N %d seed %llu: largest force difference %.3g F0\n", N,
                static_cast<unsigned long long>(seed), worst);
    EXPECT_LT(worst, 1e-6) << "seed " << seed;
  }
}

TEST(CompactionValidation, OneAndTwoThreadsGiveTheSameStaticPacking) {
  // 1200 disks compacted to a static packing with 1 and with 2 threads: bit-identical.
  const int saved = omp_get_max_threads();
  Packing result[2];
  for (int t = 0; t < 2; ++t) {
    omp_set_num_threads(t + 1);
    GasSettings gs;
    gs.N = 1200;
    gs.phi = 0.3;
    gs.seed = 3;
    result[t] = make_gas(gs);
    result[t].meta.contact.mu = 0.1;
    const CompactionResult r = compact(result[t], CompactionSettings{});
    EXPECT_TRUE(r.is_static);
  }
  omp_set_num_threads(saved);
  EXPECT_EQ(result[0].particles.x, result[1].particles.x);
  EXPECT_EQ(result[0].particles.y, result[1].particles.y);
  EXPECT_EQ(result[0].cell.Lx, result[1].cell.Lx);
  ASSERT_EQ(result[0].contacts.size(), result[1].contacts.size());
  for (std::size_t k = 0; k < result[0].contacts.size(); ++k) {
    EXPECT_EQ(result[0].contacts[k].fn, result[1].contacts[k].fn);
    EXPECT_EQ(result[0].contacts[k].ft, result[1].contacts[k].ft);
  }
}

// The 30-step version with the default sweep limit.
TEST(DeterminismValidation, OneAndTwoThreadsThirtySteps) { compare_one_and_two_threads(30, 200); }

}  // namespace
}  // namespace unjam
