// The paper's random walk over the admissible force networks (random_walk.hpp): admissibility
// of every sample, sampled ranges inside the exact LP intervals, seeding, the contact model's
// bath in the relaxation, the unique network of an isostatic mu = 0 packing; and
// scripts/plot_fig4.py on a small ensemble.csv.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "physics_test_util.hpp"
#include "unjam/ensemble/random_walk.hpp"
#include "unjam/packing/packing_io.hpp"
#include "fixture_p50.hpp"

namespace {

using unjam::Packing;

using unjam::testing::p50;

TEST(RandomWalk, EverySampleIsAdmissible) {
  const auto& d = p50();
  const double F0 = d.packing.force_unit(), tol = 1e-9 * F0;
  unjam::testing::WorstViolation worst{d.sys};
  unjam::RandomWalkOptions options;
  options.samples = 300;
  options.on_sample = [&](const unjam::ForceNetwork& net) { worst.add(net); };
  const auto result = unjam::sample_random_walk(d.packing, d.sys, options);
  std::printf("[ walk ] p50: %d samples, %d failures, %lld sweeps, eta %.4g; worst balance "
              "%.3g F0, pressure %.3g, fn %.3g F0, Coulomb %.3g F0\n",
              result.samples, result.failures, result.sweeps, result.eta, worst.balance / F0,
              worst.pressure, worst.fn / F0, worst.coulomb / F0);
  EXPECT_EQ(result.samples + result.failures, 300);
  EXPECT_GE(result.samples, 295);
  EXPECT_LT(worst.balance, tol);
  EXPECT_LT(worst.pressure, 1e-9);
  EXPECT_GE(worst.fn, -tol);
  EXPECT_LE(worst.coulomb, tol);
  EXPECT_GT(result.eta, 0.0);
  double mean_fn = 0.0;  // kick amplitude: <F_n> of the packing's network over the set
  for (const int c : d.sys.contacts) mean_fn += d.packing.contacts[c].fn;
  EXPECT_DOUBLE_EQ(result.kick_amplitude, mean_fn / d.sys.num_contacts());
}

TEST(RandomWalk, SampledRangesLieInsideLpIntervals) {
  const auto& d = p50();
  const double tol = 1e-8 * d.packing.force_unit();
  unjam::RandomWalkOptions options;
  options.samples = 1000;
  const auto r = unjam::sample_random_walk(d.packing, d.sys, options);
  ASSERT_GT(r.samples, 0);
  double coverage = 0.0;
  for (int k = 0; k < d.sys.num_contacts(); ++k) {
    EXPECT_GE(r.sample_min[k], d.bounds.fn_min[k] - tol) << "contact " << k;
    EXPECT_LE(r.sample_max[k], d.bounds.fn_max[k] + tol) << "contact " << k;
    EXPECT_LE(r.sample_min[k], r.mean[k]);
    EXPECT_LE(r.mean[k], r.sample_max[k]);
    coverage += (r.sample_max[k] - r.sample_min[k]) / (d.bounds.fn_max[k] - d.bounds.fn_min[k]);
  }
  coverage /= d.sys.num_contacts();
  std::printf("[ walk ] p50, 1000 samples: mean sampled / LP width %.3f, eta %.4g\n", coverage,
              r.eta);
  EXPECT_GT(coverage, 0.1);  // the walk moves: it is not stuck at the original network
}

// Two walks gave the same samples, bit for bit.
void expect_same_walk(const unjam::RandomWalkResult& a, const unjam::RandomWalkResult& b) {
  EXPECT_EQ(a.sample_min, b.sample_min);
  EXPECT_EQ(a.sample_max, b.sample_max);
  EXPECT_EQ(a.mean, b.mean);
  EXPECT_EQ(a.std, b.std);
  EXPECT_EQ(a.eta, b.eta);
  EXPECT_EQ(a.sweeps, b.sweeps);
}

TEST(RandomWalk, SameSeedSameSamples) {
  const auto& d = p50();
  unjam::RandomWalkOptions options;
  options.samples = 50;
  options.seed = 7;
  const auto a = unjam::sample_random_walk(d.packing, d.sys, options);
  const auto b = unjam::sample_random_walk(d.packing, d.sys, options);
  expect_same_walk(a, b);
  options.seed = 8;
  const auto c = unjam::sample_random_walk(d.packing, d.sys, options);
  EXPECT_NE(a.mean, c.mean);
}

TEST(RandomWalk, RelaxesUnderTheContactModelsBath) {
  // The relaxation's bath is the contact model's (bath_of: P_ext and M_lambda): the packing's
  // own by default, or the one the options name. The solver's path, and so the polished
  // samples' bytes, depend on M_lambda; the network's admissibility does not.
  const auto& d = p50();
  unjam::RandomWalkOptions options;
  options.samples = 20;
  options.seed = 3;
  const auto own = unjam::sample_random_walk(d.packing, d.sys, options);
  options.model = d.packing.meta.contact;
  const auto named = unjam::sample_random_walk(d.packing, d.sys, options);
  expect_same_walk(own, named);

  unjam::ContactModel heavy = d.packing.meta.contact;
  heavy.M_lambda *= 10.0;
  options.model = heavy;
  const auto heavy_named = unjam::sample_random_walk(d.packing, d.sys, options);
  Packing heavy_packing = d.packing;
  heavy_packing.meta.contact = heavy;
  options.model.reset();
  const auto heavy_own = unjam::sample_random_walk(heavy_packing, d.sys, options);
  std::printf("[ walk ] p50, 20 steps: %lld sweeps at M_lambda %g, %lld at %g\n", own.sweeps,
              d.packing.meta.contact.M_lambda, heavy_own.sweeps, heavy.M_lambda);
  expect_same_walk(heavy_named, heavy_own);
  EXPECT_NE(heavy_own.mean, own.mean);  // another bath mass: another path of the solver
}

TEST(RandomWalk, IsostaticFrictionlessPackingHasOneNetwork) {
  // mu = 0, isostatic: force-carrying contacts = 2 N' - 1, so the admissible set is the single
  // network of the packing and every sample must equal it.
  const unjam::testing::Compacted& c = unjam::testing::compacted(60, 0.0, 1);
  ASSERT_TRUE(c.result.is_static);
  const Packing& p = c.packing;
  const double F0 = p.force_unit();
  std::vector<bool> loaded(p.size(), false);
  int carrying = 0;
  for (const unjam::Contact& k : p.contacts)
    if (k.fn > 1e-9 * F0) {
      ++carrying;
      loaded[k.a] = loaded[k.b] = true;
    }
  const int non_rattlers = static_cast<int>(std::count(loaded.begin(), loaded.end(), true));
  ASSERT_EQ(carrying, 2 * non_rattlers - 1) << "not isostatic: the test needs another seed";

  const unjam::EquilibriumSystem sys = unjam::build_equilibrium_system(p);
  unjam::RandomWalkOptions options;
  options.samples = 100;
  double worst = 0.0;
  options.on_sample = [&](const unjam::ForceNetwork& net) {
    for (int k = 0; k < sys.num_contacts(); ++k) {
      worst = std::max(worst, std::abs(net.fn[k] - p.contacts[sys.contacts[k]].fn) / F0);
      EXPECT_EQ(net.ft[k], 0.0);
    }
  };
  const auto r = unjam::sample_random_walk(p, sys, options);
  std::printf("[ walk ] mu 0 N 60: %d contacts, %d samples, largest deviation %.3g F0\n",
              sys.num_contacts(), r.samples, worst);
  EXPECT_EQ(r.samples, 100);
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(r.eta, 1e-6);
}

TEST(RandomWalkPlot, Fig4ScriptWritesPng) {
  if (std::system("/usr/bin/python3 -c 'import matplotlib' > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "/usr/bin/python3 cannot import matplotlib";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "unjam-test-plot-fig4";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  {
    std::ofstream csv(dir / "ensemble.csv");
    csv << "a,b,fn,fn_min,fn_max,hr_min,hr_max,hr_mean,hr_std,walk_min,walk_max,walk_mean,"
           "walk_std,f_crit,f_crit_method,probe_converged,probe_sweeps\n"
           "0,1,1.0,0.5,2.0,0.7,1.8,1.1,0.2,0.6,1.9,1.0,0.3,1.95,nlgs,1,1000\n"
           "0,2,0.4,0.0,1.0,0.1,0.8,0.4,0.1,0.0,0.9,0.3,0.2,0.98,nlgs,1,2000\n"
           "1,2,0.0,0.0,0.3,0.0,0.2,0.1,0.05,0.0,0.25,0.1,0.05,,,,\n";
    std::ofstream json(dir / "ensemble.json");
    json << "{\"F0\": 1.5}\n";
  }
  const std::string cmd = "/usr/bin/python3 " + std::string(UNJAM_SOURCE_DIR) +
                          "/scripts/plot_fig4.py " + dir.string() + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const auto png = dir / "fig4-ensemble.png";
  ASSERT_TRUE(std::filesystem::exists(png));
  EXPECT_GT(std::filesystem::file_size(png), 1000u);
  std::filesystem::remove_all(dir);
}

}  // namespace
