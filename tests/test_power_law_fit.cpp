#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "unjam/analysis/power_law_fit.hpp"
#include "unjam/core/error.hpp"

namespace unjam {
namespace {

// Profile bins [0.5, 50), 20 logarithmic bins (10 per decade).
ResponseGrid fit_grid() {
  ResponseGrid g;
  g.half_width = 5.0;
  g.h = 1.0;
  g.r_min = 0.5;
  g.r_max = 50.0;
  g.r_bins = 20;
  return g;
}

// A profile on fit_grid's bins with d = A r_mid^-alpha and count 1 in every bin.
RadialProfile exact_profile(double A, double alpha) {
  const ResponseGrid g = fit_grid();
  RadialProfile p;
  for (int k = 0; k < g.r_bins; ++k) {
    p.r_lo.push_back(g.r_edge(k));
    p.r_hi.push_back(g.r_edge(k + 1));
    p.r_mid.push_back(std::sqrt(g.r_edge(k) * g.r_edge(k + 1)));
    p.d_mean.push_back(A * std::pow(p.r_mid.back(), -alpha));
    p.d_sem.push_back(0.0);
    p.count.push_back(1);
    p.probes.push_back(1);
  }
  return p;
}

// One probe: `per_bin` grains at r_mid of every bin, at random angles, with |u|/g =
// A r^-alpha times amplitude(rng) (per probe) times grain_noise(rng) (per grain).
template <class Amp, class Noise>
FrameField power_law_probe(double A, double alpha, int per_bin, std::mt19937_64& rng, Amp amplitude,
                           Noise grain_noise) {
  const ResponseGrid g = fit_grid();
  std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
  const double a_p = amplitude(rng);
  FrameField f;
  for (int k = 0; k < g.r_bins; ++k) {
    const double r = std::sqrt(g.r_edge(k) * g.r_edge(k + 1));
    for (int i = 0; i < per_bin; ++i) {
      const double phi = angle(rng), psi = angle(rng);
      const double d = A * std::pow(r, -alpha) * a_p * grain_noise(rng);
      f.x.push_back(r * std::cos(phi));
      f.y.push_back(r * std::sin(phi));
      f.ux.push_back(d * std::cos(psi));
      f.uy.push_back(d * std::sin(psi));
    }
  }
  return f;
}

TEST(PowerLawFit, ExactDataGiveTheExponent) {
  const PowerLawFit fit = fit_power_law(exact_profile(0.7, 1.234), FitWindow{0.0, 1e9});
  EXPECT_NEAR(fit.alpha, 1.234, 1e-12);
  EXPECT_NEAR(fit.log_A, std::log(0.7), 1e-12);
  EXPECT_NEAR(fit.R2, 1.0, 1e-12);
  EXPECT_EQ(fit.bins, 20);
  EXPECT_EQ(fit.r_lo, 0.5);
  EXPECT_EQ(fit.r_hi, 50.0);
  EXPECT_EQ(fit.alpha_err, 0.0);
  EXPECT_EQ(fit.bootstrap_samples, 0);
}

// Identical probes with exact power-law data through the accumulator: the exponent is exact
// and every bootstrap resample gives the same exponent.
TEST(PowerLawFit, ExactProbesThroughTheAccumulator) {
  ResponseAverage avg(fit_grid());
  std::mt19937_64 rng(1);
  auto one = [](std::mt19937_64&) { return 1.0; };
  for (int p = 0; p < 10; ++p) avg.add_probe(p, power_law_probe(2.0, 0.85, 3, rng, one, one), 1.0);
  const PowerLawFit fit = fit_power_law(avg, FitWindow{1.0, 40.0}, 100, 5);
  EXPECT_NEAR(fit.alpha, 0.85, 1e-12);
  EXPECT_NEAR(fit.log_A, std::log(2.0), 1e-12);
  EXPECT_EQ(fit.bootstrap_samples, 100);
  EXPECT_LT(fit.alpha_err, 1e-12);
}

TEST(PowerLawFit, DefaultWindowIsOneDecadeFromTheFirstNeighbours) {
  // Mean diameter 1.2, cell 60 x 50: window [1.2, 12] (10 d < L_min / 2 = 25).
  const FitWindow w = default_fit_window(Cell{60.0, 50.0}, 1.2);
  EXPECT_DOUBLE_EQ(w.r_lo, 1.2);
  EXPECT_DOUBLE_EQ(w.r_hi, 12.0);
  // A cell narrower than 20 d: capped at L_min / 2.
  const FitWindow capped = default_fit_window(Cell{10.0, 8.0}, 1.2);
  EXPECT_DOUBLE_EQ(capped.r_lo, 1.2);
  EXPECT_EQ(capped.r_hi, 4.0);

  // Power law inside the window, something else in every bin that is not entirely inside.
  RadialProfile p = exact_profile(1.0, 1.1);
  std::vector<std::size_t> inside;
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (p.r_lo[k] >= 1.2 && p.r_hi[k] <= 12.0)
      inside.push_back(k);
    else
      p.d_mean[k] = 5.0 + k;  // near-field plateau / far-field image contamination
  }
  // Edges r_k = 0.5 10^(k/10): r_4 = 1.256 is the first lower edge >= 1.2, r_14 = 12.56 > 12,
  // so bins 4 .. 12 enter; bin 3 = [0.998, 1.256) and bin 13 = [9.98, 12.56) straddle the edges.
  ASSERT_EQ(inside.front(), 4u);
  ASSERT_EQ(inside.back(), 12u);
  EXPECT_EQ(fit_bins(p, w), inside);
  const PowerLawFit fit = fit_power_law(p, w);
  EXPECT_NEAR(fit.alpha, 1.1, 1e-12);
  EXPECT_EQ(fit.bins, 9);
  EXPECT_EQ(fit.r_lo, p.r_lo[4]);
  EXPECT_EQ(fit.r_hi, p.r_hi[12]);

  // Empty bins are skipped too; fewer than two bins is an error.
  p.count[5] = 0;
  EXPECT_EQ(fit_power_law(p, w).bins, 8);
  EXPECT_THROW(fit_power_law(p, FitWindow{1.2, 2.0}), Error);
  EXPECT_THROW(fit_power_law(p, default_fit_window(Cell{2.0, 2.0}, 1.2)), Error);  // [1.2, 1]
}

// Noisy probes: per-probe amplitude 1 +- 0.5 and per-grain factor 1 +- 0.3 (uniform, mean 1,
// so the mean over probes is the power law). One dataset of 200 probes.
ResponseAverage noisy_dataset(std::uint64_t seed, double alpha) {
  ResponseAverage avg(fit_grid());
  std::mt19937_64 rng(seed);
  auto amplitude = [](std::mt19937_64& r) { return std::uniform_real_distribution<double>(0.5, 1.5)(r); };
  auto noise = [](std::mt19937_64& r) { return std::uniform_real_distribution<double>(0.7, 1.3)(r); };
  for (int p = 0; p < 200; ++p) avg.add_probe(p, power_law_probe(1.0, alpha, 2, rng, amplitude, noise), 1.0);
  return avg;
}

TEST(PowerLawFit, NoisyDataWithinBootstrapErrorAndDeterministic) {
  const double alpha = 1.3;
  const ResponseAverage avg = noisy_dataset(42, alpha);
  const FitWindow w{1.0, 40.0};
  const PowerLawFit fit = fit_power_law(avg, w, 400, 11);
  EXPECT_EQ(fit.bootstrap_samples, 400);
  EXPECT_GT(fit.alpha_err, 0.0);
  EXPECT_LT(fit.alpha_err, 0.05);
  EXPECT_LT(std::abs(fit.alpha - alpha), 3.0 * fit.alpha_err);
  EXPECT_GT(fit.R2, 0.99);

  // Deterministic for a seed; another seed gives another (similar) error.
  const PowerLawFit again = fit_power_law(avg, w, 400, 11);
  EXPECT_EQ(again.alpha, fit.alpha);
  EXPECT_EQ(again.alpha_err, fit.alpha_err);
  const PowerLawFit other = fit_power_law(avg, w, 400, 12);
  EXPECT_EQ(other.alpha, fit.alpha);
  EXPECT_NE(other.alpha_err, fit.alpha_err);
  EXPECT_NEAR(other.alpha_err, fit.alpha_err, 0.3 * fit.alpha_err);
}

// The bootstrap error estimates the real scatter: over 30 independent datasets, the standard
// deviation of the fitted alpha agrees with the mean bootstrap error within 40 %.
TEST(PowerLawFit, BootstrapErrorMatchesScatterOverDatasets) {
  const double alpha = 0.9;
  const FitWindow w{1.0, 40.0};
  std::vector<double> alphas;
  double err_mean = 0.0;
  for (int s = 0; s < 30; ++s) {
    const PowerLawFit fit = fit_power_law(noisy_dataset(1000 + s, alpha), w, 200, s);
    alphas.push_back(fit.alpha);
    err_mean += fit.alpha_err / 30.0;
  }
  double mean = 0.0, var = 0.0;
  for (double a : alphas) mean += a / 30.0;
  for (double a : alphas) var += (a - mean) * (a - mean) / 29.0;
  EXPECT_NEAR(mean, alpha, 3.0 * err_mean / std::sqrt(30.0));
  EXPECT_NEAR(std::sqrt(var) / err_mean, 1.0, 0.4);
}

}  // namespace
}  // namespace unjam
