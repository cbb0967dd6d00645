#pragma once
// The friction threshold of a packing (docs/ensemble.md, "The friction threshold"): the
// smallest Coulomb coefficient at which its contacts, as they stand, still admit a force
// network,
//   mu_s = min { m >= 0 : { A x = rhs, fn >= 0, |ft| <= m fn } is not empty },
// with A and rhs the balance and pressure rows of equilibrium_matrix.hpp (they do not depend
// on the friction coefficient). The set grows with m, so its emptiness is monotone in m and
// mu_s is found by bisection, one LP (has_admissible_network, dual simplex) per step. A static
// packing has mu_s <= mu (its own network is admissible at mu); mu_s / mu is how much of its
// friction the packing needs at the least, 1 at the edge of frictional failure.
#include <functional>
#include <limits>

#include "unjam/contact/equilibrium_matrix.hpp"

namespace unjam {

struct FrictionThreshold;

struct FrictionThresholdOptions {
  // Stop once mu_high - mu_low <= rel_tol * max(mu, mu_high of the start): the threshold to a
  // fraction rel_tol of the packing's own coefficient. In (0, 1).
  double rel_tol = 1e-3;
  double tolerance = 1e-9;  // CLP's feasibility tolerance, see ForceLP
  // A bracket to start from (a stopped run's last one, or a coarser run's): the set must be
  // empty at mu_low and not at mu_high (both checked, one LP each), 0 <= mu_low < mu_high.
  // NaN (the default): the bracket [0, mu] of the system's own coefficient.
  double mu_low = std::numeric_limits<double>::quiet_NaN();
  double mu_high = std::numeric_limits<double>::quiet_NaN();
  // The bracket's ends are known, both checked by an earlier run of the same bisection (its
  // checkpoint, `unjam threshold`): the bisection goes on without solving them again.
  bool bracket_checked = false;
  // Called after every LP with the LPs this run will solve in all and the result so far (its
  // bracket, LPs, iterations and seconds); may be empty.
  std::function<void(int total, const FrictionThreshold& so_far)> progress;
  // Polled before every LP; once it returns true, friction_threshold throws unjam::Cancelled.
  // May be empty.
  std::function<bool()> should_stop;
};

struct FrictionThreshold {
  double mu = 0.0;  // the system's own coefficient
  // mu_s lies in (mu_low, mu_high]: the admissible set is empty at mu_low and not at mu_high.
  // Where it is not empty without friction (or the system's mu is 0), mu_low = mu_high = 0.
  double mu_low = 0.0, mu_high = 0.0;
  int lps = 0;           // LPs solved
  long long iterations = 0;  // dual simplex iterations over the LPs
  double seconds = 0.0;  // wall time of the LPs
};

// Throws unjam::Error for a bad option, a bracket whose ends are not as stated, or (with the
// default bracket) a system whose admissible set is empty at its own mu: then the packing is
// not static, or its contact list is incomplete.
FrictionThreshold friction_threshold(const EquilibriumSystem& system,
                                     const FrictionThresholdOptions& options = {});

}  // namespace unjam
