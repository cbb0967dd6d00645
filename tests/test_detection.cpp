// Pair search, contact detection with warm-start carry-over, and the edge colouring of the
// contact graph, against brute-force references.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "physics_test_util.hpp"
#include "unjam/contact/detection.hpp"
#include "unjam/contact/neighbor_grid.hpp"
#include "unjam/core/error.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/solver/coloring.hpp"

namespace unjam {
namespace {

using testing::brute_force_pairs;

// n disks with radii in [0.5, 1] at uniform random positions (overlaps allowed) in an
// Lx x Ly cell; a fraction of them pushed to within 1e-3 of the cell edges and corners.
Particles random_disks(int n, const Cell& cell, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Particles P;
  P.resize(n);
  for (int i = 0; i < n; ++i) {
    P.radius[i] = 0.5 + 0.5 * u(rng);
    P.x[i] = u(rng) * cell.Lx;
    P.y[i] = u(rng) * cell.Ly;
    if (i % 7 == 0) P.x[i] = (u(rng) < 0.5 ? 1e-3 * u(rng) : cell.Lx * (1.0 - 1e-12) - 1e-3 * u(rng));
    if (i % 11 == 0) P.y[i] = (u(rng) < 0.5 ? 0.0 : cell.Ly * (1.0 - 1e-12) - 1e-3 * u(rng));
  }
  return P;
}

TEST(Detection, NearPairsEqualBruteForce) {
  struct Case {
    double Lx, Ly;
    int n;
    double max_gap;
  };
  // Large cells (grid), small cells (< 3 grid cells a side: all pairs), mixed (one side
  // small), cells about one or two diameters wide (several images in reach), a zero and a
  // negative detection distance.
  const Case cases[] = {{30.0, 30.0, 300, 0.01}, {30.0, 30.0, 300, 0.5}, {25.0, 17.0, 150, 0.2},
                        {40.0, 5.0, 60, 0.1},    {5.0, 40.0, 60, 0.1},   {5.5, 5.5, 12, 0.3},
                        {2.5, 2.5, 3, 0.05},     {6.0, 6.1, 20, 0.0},    {12.0, 12.0, 80, -0.2},
                        {6.3, 6.3, 25, 0.1}};
  for (const Case& cs : cases) {
    const Cell cell{cs.Lx, cs.Ly};
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
      const Particles P = random_disks(cs.n, cell, seed * 31 + cs.n);
      const auto got = find_near_pairs(P, cell, cs.max_gap);
      const auto want = brute_force_pairs(P, cell, cs.max_gap);
      EXPECT_EQ(got, want) << "cell " << cs.Lx << "x" << cs.Ly << " n " << cs.n << " max_gap "
                           << cs.max_gap << " seed " << seed << ": got " << got.size()
                           << " pairs, brute force " << want.size();
      for (const auto& [a, b] : got) EXPECT_LT(a, b);
      EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
    }
  }
}

TEST(Detection, NearPairsAcrossTheBoundaryAndInAGas) {
  // Two disks straddling the corner: found with the minimum image only.
  Particles P;
  P.resize(3);
  P.radius = {1.0, 1.0, 0.5};
  P.x = {0.2, 29.9, 15.0};
  P.y = {0.3, 29.8, 15.0};
  const Cell cell{30.0, 30.0};
  const auto pairs = find_near_pairs(P, cell, 0.01);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0], std::make_pair(0, 1));
  // A gas after make_gas: no pair overlaps, and the pair search agrees with brute force.
  GasSettings gs;
  gs.N = 400;
  gs.phi = 0.45;
  gs.seed = 3;
  const Packing gas = make_gas(gs);
  EXPECT_TRUE(find_near_pairs(gas.particles, gas.cell, 0.0).empty());
  EXPECT_EQ(find_near_pairs(gas.particles, gas.cell, 0.3), brute_force_pairs(gas.particles, gas.cell, 0.3));
}

TEST(Detection, ContactsCarryForcesOverForSurvivingPairsOnly) {
  const Cell cell{20.0, 20.0};
  Particles P = random_disks(120, cell, 99);
  const double max_gap = 0.2;
  Contacts first = detect_contacts(P, cell, max_gap, {});
  ASSERT_GT(first.size(), 20u);
  for (const Contact& c : first) {
    EXPECT_EQ(c.fn, 0.0);
    EXPECT_EQ(c.ft, 0.0);
  }
  // Give every contact a distinct force.
  for (std::size_t k = 0; k < first.size(); ++k) {
    first[k].fn = 1.0 + static_cast<double>(k);
    first[k].ft = -0.5 - static_cast<double>(k);
  }
  // Move a third of the grains: some pairs vanish, some new ones appear.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t i = 0; i < P.size(); i += 3) {
    const Vec2 r = cell.wrap({P.x[i] + 0.8 * u(rng), P.y[i] + 0.8 * u(rng)});
    P.x[i] = r.x();
    P.y[i] = r.y();
  }
  const Contacts second = detect_contacts(P, cell, max_gap, first);
  const auto want = brute_force_pairs(P, cell, max_gap);
  ASSERT_EQ(second.size(), want.size());
  int survived = 0, fresh = 0;
  for (std::size_t k = 0; k < second.size(); ++k) {
    const Contact& c = second[k];
    EXPECT_EQ(std::make_pair(c.a, c.b), want[k]);
    // Geometry at the new positions.
    const Vec2 l = cell.min_image(P.position(c.b) - P.position(c.a));
    EXPECT_NEAR((c.l - l).norm(), 0.0, 1e-12);
    EXPECT_NEAR((c.n - l / l.norm()).norm(), 0.0, 1e-14);
    EXPECT_NEAR(c.gap, l.norm() - P.radius[c.a] - P.radius[c.b], 1e-12);
    const auto old = std::find_if(first.begin(), first.end(),
                                  [&](const Contact& o) { return o.a == c.a && o.b == c.b; });
    if (old != first.end()) {
      ++survived;
      EXPECT_EQ(c.fn, old->fn);
      EXPECT_EQ(c.ft, old->ft);
    } else {
      ++fresh;
      EXPECT_EQ(c.fn, 0.0);
      EXPECT_EQ(c.ft, 0.0);
    }
  }
  EXPECT_GT(survived, 5);
  EXPECT_GT(fresh, 5);
}

TEST(Detection, UpdateGeometryKeepsTheListAndForces) {
  const Cell cell{15.0, 15.0};
  Particles P = random_disks(60, cell, 4);
  Contacts cs = detect_contacts(P, cell, 0.3, {});
  ASSERT_FALSE(cs.empty());
  for (Contact& c : cs) c.fn = 2.0;
  for (std::size_t i = 0; i < P.size(); ++i) P.x[i] = cell.wrap({P.x[i] + 0.01 * i, P.y[i]}).x();
  const Contacts before = cs;
  update_contact_geometry(P, cell, cs);
  ASSERT_EQ(cs.size(), before.size());
  for (std::size_t k = 0; k < cs.size(); ++k) {
    EXPECT_EQ(cs[k].a, before[k].a);
    EXPECT_EQ(cs[k].fn, 2.0);
    const Vec2 l = cell.min_image(P.position(cs[k].b) - P.position(cs[k].a));
    EXPECT_EQ(cs[k].l, l);
  }
}

// ---- colouring ----

Contacts dense_contact_graph(int n, std::uint64_t seed) {
  GasSettings gs;
  gs.N = n;
  gs.phi = 0.45;
  gs.seed = seed;
  const Packing gas = make_gas(gs);
  return detect_contacts(gas.particles, gas.cell, 0.6, {});  // ~5 neighbours per grain
}

void expect_valid_coloring(const Contacts& cs, int n, const Coloring& col) {
  const int nc = static_cast<int>(cs.size());
  ASSERT_EQ(static_cast<int>(col.order.size()), nc);
  ASSERT_GE(col.num_colors(), 1);
  EXPECT_EQ(col.color_start.front(), 0);
  EXPECT_EQ(col.color_start.back(), nc);
  // Every contact coloured exactly once.
  std::vector<int> seen(nc, 0);
  for (const int k : col.order) {
    ASSERT_GE(k, 0);
    ASSERT_LT(k, nc);
    ++seen[k];
  }
  for (int k = 0; k < nc; ++k) EXPECT_EQ(seen[k], 1) << "contact " << k;
  // Contacts of one colour share no grain.
  std::vector<int> max_deg(n, 0);
  for (const Contact& c : cs) ++max_deg[c.a], ++max_deg[c.b];
  const int delta = *std::max_element(max_deg.begin(), max_deg.end());
  for (int c = 0; c < col.num_colors(); ++c) {
    EXPECT_LT(col.color_start[c], col.color_start[c + 1]) << "empty colour " << c;
    std::set<int> grains;
    for (int q = col.color_start[c]; q < col.color_start[c + 1]; ++q) {
      const Contact& k = cs[col.order[q]];
      EXPECT_TRUE(grains.insert(k.a).second) << "grain " << k.a << " twice in colour " << c;
      EXPECT_TRUE(grains.insert(k.b).second) << "grain " << k.b << " twice in colour " << c;
    }
  }
  // A greedy edge colouring never needs more than 2 Delta - 1 colours.
  EXPECT_LE(col.num_colors(), 2 * delta - 1);
}

TEST(Coloring, ColoursShareNoGrainAndCoverEveryContactOnce) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const int n = 300;
    const Contacts cs = dense_contact_graph(n, seed);
    ASSERT_GT(cs.size(), 300u);
    for (std::uint64_t cseed : {0ull, 1ull, 12345ull}) expect_valid_coloring(cs, n, color_contacts(cs, n, cseed));
  }
  // Degenerate inputs: no contacts, one contact, a star (all contacts on one grain).
  EXPECT_EQ(color_contacts({}, 5, 1).order.size(), 0u);
  Contacts star;
  for (int b = 1; b < 40; ++b) star.push_back(Contact{0, b});
  const Coloring col = color_contacts(star, 40, 3);
  expect_valid_coloring(star, 40, col);
  EXPECT_EQ(col.num_colors(), 39);
}

TEST(Coloring, DeterministicForASeed) {
  const int n = 300;
  const Contacts cs = dense_contact_graph(n, 2);
  const Coloring a = color_contacts(cs, n, 77), b = color_contacts(cs, n, 77);
  EXPECT_EQ(a.order, b.order);
  EXPECT_EQ(a.color_start, b.color_start);
  // A different seed visits the contacts in another order (and the result may differ),
  // and is valid too.
  const Coloring c = color_contacts(cs, n, 78);
  expect_valid_coloring(cs, n, c);
  EXPECT_TRUE(c.order != a.order || c.color_start != a.color_start);
}

TEST(Coloring, MoreThan64NeighboursIsAnError) {
  Contacts star;
  for (int b = 1; b <= 65; ++b) star.push_back(Contact{0, b});
  EXPECT_THROW(color_contacts(star, 66, 1), Error);
}

}  // namespace
}  // namespace unjam
