#pragma once
// The power-law fit of the displacement profile, d(r) = A r^-alpha (the paper's Fig. 2 and
// eq. 1), by least squares in log-log:
//   ln d_k = ln A - alpha ln r_k   over the bins k of the window,
// with r_k = r_mid (the bin's geometric centre), d_k = d_mean, every bin weighted equally
// (the bins are logarithmic, so every decade of r weighs the same).
//
// Window: a bin enters if it lies entirely inside [r_lo, r_hi] (r_lo <= bin's lower edge,
// bin's upper edge <= r_hi) and has count > 0 and d_mean > 0. The default window is one
// decade from the first shell of neighbours, as far as the cell allows:
//   r_lo = 1 mean grain diameter d    (inside it lie only the probed pair's own grains),
//   r_hi = min(10 d, L_min / 2)       (beyond L_min / 2 the minimum-image square cuts the
//                                      circles of radius r).
// The profile is not straight on log-log axes: its local slope grows from ~1 at r ~ 3 d to
// 1.6-2 beyond r ~ 5 d, at 2000 and 8000 disks alike (docs/probe.md), so alpha depends on
// the window. One decade from d is what the paper's smallest packings allow (500 disks:
// L_min / 2 ~ 10 d), so the window is the same at every size from 500 disks on.
//
// Error: bootstrap over probes. Resample the P probes with replacement (P draws, seeded
// std::mt19937_64, indices by rejection sampling, so identical on every platform), pool their
// per-probe rows into d*_k = sum s_pk / sum c_pk, refit on the window's bins that have
// d*_k > 0 (at least 2, else the resample is dropped), and take the sample standard deviation
// (divisor n - 1) of the n refitted alphas.
#include <cstdint>
#include <vector>

#include "unjam/analysis/response_average.hpp"
#include "unjam/core/cell.hpp"

namespace unjam {

struct FitWindow {
  double r_lo = 0.0;  // length units (R_max = 1)
  double r_hi = 0.0;
};

// [mean_diameter, min(10 mean_diameter, min(Lx, Ly) / 2)]; holds fewer than two bins only in
// a cell a few diameters wide (the fit then throws).
FitWindow default_fit_window(const Cell& cell, double mean_diameter);

struct PowerLawFit {
  double alpha = 0.0;          // decay exponent, d = A r^-alpha
  double alpha_err = 0.0;      // bootstrap standard deviation of alpha (0 without bootstrap
                               // or with fewer than 2 resamples)
  double log_A = 0.0;          // ln A (d in units of g, r in units of R_max)
  double r_lo = 0.0;           // lower edge of the first bin used
  double r_hi = 0.0;           // upper edge of the last bin used
  int bins = 0;                // bins used
  double R2 = 0.0;             // 1 - SS_res / SS_tot in log-log (1 if SS_tot = 0)
  int bootstrap_samples = 0;   // resamples that gave a fit
};

// Indices of the bins that enter the fit (rule above), increasing.
std::vector<std::size_t> fit_bins(const RadialProfile& profile, FitWindow window);

// The fit of a profile, without error. Throws unjam::Error if fewer than 2 bins enter.
PowerLawFit fit_power_law(const RadialProfile& profile, FitWindow window);

// The fit of avg.profile() with the bootstrap error over avg's probes (`bootstrap_samples`
// resamples, `seed`). Deterministic: the same accumulator, window and seed give the same
// result bit for bit. Throws unjam::Error like the above, or if bootstrap_samples < 0.
PowerLawFit fit_power_law(const ResponseAverage& avg, FitWindow window, int bootstrap_samples,
                          std::uint64_t seed);

}  // namespace unjam
