#include "unjam/analysis/power_law_fit.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "unjam/core/error.hpp"

namespace unjam {

namespace {

struct LineFit {
  double slope = 0.0, intercept = 0.0, R2 = 0.0;
};

// Least squares y = intercept + slope x (centred sums); needs >= 2 distinct x.
LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double x_mean = 0.0, y_mean = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    x_mean += x[i];
    y_mean += y[i];
  }
  x_mean /= n;
  y_mean /= n;
  double Sxx = 0.0, Sxy = 0.0, Syy = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double dx = x[i] - x_mean, dy = y[i] - y_mean;
    Sxx += dx * dx;
    Sxy += dx * dy;
    Syy += dy * dy;
  }
  LineFit f;
  f.slope = Sxy / Sxx;
  f.intercept = y_mean - f.slope * x_mean;
  double SS_res = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double e = y[i] - f.intercept - f.slope * x[i];
    SS_res += e * e;
  }
  f.R2 = Syy > 0.0 ? 1.0 - SS_res / Syy : 1.0;
  return f;
}

// Uniform integer in [0, n), n >= 1: rejection sampling on the 64-bit output, so that every
// standard library gives the same sequence (std::uniform_int_distribution does not).
std::uint64_t uniform_below(std::mt19937_64& rng, std::uint64_t n) {
  const std::uint64_t reject_below = (0 - n) % n;  // 2^64 mod n
  std::uint64_t v = rng();
  while (v < reject_below) v = rng();
  return v % n;
}

}  // namespace

FitWindow default_fit_window(const Cell& cell, double mean_diameter) {
  return {mean_diameter, std::min(10.0 * mean_diameter, 0.5 * std::min(cell.Lx, cell.Ly))};
}

std::vector<std::size_t> fit_bins(const RadialProfile& profile, FitWindow window) {
  std::vector<std::size_t> k_used;
  for (std::size_t k = 0; k < profile.size(); ++k)
    if (profile.r_lo[k] >= window.r_lo && profile.r_hi[k] <= window.r_hi && profile.count[k] > 0 &&
        profile.d_mean[k] > 0.0)
      k_used.push_back(k);
  return k_used;
}

PowerLawFit fit_power_law(const RadialProfile& profile, FitWindow window) {
  const std::vector<std::size_t> k_used = fit_bins(profile, window);
  if (k_used.size() < 2)
    throw Error("power-law fit: " + std::to_string(k_used.size()) + " bin(s) with data in the window [" +
                std::to_string(window.r_lo) + ", " + std::to_string(window.r_hi) + "], need at least 2");
  std::vector<double> ln_r, ln_d;
  for (std::size_t k : k_used) {
    ln_r.push_back(std::log(profile.r_mid[k]));
    ln_d.push_back(std::log(profile.d_mean[k]));
  }
  const LineFit line = fit_line(ln_r, ln_d);
  PowerLawFit fit;
  fit.alpha = -line.slope;
  fit.log_A = line.intercept;
  fit.R2 = line.R2;
  fit.r_lo = profile.r_lo[k_used.front()];
  fit.r_hi = profile.r_hi[k_used.back()];
  fit.bins = static_cast<int>(k_used.size());
  return fit;
}

PowerLawFit fit_power_law(const ResponseAverage& avg, FitWindow window, int bootstrap_samples,
                          std::uint64_t seed) {
  if (bootstrap_samples < 0) throw Error("power-law fit: bootstrap_samples must be >= 0");
  const RadialProfile profile = avg.profile();
  PowerLawFit fit = fit_power_law(profile, window);
  const std::vector<std::size_t> k_used = fit_bins(profile, window);

  std::vector<const ProbeProfile*> rows;  // increasing probe id
  for (const auto& [id, row] : avg.probe_profiles()) rows.push_back(&row);
  const std::uint64_t P = rows.size();

  std::mt19937_64 rng(seed);
  std::vector<double> S(k_used.size()), ln_r, ln_d, alphas;
  std::vector<std::int64_t> C(k_used.size());
  for (int b = 0; b < bootstrap_samples; ++b) {
    std::fill(S.begin(), S.end(), 0.0);
    std::fill(C.begin(), C.end(), 0);
    for (std::uint64_t draw = 0; draw < P; ++draw) {
      const ProbeProfile& row = *rows[uniform_below(rng, P)];
      for (std::size_t m = 0; m < k_used.size(); ++m) {
        S[m] += row.d_sum[k_used[m]];
        C[m] += row.count[k_used[m]];
      }
    }
    ln_r.clear();
    ln_d.clear();
    for (std::size_t m = 0; m < k_used.size(); ++m)
      if (C[m] > 0 && S[m] > 0.0) {
        ln_r.push_back(std::log(profile.r_mid[k_used[m]]));
        ln_d.push_back(std::log(S[m] / static_cast<double>(C[m])));
      }
    if (ln_r.size() >= 2) alphas.push_back(-fit_line(ln_r, ln_d).slope);
  }
  fit.bootstrap_samples = static_cast<int>(alphas.size());
  if (alphas.size() >= 2) {
    double mean = 0.0;
    for (double a : alphas) mean += a;
    mean /= static_cast<double>(alphas.size());
    double var = 0.0;
    for (double a : alphas) var += (a - mean) * (a - mean);
    fit.alpha_err = std::sqrt(var / static_cast<double>(alphas.size() - 1));
  }
  return fit;
}

}  // namespace unjam
