#pragma once
// Uniform sampling of the admissible force networks (docs/ensemble.md, "The admissible
// force networks") by hit-and-run.
//
// The polytope is { y >= 0 : A_y y = rhs } in Coulomb-cone coordinates (equilibrium_matrix.hpp);
// uniform in y is uniform in (fn, ft). Contacts whose LP maximum is zero (fn_max <= fixed_tol
// F0) are open in every network: their coordinates are fixed at 0 and left out of the walk,
// so the remaining polytope has an interior in its affine hull.
//   1. The null space of the remaining equality columns A (m x n). Up to max_dense_columns
//      cone columns: an orthonormal basis B from the dense column-pivoting QR of A^T (Eigen),
//      rank threshold 1e-10 relative (O(n^2) memory, O(n^2 m) time). Beyond: no basis, but
//      the projector P = I - A^T (A A^T)^+ A through one sparse LDLT of A A^T, and the
//      dimension from numerical_rank (lp/rank.hpp).
//   2. Start: a Chebyshev-like centre, max s subject to A y = rhs, y_i >= s (CLP), then
//      projected exactly onto A y = rhs.
//   3. Step: a direction d uniform on the unit sphere of the null space (dense: B z / |z|;
//      sparse: P r / |P r|, z and r standard normal); the chord {y + t d >= 0} is
//      [t_min, t_max]; t uniform on it. Every 1000 steps y is projected back onto the
//      equalities (round-off drift).
//   4. One sample every `thin` steps after `burn_in` steps; per contact the sampled min, max,
//      mean and standard deviation of fn, and eta = <dF> / <|F|> with dF_k the standard
//      deviation of fn_k over the samples, <dF> its mean over the contacts and <|F|> the mean
//      of fn over contacts and samples (Unger, Kertesz, Wolf, cond-mat/0403089).
// The random numbers come from std::mt19937_64 seeded with `seed`: same seed, same samples.
#include <cstdint>
#include <functional>

#include <Eigen/Core>

#include "unjam/ensemble/sampled_forces.hpp"

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/ensemble/force_bounds.hpp"

namespace unjam {

struct HitAndRunOptions {
  int samples = 20000;
  int thin = 0;        // steps per sample; 0: the dimension of the polytope (at least 1)
  int burn_in = 0;     // steps before the first sample; 0: 100 x the dimension
  std::uint64_t seed = 1;
  double fixed_tol = 1e-9;         // F0: contacts with fn_max <= fixed_tol F0 stay open
  int max_dense_columns = 4000;    // up to this many cone columns a dense null-space basis
  std::function<void(const ForceNetwork&)> on_sample;  // every sample, may be empty
};

struct HitAndRunResult : SampledForces {
  int dimension = 0;                       // dimension of the sampled polytope
  int fixed_open = 0;                      // contacts open in every network (not walked)
  double start_depth = 0.0;                // s of the start: min cone coordinate (force units)
  long long steps = 0;                     // hit-and-run steps taken
  int samples = 0;
};

// Samples the admissible networks of `system`; `bounds` are its LP intervals (used to fix the
// always-open contacts). Throws unjam::Error if the polytope has no interior once the
// always-open contacts are fixed (some contact would have to slide in every network).
HitAndRunResult sample_hit_and_run(const EquilibriumSystem& system, const ForceBounds& bounds,
                                   const HitAndRunOptions& options = {});

}  // namespace unjam
