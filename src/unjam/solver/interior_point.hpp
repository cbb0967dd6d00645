#pragma once
// The contact problem of one step (contact/contact_problem.hpp) as a mixed complementarity
// problem, by a primal-dual interior-point method (docs/probe.md, "An interior-point start").
//
// Unknowns: the velocities v = q / dt^2 (free), and per contact the Stewart-Trinkle variables
// z = (fn, beta+, beta-, sigma) >= 0, ft = beta+ - beta-, with their complements w >= 0:
//     balance:  M v - A f = -b
//     w_fn    = U_n = a_n^T v + g_eff / dt^2       (Signorini: fn w_fn = 0)
//     w_beta+ = sigma + U_t,  w_beta- = sigma - U_t (ft opposes the slip U_t = a_t^T v)
//     w_sigma = mu fn - beta+ - beta-               (sigma = |U_t| > 0 only on the cone's edge)
// which is Coulomb's law with non-associated sliding (no dilatancy). At mu = 0 only fn is
// kept. The method follows the central path z w = t (Mehrotra's predictor-corrector, one
// sparse factorisation per iteration) towards t = 0. With non-associated friction the
// problem is not monotone and the central path may end before t = 0; the iterate is then a
// guess, not a solution, and the exact probe starts its path from it (probe/cd_path,
// CdPathStart::interior_point).
#include <vector>

#include <Eigen/Core>

#include "unjam/contact/contact_problem.hpp"

namespace unjam {

struct InteriorPointSettings {
  double velocity_scale = 0.0;  // U of order one (length / t0^2), e.g. g / dt^2; > 0 required
  int max_iterations = 40;
  double target = 1e-8;         // stop where the mean of z w (scaled by F0 and velocity_scale) is below
  int stall_iterations = 8;     // stop where that mean has not halved over this many iterations,
  double stall_below = 1e-2;    // once it is below this
  // The wide neighbourhood (docs/probe.md, "Keeping the iterates centred"): every step is
  // shortened (by factors 0.7) until the new iterate has min z w >= gamma (mean z w), gamma =
  // the smaller of `neighbourhood` and the present iterate's own min z w / mean z w, so that
  // no pair is driven to the boundary ahead of the others. 0: plain Mehrotra, no such cut
  // (the exact probe runs it so where plain Mehrotra ends far from a solution,
  // CdPathSettings::interior_neighbourhood).
  double neighbourhood = 0.0;
  // Where the predictor-corrector step, so cut, is shorter than `short_step`, plain Newton
  // steps towards sigma t (no second-order term) are tried in its place, sigma = 0.3, 0.6,
  // 0.9 and 1, each cut in the same way; the first that goes at least half way is taken,
  // else the last (a centring step). Only with neighbourhood > 0.
  double short_step = 0.1;
};

struct InteriorPointResult {
  Eigen::VectorXd f;            // (fn_0, ft_0, fn_1, ...), force units
  Eigen::VectorXd q;            // generalised displacement over the step, dt^2 v (rows of A)
  int iterations = 0;
  double complementarity = 0.0; // mean z w at the end (scaled)
  double natural_residual = 0.0;  // max |min(z, w)| at the end (scaled: F0, velocity_scale)
  bool stalled = false;         // stopped short of the target: max_iterations, the stall test or a singular system
  int short_steps = 0;          // iterations that took a plain Newton step in place of the predictor-corrector's
  std::vector<double> centrality;  // min z w / mean z w of every iterate, the start's first
  // Per contact, which member of each complementary pair is the larger at the end (the
  // iterate's own reading of the states, where the forces alone are ambiguous): closed where
  // fn > w_fn (the normal displacement's complement), sliding where sigma > w_sigma =
  // mu fn - beta+ - beta- (the slip rate exceeds the distance to the cone's edge, mu fn - |ft|
  // where one beta is zero; never at mu = 0).
  std::vector<bool> closed, sliding;
};

// Throws unjam::Error for a velocity_scale that is not positive, non-positive iteration counts,
// a neighbourhood outside [0, 1) or a short_step outside [0, 1].
InteriorPointResult interior_point_step(const ContactProblem& problem, const InteriorPointSettings& settings);

}  // namespace unjam
