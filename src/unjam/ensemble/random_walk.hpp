#pragma once
// The paper's exploration of the admissible force networks (docs/ensemble.md, "The paper's
// random walk and Fig. 4"; Unger, Kertesz, Wolf, cond-mat/0403089): a random walk of kicks,
// each relaxed back into the admissible set by the contact-dynamics solver at fixed geometry.
//
// Start: the packing's own network on the contacts of the admissible set (`system`). Step:
//   1. kick: fn_k += U(-a, a), ft_k += U(-a, a) for every contact of the set, with the
//      amplitude a = kick <F_n>, <F_n> the mean normal force of the packing's network over
//      the set (force units). A kicked fn may be negative and ft may leave the Coulomb
//      cone: NLGS projects every contact onto its law at its first update, and the warm
//      start only applies the kicked forces to the velocities (no clamp needed);
//   2. relax: solve_static on a copy of the packing that holds only the contacts of the set
//      (all treated as touching, g_eff = 0), under the contact model of the options (mu, and
//      the bath of P_ext and M_lambda: bath_of), warm-started from the kicked forces: NLGS
//      to a coarse residual, then the exact polish onto the balance rows;
//   3. if the solve converged, the relaxed network is the new state of the walk and one
//      sample; otherwise the step counts as a failure and the walk stays where it was.
// Every sample is admissible: balance and pressure rows to the solve tolerance, fn >= 0,
// |ft| <= mu fn. The samples are correlated and not uniform on the polytope (compare
// hit_and_run.hpp). Per contact: sampled min, max, mean and standard deviation (n - 1) of
// fn, and eta = <dF> / <|F|> as in hit_and_run.hpp.
// Random numbers (kicks and the NLGS colour orders) come from std::mt19937_64 seeded with
// `seed`; the NLGS result does not depend on the thread count: same seed, same samples.
#include <cstdint>
#include <functional>
#include <optional>

#include <Eigen/Core>

#include "unjam/ensemble/sampled_forces.hpp"

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/packing/contact_model.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

struct RandomWalkOptions {
  int samples = 20000;      // steps of the walk (kick + relaxation); failures are not samples
  std::uint64_t seed = 1;
  double kick = 1.0;        // kick amplitude in units of <F_n>
  double tol = 1e-10;       // static solve target: grain force, torque / R residual / F0 and
                            // |P_in / P_ext - 1|
  int max_sweeps = 200000;  // NLGS sweeps per relaxation before it counts as a failure
  // The contact model of the relaxation (mu, the bath's P_ext and M_lambda, touch_gap: the
  // model that selected `system`); empty: the packing's own (contact_model_of).
  std::optional<ContactModel> model;
  std::function<void(const ForceNetwork&)> on_sample;  // every sample, may be empty
  std::function<void(int, int)> progress;              // (steps done, steps), may be empty
};

struct RandomWalkResult : SampledForces {
  double kick_amplitude = 0.0;             // a = kick <F_n> (force units)
  int samples = 0;                         // converged relaxations
  int failures = 0;                        // relaxations that did not converge
  long long sweeps = 0;                    // NLGS sweeps over all relaxations
};

// Walks from the network of `packing` over the admissible set of `system` (built from the
// same packing). Throws unjam::Error if options.samples < 1 or the kick is negative.
RandomWalkResult sample_random_walk(const Packing& packing, const EquilibriumSystem& system,
                                    const RandomWalkOptions& options = {});

}  // namespace unjam
