// Exact per-contact normal-force intervals by LP: fixtures against an independent LP (HiGHS),
// hand-made systems with known answers, monotonicity in mu, runs stopped and resumed through
// their checkpoint (campaign/bounds_checkpoint), the command-line tool; the friction threshold
// (ensemble/friction_threshold) against the LP's emptiness by both methods.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include <coin/ClpSimplex.hpp>

#include "unjam/campaign/bounds_checkpoint.hpp"
#include "unjam/campaign/threshold_checkpoint.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/ensemble/friction_threshold.hpp"
#include "unjam/lp/force_lp.hpp"
#include "unjam/lp/rank.hpp"
#include "unjam/packing/packing_io.hpp"

namespace {

namespace fs = std::filesystem;
using unjam::Contact;
using unjam::Packing;

std::string fixture_dir(const char* name) { return std::string(UNJAM_FIXTURES_DIR) + "/" + name; }

struct Reference {
  int a, b;
  double fn, fn_min, fn_max;
};

std::vector<Reference> read_reference(const std::string& dir) {
  std::ifstream in(dir + "/bounds-reference.csv");
  std::string line;
  std::getline(in, line);  // header a,b,fn,fn_min,fn_max
  std::vector<Reference> rows;
  while (std::getline(in, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    Reference r{};
    s >> r.a >> r.b >> r.fn >> r.fn_min >> r.fn_max;
    rows.push_back(r);
  }
  return rows;
}

// A contact from a to b with branch vector l (minimum image chosen by hand).
Contact contact(int a, int b, unjam::Vec2 l) {
  Contact c;
  c.a = a;
  c.b = b;
  c.l = l;
  c.n = l.normalized();
  return c;
}

// Two disks R = 0.5 in a periodic 2 x 10 cell, touching along x directly and through the
// periodic image. x-balance: fn_0 = fn_1; torque and y balance: ft = 0; pressure:
// (fn_0 + fn_1) |l| = 2 V P_ext = 40, so fn = 20 exactly, for any mu.
Packing two_disk_chain(double mu) {
  Packing p;
  p.cell = {2.0, 10.0};
  p.meta.contact.mu = mu;
  p.particles.resize(2);
  p.particles.x = {0.5, 1.5};
  p.particles.y = {5.0, 5.0};
  p.particles.radius = {0.5, 0.5};
  p.contacts = {contact(0, 1, {1, 0}), contact(1, 0, {1, 0})};
  for (auto& c : p.contacts) c.fn = 20.0;
  return p;
}

// Four disks R = 0.5 on a square lattice in a periodic 2 x 2 cell: two horizontal and two
// vertical chains of two contacts. At mu = 0 each chain carries one force h_A, h_B, v_A, v_B
// >= 0 with 2 (h_A + h_B + v_A + v_B) = 2 V P_ext = 8: every interval is [0, 4].
Packing square_lattice(double mu) {
  Packing p;
  p.cell = {2.0, 2.0};
  p.meta.contact.mu = mu;
  p.particles.resize(4);
  p.particles.x = {0.5, 1.5, 0.5, 1.5};
  p.particles.y = {0.5, 0.5, 1.5, 1.5};
  p.particles.radius = {0.5, 0.5, 0.5, 0.5};
  p.contacts = {contact(0, 1, {1, 0}), contact(1, 0, {1, 0}), contact(2, 3, {1, 0}),
                contact(3, 2, {1, 0}), contact(0, 2, {0, 1}), contact(2, 0, {0, 1}),
                contact(1, 3, {0, 1}), contact(3, 1, {0, 1})};
  for (auto& c : p.contacts) c.fn = 1.0;
  return p;
}

void expect_matches_reference(const char* name, unjam::LpMethod method, int threads) {
  const Packing p = unjam::read_packing(fixture_dir(name));
  const auto sys = unjam::build_equilibrium_system(p);
  const auto ref = read_reference(fixture_dir(name));
  ASSERT_EQ(static_cast<int>(ref.size()), sys.num_contacts()) << name;
  unjam::ForceBoundsOptions options;
  options.method = method;
  options.threads = threads;
  const auto bounds = unjam::compute_force_bounds(sys, options);
  const double F0 = p.force_unit();
  for (int k = 0; k < sys.num_contacts(); ++k) {
    const Contact& c = p.contacts[sys.contacts[k]];
    ASSERT_EQ(c.a, ref[k].a);
    ASSERT_EQ(c.b, ref[k].b);
    EXPECT_NEAR(bounds.fn_min[k], ref[k].fn_min, 1e-6 * F0) << name << " contact " << k;
    EXPECT_NEAR(bounds.fn_max[k], ref[k].fn_max, 1e-6 * F0) << name << " contact " << k;
  }
}

TEST(ForceBounds, P50MatchesReferenceBarrier) {
  expect_matches_reference("p50-mu0.1", unjam::LpMethod::barrier, 1);
}
TEST(ForceBounds, P50MatchesReferenceSimplex) {
  expect_matches_reference("p50-mu0.1", unjam::LpMethod::simplex, 1);
}
TEST(ForceBounds, P50MatchesReferenceTwoThreads) {
  expect_matches_reference("p50-mu0.1", unjam::LpMethod::barrier, 2);
}
TEST(ForceBounds, Lattice16MatchesReference) {
  expect_matches_reference("lattice16", unjam::LpMethod::barrier, 1);
  expect_matches_reference("lattice16", unjam::LpMethod::simplex, 1);
}

TEST(ForceBounds, MinimaCertifiedByArgmaxNetworksEqualTheirOwnLp) {
  // compute_force_bounds skips the min LP of a contact that some argmax network leaves open;
  // every minimum must equal the plain LP of that contact, and some must have been skipped.
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p);
  const auto bounds = unjam::compute_force_bounds(sys);
  EXPECT_GT(bounds.min_lps_skipped, 5);
  EXPECT_LT(bounds.min_lps_skipped, sys.num_contacts());
  unjam::ForceLP lp(sys);
  const double F0 = p.force_unit();
  int zeros = 0;
  for (int k = 0; k < sys.num_contacts(); ++k) {
    const double direct = lp.min_fn(k);
    EXPECT_NEAR(bounds.fn_min[k], direct, 1e-8 * F0) << "contact " << k;
    if (bounds.fn_min[k] == 0.0) {
      ++zeros;
      EXPECT_LE(direct, 1e-9 * F0) << "contact " << k << " certified open";
    }
  }
  EXPECT_GE(zeros, bounds.min_lps_skipped);
}

TEST(ForceBounds, SharedCholeskyAnalysisGivesTheFreshOptimum) {
  // One ForceLP re-solves LP after LP with the Cholesky analysis of its first solve (and a
  // copy carries it to another thread); each optimum must equal that of a ForceLP built
  // for that LP alone, whose analysis is its own. Min and max alternate so that rows
  // dropped by one factorisation sequence cannot leak into the next.
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p);
  const double F0 = p.force_unit();
  unjam::ForceLP shared(sys);
  for (int k = 0; k < sys.num_contacts(); ++k) {
    const double shared_max = shared.max_fn(k), shared_min = shared.min_fn(k);
    EXPECT_NEAR(shared_max, unjam::ForceLP(sys).max_fn(k), 1e-9 * F0) << "contact " << k;
    EXPECT_NEAR(shared_min, unjam::ForceLP(sys).min_fn(k), 1e-9 * F0) << "contact " << k;
    EXPECT_LE(shared_min, shared_max + 1e-9 * F0) << "contact " << k;
  }
  unjam::ForceLP copy(shared);
  EXPECT_NEAR(copy.max_fn(0), unjam::ForceLP(sys).max_fn(0), 1e-9 * F0);
}

TEST(ForceBounds, StalledBarrierIsSolvedAgainAtLooserTolerance) {
  // At 8000 disks a barrier solve now and then stalls just short of the 1e-9 gap; p50 does the
  // same at a tolerance of 1e-13 (the maximum of contact 59). Each such LP must be solved
  // again by the barrier at 10x / 100x the tolerance (not by the simplex fallback, minutes at
  // 8000 disks), be counted and flagged, and end at the right maximum.
  // (Only maxima: at 1e-13 CLP's barrier also ends some minima "optimal" at wrong points,
  // which is why ForceLP's tolerance stays at 1e-9.)
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p);
  const auto ref = read_reference(fixture_dir("p50-mu0.1"));
  const double F0 = p.force_unit();
  unjam::ForceLP lp(sys, unjam::LpMethod::barrier, 1e-13);
  long long flagged = 0;
  for (int k = 0; k < sys.num_contacts(); ++k) {
    EXPECT_NEAR(lp.max_fn(k), ref[k].fn_max, 1e-8 * F0) << "contact " << k;
    flagged += lp.last_solve_loosened();
  }
  EXPECT_GE(lp.loosened_solves(), 1);
  EXPECT_EQ(flagged, lp.loosened_solves());
  // At the default tolerance none of them stalls.
  unjam::ForceLP normal(sys);
  for (int k = 0; k < sys.num_contacts(); ++k) normal.max_fn(k);
  EXPECT_EQ(normal.loosened_solves(), 0);
}

// The LP's tolerances are checked before any LP; a wider open tolerance turns exactly the
// minima at or below it into 0 (some of them without an LP of their own) and leaves every other
// end to the bit; a looser LP tolerance moves the ends by no more than the docs say
// (docs/ensemble.md, "The LP's tolerances").
TEST(ForceBounds, TolerancesAreCheckedAndOpenTolOnlyZeroesTheMinimaBelowIt) {
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p);
  const double F0 = p.force_unit();
  const double nan = std::nan("");
  for (const auto& [tolerance, open, why] :
       {std::tuple{0.0, 1e-9, "LP tolerance must be in [1e-12, 1e-06] (got 0)"},
        std::tuple{1e-13, 1e-9, "LP tolerance must be in [1e-12, 1e-06] (got 1e-13)"},
        std::tuple{2e-6, 1e-9, "LP tolerance"}, std::tuple{nan, 1e-9, "LP tolerance"},
        std::tuple{1e-9, 0.0, "open tolerance must be in (0, 0.001] F0 (got 0)"},
        std::tuple{1e-9, -1.0, "open tolerance"}, std::tuple{1e-9, 2e-3, "open tolerance"},
        std::tuple{1e-9, nan, "open tolerance"}}) {
    unjam::ForceBoundsOptions o;
    o.tolerance = tolerance;
    o.open_tol_F0 = open;
    int lps = 0;
    o.progress = [&lps](int, int) { ++lps; };
    try {
      unjam::compute_force_bounds(sys, o);
      ADD_FAILURE() << "accepted: tolerance " << tolerance << ", open " << open;
    } catch (const unjam::Error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_EQ(lps, 0);
  }
  const unjam::ForceBounds normal = unjam::compute_force_bounds(sys);
  unjam::ForceBoundsOptions wide;
  wide.open_tol_F0 = unjam::kMaxOpenTolF0;  // 1e-3 F0
  const unjam::ForceBounds w = unjam::compute_force_bounds(sys, wide);
  int zeroed = 0;
  for (int k = 0; k < sys.num_contacts(); ++k) {
    EXPECT_EQ(w.fn_max[k], normal.fn_max[k]) << k;
    if (normal.fn_min[k] > 1e-3 * F0 * (1 + 1e-6)) {
      EXPECT_EQ(w.fn_min[k], normal.fn_min[k]) << k;
    } else {
      EXPECT_EQ(w.fn_min[k], 0.0) << k;
      zeroed += normal.fn_min[k] > 0.0;
    }
  }
  EXPECT_GE(w.min_lps_skipped, normal.min_lps_skipped);
  EXPECT_GE(zeroed, 1);  // p50: one minimum lies in (1e-9, 1e-3] F0
  unjam::ForceBoundsOptions loose;
  loose.tolerance = unjam::kMaxLpTolerance;
  const unjam::ForceBounds l = unjam::compute_force_bounds(sys, loose);
  double moved = 0.0;
  for (int k = 0; k < sys.num_contacts(); ++k)
    moved = std::max({moved, std::abs(l.fn_max[k] - normal.fn_max[k]), std::abs(l.fn_min[k] - normal.fn_min[k])});
  EXPECT_LT(moved, 2e-6 * F0);  // measured: 4.3e-7 F0
}

TEST(ForceBounds, PackingNetworkLiesInsideEveryInterval) {
  for (const char* name : {"p50-mu0.1", "lattice16"}) {
    const Packing p = unjam::read_packing(fixture_dir(name));
    const auto sys = unjam::build_equilibrium_system(p);
    const auto bounds = unjam::compute_force_bounds(sys);
    const double tol = 1e-7 * p.force_unit();
    for (int k = 0; k < sys.num_contacts(); ++k) {
      const double fn = p.contacts[sys.contacts[k]].fn;
      EXPECT_LE(bounds.fn_min[k], fn + tol) << name << " contact " << k;
      EXPECT_GE(bounds.fn_max[k], fn - tol) << name << " contact " << k;
    }
  }
}

TEST(ForceBounds, TwoDiskChainIsDeterminateForAnyMu) {
  for (double mu : {0.0, 0.5}) {
    const Packing p = two_disk_chain(mu);
    const auto sys = unjam::build_equilibrium_system(p);
    for (auto method : {unjam::LpMethod::barrier, unjam::LpMethod::simplex}) {
      unjam::ForceBoundsOptions options;
      options.method = method;
      const auto bounds = unjam::compute_force_bounds(sys, options);
      for (int k = 0; k < 2; ++k) {
        EXPECT_NEAR(bounds.fn_min[k], 20.0, 1e-7) << "mu " << mu;
        EXPECT_NEAR(bounds.fn_max[k], 20.0, 1e-7) << "mu " << mu;
      }
    }
  }
}

TEST(ForceBounds, SquareLatticeAtMuZeroByHand) {
  const Packing p = square_lattice(0.0);
  const auto sys = unjam::build_equilibrium_system(p);
  EXPECT_EQ(unjam::equilibrium_rank(sys).dimension, 3);  // 4 chain forces, 1 pressure row
  const auto bounds = unjam::compute_force_bounds(sys);
  for (int k = 0; k < 8; ++k) {
    EXPECT_NEAR(bounds.fn_min[k], 0.0, 1e-7);
    EXPECT_NEAR(bounds.fn_max[k], 4.0, 1e-7);
  }
}

TEST(ForceBounds, RaisingMuOnlyWidensIntervals) {
  Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto contacts = unjam::select_contacts(p);
  const auto sys01 = unjam::build_equilibrium_system(p, contacts);
  p.meta.contact.mu = 0.3;
  const auto sys03 = unjam::build_equilibrium_system(p, contacts);
  const auto b01 = unjam::compute_force_bounds(sys01);
  const auto b03 = unjam::compute_force_bounds(sys03);
  const double tol = 1e-7 * p.force_unit();
  double widening = 0.0;
  for (int k = 0; k < sys01.num_contacts(); ++k) {
    EXPECT_LE(b03.fn_min[k], b01.fn_min[k] + tol) << k;
    EXPECT_GE(b03.fn_max[k], b01.fn_max[k] - tol) << k;
    widening += (b03.fn_max[k] - b03.fn_min[k]) - (b01.fn_max[k] - b01.fn_min[k]);
  }
  EXPECT_GT(widening, 0.0);
}

TEST(ForceBounds, NetworkAtMaxIsAdmissibleAndAttainsTheMax) {
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p);
  for (auto method : {unjam::LpMethod::barrier, unjam::LpMethod::simplex}) {
    unjam::ForceBoundsOptions options;
    options.method = method;
    options.keep_networks_at_max = true;
    const auto bounds = unjam::compute_force_bounds(sys, options);
    ASSERT_EQ(static_cast<int>(bounds.network_at_max.size()), sys.num_contacts());
    const double F0 = p.force_unit(), tol = 1e-7 * F0;
    for (int k = 0; k < sys.num_contacts(); k += 7) {
      const auto& net = bounds.network_at_max[k];
      EXPECT_NEAR(net.fn[k], bounds.fn_max[k], 1e-9 * F0);
      Eigen::VectorXd x(2 * sys.num_contacts());
      for (int j = 0; j < sys.num_contacts(); ++j) {
        x[2 * j] = net.fn[j];
        x[2 * j + 1] = net.ft[j];
        EXPECT_GE(net.fn[j], -tol);
        EXPECT_LE(std::abs(net.ft[j]), sys.mu * net.fn[j] + tol);
      }
      EXPECT_LT((sys.A * x - sys.rhs).cwiseAbs().maxCoeff(), 1e-6 * F0);
      const auto states = unjam::contact_states(net, sys.mu, 1e-9 * F0);
      EXPECT_NE(states[k], unjam::ContactState::open);
    }
  }
}

TEST(ForceBounds, InfeasibleSystemIsReported) {
  Packing p = two_disk_chain(0.5);
  p.contacts.pop_back();  // one contact cannot balance: fn = 0, but P_ext needs fn > 0
  const auto sys = unjam::build_equilibrium_system(p);
  try {
    unjam::compute_force_bounds(sys);
    FAIL() << "expected unjam::Error";
  } catch (const unjam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("no admissible force network"), std::string::npos);
  }
}

// Below the friction coefficient at which the packing can still be held (p500-mu0.1: between
// 0.097 and 0.0975, by dual simplex) the admissible set is empty. CLP's barrier then ends
// "optimal" at points whose grains are out of balance by ~1e-4 of their forces, which passed a
// check against max |rhs| (the pressure row's 2 V P_ext) and gave intervals with fn_min > fn_max
// (docs/ensemble.md, "The LP"). Both methods must report the empty set, and just above the
// threshold find the same intervals.
TEST(ForceBounds, BelowThePackingsOwnThresholdBothMethodsFindNoNetwork) {
  Packing p = unjam::read_packing(fixture_dir("p500-mu0.1"));
  const auto contacts = unjam::select_contacts(p);
  for (const double mu : {0.095, 0.096, 0.097}) {
    p.meta.contact.mu = mu;
    const auto sys = unjam::build_equilibrium_system(p, contacts);
    for (const auto method : {unjam::LpMethod::barrier, unjam::LpMethod::simplex}) {
      try {
        unjam::ForceLP lp(sys, method);
        FAIL() << "mu = " << mu << ": expected no admissible network";
      } catch (const unjam::Error& e) {
        EXPECT_NE(std::string(e.what()).find("no admissible force network"), std::string::npos) << e.what();
      }
    }
  }
  p.meta.contact.mu = 0.0975;
  const auto sys = unjam::build_equilibrium_system(p, contacts);
  unjam::ForceLP barrier(sys, unjam::LpMethod::barrier), simplex(sys, unjam::LpMethod::simplex);
  const double F0 = p.force_unit();
  // Each simplex optimum's network, so near the threshold, balances every grain and the
  // pressure to round-off and lies in the cones (ForceLP checks it, and solves again without
  // scaling where CLP's scaled optimum fails: docs/ensemble.md, "The LP").
  const auto expect_admissible = [&](const unjam::ForceNetwork& net, int k) {
    Eigen::VectorXd x(2 * sys.num_contacts());
    for (int j = 0; j < sys.num_contacts(); ++j) {
      x[2 * j] = net.fn[j];
      x[2 * j + 1] = net.ft[j];
      EXPECT_GE(net.fn[j], -1e-9 * F0) << k;
      EXPECT_LE(std::abs(net.ft[j]), sys.mu * net.fn[j] + 1e-9 * F0) << k;
    }
    EXPECT_LT((sys.A * x - sys.rhs).cwiseAbs().maxCoeff(), 1e-8 * F0) << k;
  };
  for (int k = 0; k < sys.num_contacts(); k += 97) {
    const double lo = barrier.min_fn(k), hi = barrier.max_fn(k);
    EXPECT_LE(lo, hi) << k;
    EXPECT_NEAR(lo, simplex.min_fn(k), 1e-7 * F0) << k;
    expect_admissible(simplex.network(), k);
    EXPECT_NEAR(hi, simplex.max_fn(k), 1e-7 * F0) << k;
    expect_admissible(simplex.network(), k);
  }
  EXPECT_EQ(barrier.simplex_finishes(), 0);
  EXPECT_EQ(barrier.unscaled_solves(), 0);  // only simplex solves are re-solved unscaled
}

// A simplex optimum is not taken on trust either. On p500-mu0.1 at its own mu, the min of fn of
// contact 618 warm-started from that of contact 617 ends "optimal" on CLP's scaled model
// (Debian's CLP 1.17) at a point with a cone coordinate of -4.6e-9 (the tolerance is 1e-9), so
// the contact's force lies outside its cone; ForceLP solves it again without scaling, where the
// optimum is admissible and its value that of the LP from scratch (docs/ensemble.md, "The LP").
TEST(ForceBounds, ASimplexOptimumOutsideTheConesIsSolvedAgainUnscaled) {
  const Packing p = unjam::read_packing(fixture_dir("p500-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  const double F0 = p.force_unit();
  unjam::ForceLP warm(sys, unjam::LpMethod::simplex), cold(sys, unjam::LpMethod::simplex);
  warm.min_fn(617);
  const double v = warm.min_fn(618);
  EXPECT_EQ(warm.unscaled_solves(), 1)
      << "CLP's scaled optimum is admissible here now: the unscaled solve needs another case";
  const unjam::ForceNetwork net = warm.network();
  for (int j = 0; j < sys.num_contacts(); ++j)  // the cone coordinates fn -+ ft / mu >= -1e-9
    EXPECT_GE(net.fn[j] - std::abs(net.ft[j]) / sys.mu, -1e-9) << j;
  EXPECT_NEAR(net.fn[618], v, 1e-12 * F0);
  EXPECT_NEAR(v, cold.min_fn(618), 1e-10 * F0);
  EXPECT_EQ(cold.unscaled_solves(), 0);
}

// The friction threshold of p500-mu0.1 lies between 0.097 and 0.0975 (the test above: no
// network at 0.095-0.097 by both methods, one at 0.0975). The bisection must bracket it to
// 1e-3 mu in 12 LPs, with no network at its lower end and one at its upper end by the other
// LP method too (the barrier with the row check).
TEST(FrictionThreshold, BracketsThePackingsOwnThreshold) {
  const Packing p = unjam::read_packing(fixture_dir("p500-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  std::vector<std::pair<double, double>> seen;
  unjam::FrictionThresholdOptions o;
  o.progress = [&](int total, const unjam::FrictionThreshold& so_far) {
    EXPECT_EQ(so_far.lps, static_cast<int>(seen.size()) + 1);
    EXPECT_EQ(total, 12);
    EXPECT_GT(so_far.iterations, 0);
    seen.emplace_back(so_far.mu_low, so_far.mu_high);
  };
  const unjam::FrictionThreshold t = unjam::friction_threshold(sys, o);
  EXPECT_EQ(t.mu, 0.1);
  EXPECT_GE(t.mu_low, 0.097);
  EXPECT_LE(t.mu_high, 0.0975);
  EXPECT_LE(t.mu_high - t.mu_low, 1e-4 + 1e-15);
  EXPECT_GT(t.mu_high - t.mu_low, 0.5e-4) << "no more LPs than needed";
  EXPECT_EQ(t.lps, 12);
  ASSERT_EQ(seen.size(), 12u);
  for (std::size_t i = 1; i < seen.size(); ++i) {  // nested brackets
    EXPECT_GE(seen[i].first, seen[i - 1].first);
    EXPECT_LE(seen[i].second, seen[i - 1].second);
  }
  EXPECT_EQ(seen.back(), std::make_pair(t.mu_low, t.mu_high));
  for (const double mu : {t.mu_low, t.mu_high}) {
    auto at = sys;
    at.mu = mu;
    EXPECT_EQ(unjam::has_admissible_network(at), mu == t.mu_high) << mu;
    bool built = true;
    try {
      unjam::ForceLP barrier(at, unjam::LpMethod::barrier);
    } catch (const unjam::Error&) {
      built = false;
    }
    EXPECT_EQ(built, mu == t.mu_high) << mu;
  }
}

// The admissibility test warm-started from the last LP's basis (the friction threshold's
// bisection) gives the verdict of the test from scratch at every mu, on both sides of p500-mu0.1's
// threshold (in (0.09707, 0.09717]) and near it; it uses the basis (an LP solved again from its own
// optimal basis takes no iteration, and the warm LPs take fewer iterations in all); a basis of
// another size (the frictionless LP has one cone column per contact) is ignored.
TEST(FrictionThreshold, WarmStartedAdmissibilityAgreesWithTheColdOne) {
  const Packing p = unjam::read_packing(fixture_dir("p500-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  unjam::SimplexBasis warm;
  long long warm_iterations = 0, cold_iterations = 0;
  auto at = sys;
  for (const double mu : {0.1, 0.05, 0.0970, 0.0973, 0.2}) {
    at.mu = mu;
    unjam::SimplexBasis cold;
    const bool found = unjam::has_admissible_network(at, 1e-9, warm);
    EXPECT_EQ(found, unjam::has_admissible_network(at, 1e-9, cold)) << mu;
    if (mu <= 0.097) EXPECT_FALSE(found) << mu;
    if (mu >= 0.0973) EXPECT_TRUE(found) << mu;
    EXPECT_EQ(warm.status.size(), static_cast<std::size_t>(2 * sys.num_contacts() + sys.rhs.size()));
    warm_iterations += warm.iterations;
    cold_iterations += cold.iterations;
  }
  EXPECT_LT(warm_iterations, cold_iterations);
  ASSERT_EQ(at.mu, 0.2);
  ASSERT_TRUE(unjam::has_admissible_network(at, 1e-9, warm));
  EXPECT_EQ(warm.iterations, 0) << "solved again from its own optimal basis";
  at.mu = 0.0;
  EXPECT_FALSE(unjam::has_admissible_network(at, 1e-9, warm));
  EXPECT_EQ(warm.status.size(), static_cast<std::size_t>(sys.num_contacts() + sys.rhs.size()));
}

// CLP's infeasibility ray below a packing's threshold is a certificate that the set is empty
// (proves_no_admissible_network), whatever its sign or scale; the same ray, or a broken one,
// never certifies a set that is not empty: just above p500-mu0.1's threshold (0.09707, 0.09717]
// and at the packing's own mu.
TEST(FrictionThreshold, AnEmptySetHasACertificateAndANonEmptyOneNone) {
  const Packing p = unjam::read_packing(fixture_dir("p500-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  const auto cone = [&](double mu) {
    auto at = sys;
    at.mu = mu;
    return unjam::cone_matrix(at);
  };
  const Eigen::SparseMatrix<double> below = cone(0.0970);
  ClpSimplex model;
  unjam::load_admissible_set(model, below, sys.rhs, 1e-9);
  model.dual();
  ASSERT_EQ(model.status(), 1);
  double* ray = model.infeasibilityRay();
  ASSERT_NE(ray, nullptr);
  const Eigen::VectorXd w = Eigen::Map<const Eigen::VectorXd>(ray, sys.rhs.size());
  delete[] ray;
  EXPECT_TRUE(unjam::proves_no_admissible_network(below, sys.rhs, w));
  EXPECT_TRUE(unjam::proves_no_admissible_network(below, sys.rhs, -3.0 * w));
  for (const double mu : {0.0973, 0.1})
    EXPECT_FALSE(unjam::proves_no_admissible_network(cone(mu), sys.rhs, w)) << mu;
  Eigen::VectorXd without_pressure = w;
  without_pressure[sys.pressure_row()] = 0.0;  // then w . rhs = 0: no certificate
  EXPECT_FALSE(unjam::proves_no_admissible_network(below, sys.rhs, without_pressure));
  Eigen::VectorXd one_grain_off = w;  // one balance row's multiplier changed
  one_grain_off[0] += 1e3 * (1.0 + std::abs(w[0]));
  EXPECT_FALSE(unjam::proves_no_admissible_network(below, sys.rhs, one_grain_off));
}

// Near the threshold of p1000-mu0.1 (in (0.093945, 0.094043]) CLP's dual simplex from scratch
// ends infeasible at mu = 0.09397 without leaving a ray, with scaling and without: no
// certificate. The verdict then comes from the elastic LP, whose duals prove the set empty; at
// 0.09399 the set has a point. Both verdicts agree with the bisection's bracket.
TEST(FrictionThreshold, AnEmptySetWithoutClpsRayIsProvedByTheElasticLp) {
  const Packing p = unjam::read_packing(fixture_dir("p1000-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  auto at = sys;
  at.mu = 0.09397;
  const Eigen::SparseMatrix<double> Ay = unjam::cone_matrix(at);
  ClpSimplex model;
  unjam::load_admissible_set(model, Ay, sys.rhs, 1e-9);
  model.dual();
  EXPECT_EQ(model.status(), 1);
  double* ray = model.infeasibilityRay();
  EXPECT_EQ(ray, nullptr) << "CLP left a ray: this test no longer reaches the elastic LP";
  delete[] ray;
  EXPECT_FALSE(unjam::has_admissible_network(at));
  at.mu = 0.09399;
  EXPECT_TRUE(unjam::has_admissible_network(at));
}

// On p50-mu0.1 (threshold 0.048): from a bracket given, the bisection ends on the bracket it
// reaches from [0, mu] (there it passes (0.025, 0.05] after 4 LPs, so 2 fewer); a bracket
// whose ends are not as stated is refused; a run stopped on request throws Cancelled.
TEST(FrictionThreshold, FromABracketToTheSameEnd) {
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  const unjam::FrictionThreshold t = unjam::friction_threshold(sys);
  EXPECT_EQ(t.lps, 12);
  unjam::FrictionThresholdOptions from;
  from.mu_low = 0.025;
  from.mu_high = 0.05;
  const unjam::FrictionThreshold u = unjam::friction_threshold(sys, from);
  EXPECT_EQ(u.mu_low, t.mu_low);
  EXPECT_EQ(u.mu_high, t.mu_high);
  EXPECT_EQ(u.lps, 10);
  const auto refused = [&](double lo, double hi, const char* phrase) {
    unjam::FrictionThresholdOptions b;
    b.mu_low = lo;
    b.mu_high = hi;
    try {
      unjam::friction_threshold(sys, b);
      ADD_FAILURE() << lo << ", " << hi << ": expected an error";
    } catch (const unjam::Error& e) {
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
    }
  };
  refused(0.049, 0.1, "not empty at mu_low");
  refused(0.01, 0.047, "empty at mu_high");
  refused(0.1, 0.05, "0 <= mu_low < mu_high");
  // Stopped on request before its fourth LP.
  unjam::FrictionThresholdOptions stop;
  int polls = 0;
  stop.should_stop = [&polls] { return ++polls > 3; };
  EXPECT_THROW(unjam::friction_threshold(sys, stop), unjam::Cancelled);
  EXPECT_EQ(polls, 4);
}

// A bracket whose ends an earlier run checked (a checkpoint's) is not solved again: from the
// bracket after the 5th LP of a run, 7 more LPs end on that run's bracket, to the bit. Without a
// bracket the option is an error.
TEST(FrictionThreshold, ACheckedBracketIsNotSolvedAgain) {
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  unjam::FrictionThresholdOptions whole;
  std::vector<std::pair<double, double>> seen;
  whole.progress = [&](int, const unjam::FrictionThreshold& r) { seen.emplace_back(r.mu_low, r.mu_high); };
  const unjam::FrictionThreshold t = unjam::friction_threshold(sys, whole);
  ASSERT_EQ(seen.size(), 12u);
  unjam::FrictionThresholdOptions from;
  std::tie(from.mu_low, from.mu_high) = seen[4];
  from.bracket_checked = true;
  int calls = 0;
  from.progress = [&](int total, const unjam::FrictionThreshold& r) {
    EXPECT_EQ(total, 7);
    EXPECT_EQ(std::make_pair(r.mu_low, r.mu_high), seen[5 + calls]) << calls;
    ++calls;
  };
  const unjam::FrictionThreshold u = unjam::friction_threshold(sys, from);
  EXPECT_EQ(u.lps, 7);
  EXPECT_EQ(calls, 7);
  EXPECT_EQ(u.mu_low, t.mu_low);
  EXPECT_EQ(u.mu_high, t.mu_high);
  unjam::FrictionThresholdOptions bad;
  bad.bracket_checked = true;
  EXPECT_THROW(unjam::friction_threshold(sys, bad), unjam::Error);
}

// lattice16 (a triangular lattice: every contact's force along its normal) needs no friction:
// mu_s = 0 after two LPs; read without friction, after one. A packing read far below its
// threshold has no network at its own mu: an error, as for `unjam bounds`.
TEST(FrictionThreshold, ZeroWhereNoFrictionIsNeededAndAnErrorWithoutANetwork) {
  Packing p = unjam::read_packing(fixture_dir("lattice16"));
  auto sys = unjam::build_equilibrium_system(p, unjam::select_contacts(p));
  unjam::FrictionThreshold t = unjam::friction_threshold(sys);
  EXPECT_EQ(t.mu_low, 0.0);
  EXPECT_EQ(t.mu_high, 0.0);
  EXPECT_EQ(t.lps, 2);
  sys.mu = 0.0;
  t = unjam::friction_threshold(sys);
  EXPECT_EQ(t.mu_high, 0.0);
  EXPECT_EQ(t.lps, 1);
  unjam::FrictionThresholdOptions bad;
  bad.rel_tol = 0.0;
  EXPECT_THROW(unjam::friction_threshold(sys, bad), unjam::Error);
  Packing q = unjam::read_packing(fixture_dir("p50-mu0.1"));
  q.meta.contact.mu = 0.04;  // its threshold is 0.048 (docs/ensemble.md, "The friction threshold")
  try {
    unjam::friction_threshold(unjam::build_equilibrium_system(q, unjam::select_contacts(q)));
    ADD_FAILURE() << "expected no admissible network at mu = 0.04";
  } catch (const unjam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("no admissible force network at the packing's own mu"), std::string::npos)
        << e.what();
  }
}

// Opening the checkpoint `file` of type Checkpoint for a run of `settings` is refused with an
// unjam::Error naming the file and saying `why`, and the file is left as it was.
template <typename Checkpoint>
void expect_checkpoint_refused(const fs::path& file, const nlohmann::json& settings, const std::string& why) {
  const std::string before = unjam::read_file(file);
  try {
    Checkpoint c(file, settings);
    ADD_FAILURE() << "accepted; expected: " << why;
  } catch (const unjam::Error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
  EXPECT_EQ(unjam::read_file(file), before);
}

// A run stopped every 40 LPs (alternately on 1 and 2 threads) and resumed from its checkpoint
// until it is complete gives the bits of one uninterrupted run, solves no LP twice and records
// the time of every run.
TEST(BoundsCheckpoint, StoppedRunsResumeToTheBitsOfOneRun) {
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const auto sys = unjam::build_equilibrium_system(p);
  unjam::ForceBoundsOptions one;
  int lps_of_one = 0;
  one.checkpoint = [&](const unjam::ForceBounds&) { ++lps_of_one; };
  const unjam::ForceBounds whole = unjam::compute_force_bounds(sys, one);
  const fs::path file = fs::temp_directory_path() / "unjam_test_bounds_checkpoint.json";
  fs::remove(file);
  const auto settings =
      unjam::bounds_checkpoint_settings("p50", p, 1e-9, 1e-9, unjam::ForceBoundsOptions{}, "", sys.num_contacts());
  unjam::ForceBounds b;
  int runs = 0, lps = 0;
  do {
    const unjam::BoundsCheckpoint c(file, settings);
    ASSERT_EQ(c.resumed() != nullptr, runs > 0);
    EXPECT_EQ(c.earlier().runs, runs);
    EXPECT_EQ(c.earlier().wall_seconds, 1.5 * runs);
    if (c.resumed()) EXPECT_GE(unjam::known_values(*c.resumed()), lps);  // every LP solved gave a value
    unjam::ForceBoundsOptions lp;
    lp.threads = 1 + runs % 2;
    c.attach(lp, 1e9, 40, nullptr, [&c] { return c.earlier() + unjam::CampaignTime{1, 1.5, 2.5, 0}; });
    const auto count = lp.checkpoint;
    lp.checkpoint = [&](const unjam::ForceBounds& x) { ++lps; count(x); };
    b = unjam::compute_force_bounds(sys, lp);
    if (b.complete) c.remove();
    else c.save(b, c.earlier() + unjam::CampaignTime{1, 1.5, 2.5, 0});
    ++runs;
  } while (!b.complete && runs < 20);
  EXPECT_GE(runs, 3);
  EXPECT_TRUE(b.complete);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_EQ(lps, lps_of_one);  // no LP solved twice
  for (int k = 0; k < sys.num_contacts(); ++k) {
    EXPECT_EQ(b.fn_min[k], whole.fn_min[k]) << k;
    EXPECT_EQ(b.fn_max[k], whole.fn_max[k]) << k;
  }
  EXPECT_EQ(b.min_lps_skipped, whole.min_lps_skipped);
  EXPECT_EQ(b.iterations, whole.iterations);
  EXPECT_EQ(b.simplex_finishes, whole.simplex_finishes);
  EXPECT_EQ(b.unscaled_solves, whole.unscaled_solves);
}

// A checkpoint of another run, or one that is not a checkpoint, is refused with its name and
// the reason, and left as it is.
TEST(BoundsCheckpoint, OtherRunsAndDamagedFilesAreRefusedAndKept) {
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const Packing other = unjam::read_packing(fixture_dir("p50-mu1"));
  const auto sys = unjam::build_equilibrium_system(p);
  const int Nc = sys.num_contacts();
  const fs::path file = fs::temp_directory_path() / "unjam_test_bounds_checkpoint_refused.json";
  const unjam::ForceBoundsOptions barrier;
  unjam::ForceBoundsOptions simplex, looser, wider_open;
  simplex.method = unjam::LpMethod::simplex;
  looser.tolerance = 1e-8;
  wider_open.open_tol_F0 = 1e-6;
  const auto settings = unjam::bounds_checkpoint_settings("p50", p, 1e-9, 1e-9, barrier, "", Nc);
  // The defaults' settings are those saved before the tolerances could be set (no such keys),
  // so that such a checkpoint is resumed by the default run; the threads are not part of them.
  EXPECT_FALSE(settings.contains("lp_tolerance"));
  EXPECT_FALSE(settings.contains("open_tol_F0"));
  unjam::ForceBoundsOptions two_threads;
  two_threads.threads = 2;
  EXPECT_EQ(unjam::bounds_checkpoint_settings("p50", p, 1e-9, 1e-9, two_threads, "", Nc), settings);
  unjam::ForceBounds partial;
  partial.fn_min = partial.fn_max = Eigen::VectorXd::Constant(Nc, std::nan(""));
  partial.fn_max[3] = 2.5;
  partial.iterations = 17;
  const auto refused = [&](const nlohmann::json& now, const std::string& why) {
    expect_checkpoint_refused<unjam::BoundsCheckpoint>(file, now, why);
  };
  unjam::BoundsCheckpoint(file, settings).save(partial, {});
  {
    const unjam::BoundsCheckpoint c(file, settings);  // its own run reads it back
    ASSERT_NE(c.resumed(), nullptr);
    EXPECT_EQ(c.resumed()->fn_max[3], 2.5);
    EXPECT_TRUE(std::isnan(c.resumed()->fn_max[4]));
    EXPECT_EQ(c.resumed()->iterations, 17);
    EXPECT_EQ(unjam::known_values(*c.resumed()), 1);
  }
  refused(unjam::bounds_checkpoint_settings("p50", p, 1e-9, 1e-8, barrier, "", Nc), "fn_tol");
  refused(unjam::bounds_checkpoint_settings("p50", p, 1e-9, 1e-9, simplex, "", Nc), "method");
  refused(unjam::bounds_checkpoint_settings("p50", p, 1e-9, 1e-9, looser, "", Nc), "lp_tolerance: none there, 1e-08 here");
  refused(unjam::bounds_checkpoint_settings("p50", p, 1e-9, 1e-9, wider_open, "", Nc), "open_tol_F0: none there, 1e-06 here");
  refused(unjam::bounds_checkpoint_settings("p50", other, 1e-9, 1e-9, barrier, "", Nc), "packing_fingerprint");
  const auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
    auto j = nlohmann::json::parse(unjam::read_file(file));
    edit(j);
    unjam::write_file_atomic(file, j.dump());
  };
  edited([](nlohmann::json& j) { j["fn_max"].erase(0); });
  refused(settings, "damaged (80 values for 81 contacts)");
  fs::remove(file);
  unjam::BoundsCheckpoint(file, settings).save(partial, {});
  edited([](nlohmann::json& j) { j["fn_min"][2] = "x"; });
  refused(settings, "damaged");
  fs::remove(file);
  unjam::BoundsCheckpoint(file, settings).save(partial, {});
  edited([](nlohmann::json& j) { j.erase("iterations"); });
  refused(settings, "damaged");
  // Counts out of their type's range or negative, and a negative minimum: refused, not cast.
  for (const auto& [key, value, why] :
       {std::tuple{"iterations", nlohmann::json(1e300), "iterations must be an integer"},
        std::tuple{"min_lps_skipped", nlohmann::json(2.5), "min_lps_skipped must be an integer"},
        std::tuple{"unscaled_solves", nlohmann::json(-1), "unscaled_solves is negative"},
        std::tuple{"min_lps_skipped", nlohmann::json(Nc + 1), "min_lps_skipped is more than its 81 contacts"}}) {
    fs::remove(file);
    unjam::BoundsCheckpoint(file, settings).save(partial, {});
    edited([&](nlohmann::json& j) { j[key] = value; });
    refused(settings, why);
  }
  fs::remove(file);
  unjam::BoundsCheckpoint(file, settings).save(partial, {});
  edited([](nlohmann::json& j) { j["fn_min"][2] = -0.5; });
  refused(settings, "a negative fn_min");
  unjam::write_file_atomic(file, "{\"settings\": ");
  refused(settings, "not a bounds checkpoint");
  fs::remove(file);
  // A place it cannot write is refused when the checkpoint is made, before any LP: under a
  // regular file, and a directory in the file's place.
  const fs::path blocker = fs::temp_directory_path() / "unjam_test_bounds_checkpoint_blocker";
  fs::remove_all(blocker);
  unjam::write_file_atomic(blocker, "a file");
  for (const auto& [place, why] : {std::pair{blocker / "cp.json", std::string("cannot create directory")},
                                   std::pair{fs::temp_directory_path(), std::string("is a directory")}}) {
    try {
      unjam::BoundsCheckpoint c(place, settings);
      ADD_FAILURE() << place << " accepted";
    } catch (const unjam::Error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(unjam::read_file(blocker), "a file");
  fs::remove(blocker);
}

// The threshold's checkpoint reads back what it saved; a bracket that is not
// 0 <= mu_low < mu_high <= mu, counts out of their type's range or negative, and a file that is
// not a checkpoint are refused with the file's name, and the file kept.
TEST(ThresholdCheckpoint, ReadsBackWhatItSavedAndRefusesDamagedFiles) {
  const Packing p = unjam::read_packing(fixture_dir("p50-mu0.1"));
  const fs::path file = fs::temp_directory_path() / "unjam_test_threshold_checkpoint.json";
  fs::remove(file);
  const auto settings = unjam::threshold_checkpoint_settings(p, 1e-9, 1e-9, 81, 0.1, 1e-3);
  unjam::ThresholdProgress saved;
  saved.so_far.mu_low = 0.05;
  saved.so_far.mu_high = 0.075;
  saved.so_far.lps = 4;
  saved.so_far.iterations = 321;
  saved.so_far.seconds = 0.25;
  saved.runs = 2;
  {
    const unjam::ThresholdCheckpoint c(file, settings);
    EXPECT_FALSE(c.resumed().has_value());
    c.save(saved);
  }
  {
    const unjam::ThresholdCheckpoint c(file, settings);
    ASSERT_TRUE(c.resumed().has_value());
    const unjam::FrictionThreshold& t = c.resumed()->so_far;
    EXPECT_EQ(t.mu, 0.1);  // the run's own mu, from its settings
    EXPECT_EQ(t.mu_low, 0.05);
    EXPECT_EQ(t.mu_high, 0.075);
    EXPECT_EQ(t.lps, 4);
    EXPECT_EQ(t.iterations, 321);
    EXPECT_EQ(t.seconds, 0.25);
    EXPECT_EQ(c.resumed()->runs, 2);
    // Attached to a run: it starts from the bracket read, unless the run has its own.
    unjam::FrictionThresholdOptions own;
    own.mu_low = 0.01;
    EXPECT_THROW(c.attach(own), unjam::Error);
    unjam::FrictionThresholdOptions o;
    int called = 0;
    o.progress = [&called](int, const unjam::FrictionThreshold&) { ++called; };
    c.attach(o);
    EXPECT_EQ(o.mu_low, 0.05);
    EXPECT_EQ(o.mu_high, 0.075);
    EXPECT_TRUE(o.bracket_checked);
    // Its hook saves the run's bracket with every run's counts, then calls the run's own hook.
    unjam::FrictionThreshold now;
    now.mu = 0.1;
    now.mu_low = 0.0625;
    now.mu_high = 0.075;
    now.lps = 1;
    now.iterations = 9;
    now.seconds = 0.5;
    o.progress(7, now);
    EXPECT_EQ(called, 1);
    const unjam::FrictionThreshold all = c.with_earlier(now);
    EXPECT_EQ(all.lps, 5);
    EXPECT_EQ(all.iterations, 330);
    EXPECT_EQ(all.seconds, 0.75);
    const unjam::ThresholdCheckpoint again(file, settings);
    ASSERT_TRUE(again.resumed().has_value());
    EXPECT_EQ(again.resumed()->so_far.mu_low, 0.0625);
    EXPECT_EQ(again.resumed()->so_far.lps, 5);
    EXPECT_EQ(again.resumed()->runs, 3);
  }
  const auto refused_after = [&](const std::function<void(nlohmann::json&)>& edit, const std::string& why) {
    fs::remove(file);
    unjam::ThresholdCheckpoint(file, settings).save(saved);
    auto j = nlohmann::json::parse(unjam::read_file(file));
    edit(j);
    unjam::write_file_atomic(file, j.dump());
    expect_checkpoint_refused<unjam::ThresholdCheckpoint>(file, settings, why);
  };
  refused_after([](nlohmann::json& j) { j["mu_high"] = 0.2; }, "its bracket is not");
  refused_after([](nlohmann::json& j) { j["mu_low"] = 0.075; }, "its bracket is not");
  refused_after([](nlohmann::json& j) { j["mu_low"] = -0.01; }, "its bracket is not");
  refused_after([](nlohmann::json& j) { j["lps"] = 1e300; }, "lps must be an integer");
  refused_after([](nlohmann::json& j) { j["runs"] = 1.5; }, "runs must be an integer");
  refused_after([](nlohmann::json& j) { j["simplex_iterations"] = -3; }, "its counts are not");
  refused_after([](nlohmann::json& j) { j["lp_seconds"] = -1.0; }, "its counts are not");
  refused_after([](nlohmann::json& j) { j["runs"] = 0; }, "its counts are not");
  refused_after([](nlohmann::json& j) { j.erase("lp_seconds"); }, "damaged");
  refused_after([](nlohmann::json& j) { j["settings"]["rel_tol"] = 2e-3; }, "rel_tol: 0.002 there, 0.001 here");
  refused_after([](nlohmann::json& j) { j = nlohmann::json::array(); }, "not a threshold checkpoint");
  fs::remove(file);
}

TEST(ForceBounds, CommandWritesCsvAndJson) {
  const fs::path dir = fs::temp_directory_path() / "unjam_test_bounds_cmd";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const char* f : {"meta.json", "particles.csv", "contacts.csv"})
    fs::copy_file(fs::path(fixture_dir("p50-mu0.1")) / f, dir / f);
  const std::string cmd = std::string(UNJAM_BINARY) + " bounds " + dir.string() + " > " +
                          (dir / "stdout.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream csv(dir / "bounds.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("a,b,fn,fn_min,fn_max", 0), 0u);
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 81);
  ASSERT_TRUE(fs::exists(dir / "bounds.json"));
  // How each LP was solved: on p50 every barrier point passes the row check.
  const auto j = nlohmann::json::parse(unjam::read_file(dir / "bounds.json"));
  EXPECT_EQ(j.at("lps_at_looser_tolerance").get<long long>(), 0);
  EXPECT_EQ(j.at("lps_finished_by_simplex").get<long long>(), 0);
  EXPECT_EQ(j.at("lps_solved_unscaled").get<long long>(), 0);
  fs::remove_all(dir);
}

}  // namespace
