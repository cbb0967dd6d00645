#pragma once
// The static force solve: at fixed geometry, with all velocities and the cell strain rate
// set to zero, find contact forces that balance every grain with P_in = P_ext. It is one
// contact-dynamics step with v_free = 0 (the reference's "final force solve"): NLGS
// (kStatic rule) to a coarse residual, then the exact polish of force_polish.hpp on the
// active set NLGS found; if the polish fails (active set not settled yet), NLGS goes on
// to a ten times smaller residual and the polish is tried again.
// The step's contact model: mu from packing.meta.contact, P_ext and M_lambda from `bath` for
// NLGS, touch_gap from the settings (g_eff by touching_gaps, step_problem.hpp); the polish
// takes the packing's model with that touch_gap (with_touch_gap).
#include <cstdint>

#include "unjam/packing/packing.hpp"
#include "unjam/solver/nlgs.hpp"
#include "unjam/solver/step_problem.hpp"

namespace unjam {

struct StaticSolveSettings {
  // Time step of the solve's step (v_free = 0; simulation time units). The static network
  // does not depend on it, the NLGS iterates that reach it do: the compaction passes its own
  // step (DynamicsSettings::dt), so that a packing's bytes depend on --dt as its dynamics do;
  // the random walk's relaxation keeps this default.
  double dt = 0.01;
  double tol = 1e-9;          // target: grain force and torque / R residual / F0, |P_in/P_ext - 1|
  double polish_from = 1e-2;  // first NLGS residual at which the polish is tried; 0: no polish
  double touch_gap = 1e-6;    // pairs with gap below this touch: they can close (g_eff = 0)
  double relax = 1.0;         // over-relaxation of the NLGS sweeps (NlgsSettings::relax)
  int max_sweeps = 1000000;
  int check_every = 50;
  std::uint64_t seed = 0;
};

struct StaticSolveReport {
  bool converged = false;
  int sweeps = 0;                 // NLGS sweeps in all
  double max_residual_F0 = 0.0;   // largest grain force or torque / R residual / F0
  double pressure_error = 0.0;    // |P_in / P_ext - 1|
  bool polished = false;          // the final network came from the polish
};

// Solves in place: packing.contacts' forces become the static network (warm-started from
// their current values); velocities and lambda are set to zero. `threading` holds the
// measurements of Threading::kAuto (nlgs.hpp), shared by the solve's NLGS rounds and by
// whatever else the caller passes it to.
StaticSolveReport solve_static(Packing& packing, const Bath& bath, const StaticSolveSettings& settings,
                               NlgsThreading& threading);
// The same with measurements of its own.
StaticSolveReport solve_static(Packing& packing, const Bath& bath, const StaticSolveSettings& settings);

}  // namespace unjam
