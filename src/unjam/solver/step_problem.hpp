#pragma once
// The frictional contact problem of one contact-dynamics time step (docs/method.md, "One time
// step", with the cell strain rate of the pressure bath): the data the solver needs besides its
// unknowns. The unknowns live in the caller's Contacts (forces fn, ft; geometry read only) and
// Particles (velocities: free velocities in, velocities at t+dt out).
#include <vector>

#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/cell.hpp"
#include "unjam/packing/contact.hpp"

namespace unjam {

// Andersen-type pressure bath: M_lambda dlambda/dt = P_in - P_ext, lambda = Ldot/L.
struct Bath {
  bool enabled = true;    // false: the cell strain rate stays lambda_t (0 for a fixed cell)
  double P_ext = 1.0;     // external pressure
  double M_lambda = 100.0;  // inertia of the cell (mass units per area; docs/method.md)
};

// The bath of a contact model: its P_ext and M_lambda, enabled.
inline Bath bath_of(const ContactModel& model) { return {true, model.P_ext, model.M_lambda}; }

struct StepProblem {
  Cell cell;                   // cell at time t; V = Lx Ly
  // Time step (simulation time units): the solver's input, not a setting of its own; the
  // step that builds the problem sets it from its setting (docs/ARCHITECTURE.md, "Time
  // steps"): ContactProblem::dt (step_problem), DynamicsSettings::dt (advance),
  // StaticSolveSettings::dt (solve_static).
  double dt = 0.01;
  double mu = 0.0;             // Coulomb friction coefficient
  Bath bath;
  double lambda_t = 0.0;       // cell strain rate at time t
  // Per contact, the gap the step must respect: the contact closes when
  // g_eff + dt U*_n <= 0. max(gap, 0) by default (docs/method.md, "One time
  // step": no overlap correction); -g for the probe's opened contact (docs/probe.md).
  std::vector<double> g_eff;
};

// g_eff = max(gap, 0) for every contact.
std::vector<double> positive_gaps(const Contacts& contacts);

// g_eff of a static packing's contacts: 0 for pairs that touch (classify_contact: gap <
// touch_gap, overlaps included), the gap otherwise, as build_contact_problem sets it. The
// static solve uses it.
std::vector<double> touching_gaps(const Contacts& contacts, double touch_gap);

// The step of `problem` for solve_nlgs: its cell, dt, mu, bath (P_ext, M_lambda; enabled)
// and g_eff, starting at rest (lambda_t = 0).
StepProblem step_problem(const ContactProblem& problem);

}  // namespace unjam
