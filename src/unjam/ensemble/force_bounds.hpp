#pragma once
// Exact per-contact intervals of the normal force over the admissible force networks
// (docs/ensemble.md, "The LP"):
//   [fn_min_k, fn_max_k] = [min, max] fn_k  over  { A x = rhs, fn >= 0, |ft| <= mu fn }
// with A the balance and pressure rows of equilibrium_matrix.hpp, each end one LP of
// lp/force_lp.hpp. fn_max_k is the bound on the critical force F_crit of contact k
// (docs/probe.md, "The fast method").
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/core/work_source.hpp"
#include "unjam/lp/force_lp.hpp"

namespace unjam {

struct ForceBounds;

// The largest ForceBoundsOptions::open_tol_F0: a contact carrying 1e-3 F0 is not open.
inline constexpr double kMaxOpenTolF0 = 1e-3;

struct ForceBoundsOptions {
  int threads = 1;                  // OpenMP threads, one ForceLP copy each
  LpMethod method = LpMethod::barrier;
  // CLP's primal and dual feasibility tolerance (absolute, on the scaled model; see ForceLP).
  // 1e-9 is the tested value; allowed: [kMinLpTolerance, kMaxLpTolerance] (lp/force_lp.hpp;
  // docs/ensemble.md, "The LP's tolerances").
  double tolerance = 1e-9;
  bool keep_networks_at_max = false;  // store the argmax network of every contact
  // A contact with fn <= open_tol_F0 F0 in an admissible network can open: its fn_min is 0.
  // Minima at or below this are reported as 0 (the LP's own accuracy is ~tolerance).
  // Allowed: (0, kMaxOpenTolF0].
  double open_tol_F0 = 1e-9;
  // Called with (LPs done, total = 2 N_c) after every LP, one call at a time; may be empty.
  std::function<void(int, int)> progress;
  // Polled before LPs are handed out; once true no more are, and the result is incomplete
  // (ForceBounds::complete false). May be empty.
  std::function<bool()> should_stop;
  // Called after every LP with what is known so far (see ForceBounds::complete); may be empty.
  std::function<void(const ForceBounds&)> checkpoint;
  // A partial result to resume from (a checkpoint's; not with keep_networks_at_max): its
  // known values are kept, the LPs of the others are solved.
  const ForceBounds* resume = nullptr;
};

struct ForceBounds {
  Eigen::VectorXd fn_min, fn_max;            // per contact of the system
  std::vector<ForceNetwork> network_at_max;  // per contact, if keep_networks_at_max
  int min_lps_skipped = 0;  // minima certified 0 by another LP's network, without their own
  long long iterations = 0;                  // solver iterations over all LPs
  long long loosened_solves = 0;  // LPs solved at looser tolerances (ForceLP::loosened_solves)
  long long simplex_finishes = 0;  // barrier LPs finished by simplex (ForceLP::simplex_finishes)
  long long unscaled_solves = 0;   // simplex LPs solved again unscaled (ForceLP::unscaled_solves)
  double seconds = 0.0;                      // wall time of all LPs (model build included)
  // false if should_stop stopped the LPs: then NaN marks the values not known yet, and
  // fn_min = 0 every contact some optimal network opened (what a resume needs).
  bool complete = true;
};

// Throws unjam::Error, naming the option and its range, where tolerance is not in
// [kMinLpTolerance, kMaxLpTolerance] or open_tol_F0 not in (0, kMaxOpenTolF0] (NaN in neither).
void check_force_bounds_options(const ForceBoundsOptions& options);

// Both ends of every contact's interval. Every optimal network is admissible, so a contact
// it leaves open (fn <= open_tol) can open: fn_min = 0 with no LP of its own. Hence:
//   1. fn_max of every contact (one LP each); the contacts its argmax networks open get
//      fn_min = 0;
//   2. fn_min by LP for the rest, skipping any contact an earlier minimum's network opened.
// On a 2000-disk mu = 0.1 packing about a third of the contacts can open, and this saves
// 86 % of their min LPs (docs/ensemble.md).
// The LPs are handed out one at a time (the simplex: in contiguous chunks of 16) to the
// threads; each barrier LP starts from scratch, so its optimum does not depend on which thread
// solves it, nor on what it solved before.
// Throws unjam::Error for options outside their ranges (check_force_bounds_options).
ForceBounds compute_force_bounds(const EquilibriumSystem& system,
                                 const ForceBoundsOptions& options = {});

// The same over the processes of `distributor` (core/work_source.hpp), `options.threads` each:
// the result, progress and counts are those of the gathering process (rank 0); elsewhere
// the returned bounds are incomplete.
ForceBounds compute_force_bounds(const EquilibriumSystem& system, const ForceBoundsOptions& options,
                                 WorkDistributor& distributor);

}  // namespace unjam
