#pragma once
// Exact completion of a static force solve. NLGS reaches the static network only slowly
// (the error decays over ~(L/d)^2 sweeps, docs/method.md), but it finds the active set
// early: which contacts are open (fn = 0), sliding (|ft| = mu fn) or sticking. With the
// active set fixed, balance is a linear system. The polish makes the smallest change to
// the forces that satisfies it exactly:
//     delta = -B^T (B B^T)^{-1} r,   r = B f - rhs,
// where B holds the balance rows (force, torque / R, pressure) restricted to the free force
// components: (fn, ft) of a sticking contact, fn along n + s mu t of a sliding one with slip
// sign s, fn alone when mu = 0. A contact whose corrected fn turns negative becomes open, a
// sticking one that leaves the Coulomb cone becomes sliding, and the solve repeats.
#include "unjam/packing/packing.hpp"

namespace unjam {

struct PolishResult {
  bool success = false;      // admissible network with residual below the target
  double max_residual_F0 = 0.0;  // largest grain force or torque / R residual, / F0
  double pressure_error = 0.0;   // |P_in / P_ext - 1|
  double max_change_F0 = 0.0;    // largest change of a force component, / F0
  int active = 0;            // contacts carrying force after the polish
  int rounds = 0;            // active-set updates
};

// Polishes packing.contacts in place when it succeeds; leaves them untouched otherwise.
// Only pairs that touch and carry force (classify_contact with touch_gap and fn_min = 0,
// packing/contact_model.hpp) enter; any other is set open.
PolishResult polish_forces(Packing& packing, double tol, double touch_gap);

}  // namespace unjam
