#pragma once
// Exact completion of a static force solve. NLGS reaches the static network only slowly
// (the error decays over ~(L/d)^2 sweeps, docs/method.md), but it finds the active set
// early: which contacts are open (fn = 0), sliding (|ft| = mu fn) or sticking. With the
// active set fixed, balance is a linear system. The polish makes the smallest change to
// the forces that satisfies it exactly:
//     delta = -B^T (B B^T)^{-1} r,   r = B f - rhs,
// where B holds the balance rows (force, torque / R, pressure) restricted to the free force
// components: (fn, ft) of a closed contact, fn along n + s mu t of a sliding one with slip
// sign s = sign(ft), fn alone when mu = 0. The states are the project's one contact state,
// contact_state (packing/contact.hpp): first of the NLGS network (a contact with
// mu fn - |ft| <= 1e-9 mu fn slides), then of each corrected network, strictly (tol just
// below 0): a contact whose fn turned negative becomes open, a closed one outside the Coulomb
// cone (|ft| > mu fn) becomes sliding, and the solve repeats (core/least_norm.hpp,
// solve_active_set). States only move closed -> sliding -> open.
#include <vector>

#include "unjam/packing/contact.hpp"
#include "unjam/packing/contact_model.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

struct PolishResult {
  bool success = false;      // admissible network with residual below the target
  double max_residual_F0 = 0.0;  // largest grain force or torque / R residual, / F0
  double pressure_error = 0.0;   // |P_in / P_ext - 1|
  double max_change_F0 = 0.0;    // largest change of a force component, / F0
  int active = 0;            // contacts carrying force after the polish
  int rounds = 0;            // least-norm solves (active sets tried)
  // On success, per contact of packing.contacts, its state in the final active set: open (the
  // pairs left out and those opened: fn = ft = 0), sliding (ft = +-mu fn), closed (fn >= 0,
  // |ft| <= mu fn). contact_state(fn, ft, mu, 0) of the forces written gives the same, except
  // for a closed contact on the boundary (fn = 0 or |ft| = mu fn exactly).
  std::vector<ContactState> states;
};

// Polishes packing.contacts in place when it succeeds; leaves them untouched otherwise.
// `model`: the solve's contact model; mu, and P_ext for F0 and the pressure row (the balance
// rows are model_system's, contact/contact_problem.hpp, as in every ContactProblem); only
// pairs that touch and carry force (classify_contact with model.touch_gap and fn_min = 0,
// packing/contact_model.hpp) enter, any other is set open. M_lambda is not used (no inertia
// in a static network).
PolishResult polish_forces(Packing& packing, double tol, const ContactModel& model);

}  // namespace unjam
