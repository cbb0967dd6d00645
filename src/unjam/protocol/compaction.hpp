#pragma once
// The compaction protocol (docs/method.md, "Compaction"): integrate the packing under the pressure
// bath until it is static. The dynamics runs with a loose NLGS tolerance; once the
// force-carrying grains have nearly stopped and P_in ~ P_ext, a static force solve at the
// fixed geometry decides: if it reaches the residual target the packing is static (its
// network balances every grain with P_in = P_ext, velocities set to zero), else the
// dynamics goes on. An attempt may take attempt_budget (L / d)^2 sweeps (NLGS needs ~(L/d)^2
// sweeps to carry a rigid response across the cell, docs/method.md), and the next one
// waits until the dynamics has spent as many sweeps or the loaded grains have slowed down
// three times.
#include <cstddef>
#include <cstdint>
#include <functional>

#include "unjam/packing/packing.hpp"
#include "unjam/solver/static_solve.hpp"
#include "unjam/solver/time_step.hpp"

namespace unjam {

struct CompactionSettings {
  DynamicsSettings dynamics;
  StaticSolveSettings final_solve;
  double v_static = 1e-3;      // mean speed of force-carrying grains (R_max / t0) to try
  double p_static = 1e-2;      // ... and |P_in / P_ext - 1| below this
  double attempt_budget = 0.5;   // sweeps of one attempt, in units of (L / d)^2 (at least 2000)
  std::int64_t max_steps = 10'000'000;
};

struct CompactionProgress {
  std::int64_t step = 0;
  double time = 0.0;
  double phi = 0.0;
  double P_ratio = 0.0;        // P_in / P_ext
  double v_mean = 0.0;         // mean speed of force-carrying grains
  double sweeps_per_step = 0.0;  // since the last report
  int contacts = 0;
  double elapsed_s = 0.0;
  double eta_s = -1.0;         // estimated seconds left, < 0 while unknown
  int static_attempts = 0;
};

struct CompactionHooks {
  std::function<void(const CompactionProgress&)> progress;  // called every progress_s
  double progress_s = 2.0;
  std::function<void(const Packing&)> checkpoint;           // called every checkpoint_s
  double checkpoint_s = 60.0;
  std::function<bool()> should_stop;                        // polled every step
  // After every static solve attempt: step, mean speed of loaded grains, the solve's report.
  std::function<void(std::int64_t, double, const StaticSolveReport&)> attempt;
};

struct CompactionResult {
  bool is_static = false;
  bool stopped = false;        // should_stop returned true
  std::int64_t steps = 0;      // steps taken by this call
  std::int64_t sweeps = 0;     // NLGS sweeps of the dynamics
  std::int64_t contact_updates = 0;
  int static_attempts = 0;
  StaticSolveReport final_solve;  // report of the last static solve
  double wall_s = 0.0;
};

// Throws unjam::Error on invalid settings (mu < 0, P_ext <= 0, dt <= 0, M_lambda <= 0, ...).
void validate(const CompactionSettings& settings, double mu);

// Runs the protocol from the packing's current state (a gas, or a stopped run). Throws
// unjam::Error if the cell shrinks below Packing::min_cell_side (too few grains to jam).
CompactionResult compact(Packing& packing, const CompactionSettings& settings,
                         const CompactionHooks& hooks = {});

// Peak memory of a compaction of N disks, an upper estimate: 16 MB + 8 kB per disk. The
// measured peak resident size is 13.6 MB at N = 1000 and 18.4 MB at N = 2000, i.e. ~4.9 kB
// per disk (docs/benchmarks.md, "Memory"); the margin covers the fill of the static solve's
// factorisation, which grows a little faster than N.
std::size_t estimated_memory_bytes(std::size_t N);

// Mean speed of the grains that carry a compressive contact force (rattlers drift for ever
// in zero gravity and are left out).
double mean_speed_of_loaded_grains(const Packing& packing);

}  // namespace unjam
