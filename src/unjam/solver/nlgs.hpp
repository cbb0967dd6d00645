#pragma once
// Nonlinear Gauss-Seidel for the contact problem of one time step (docs/method.md,
// "One time step").
//
// Each contact is solved in closed form given the forces of all others (open, sticking or
// sliding), and its force change is applied to the two velocities at once. Contacts are
// swept colour by colour (see coloring.hpp): a colour's contacts share no grain, so they are
// updated in parallel with exactly the result of a sequential sweep; the colour order is
// reshuffled every sweep. The cell strain rate is one more unknown: after every colour,
// lambda* = lambda_t + dt (P_in - P_ext) / M_lambda with the current P_in. All reductions
// run over fixed blocks in a fixed order, so the result is the same for any thread count.
#include <cstdint>

#include "unjam/packing/contact.hpp"
#include "unjam/packing/particles.hpp"
#include "unjam/solver/step_problem.hpp"

namespace unjam {

enum class Convergence {
  // The dynamics (docs/method.md, "One time step", convergence rules): 90 % of contacts with
  // |dR|^2 / |R_new + R_old|^2 < tol, the rest with |dR|^2 < tol <|R|>^2, and the summed normal
  // force changed by a relative^2 < tol.
  kForceChange,
  // Largest change of a contact's relative velocity in a sweep, dt |dR| / m_eff, below
  // velocity_tol (the probe, docs/probe.md, "The reference method": forces barely move there).
  kVelocityChange,
  // Static solve (v_free = 0): every grain's net force m |v| / dt and torque I |w| / (dt R)
  // below static_tol * F0 and |P_in / P_ext - 1| below static_tol; checked every check_every.
  kStatic,
};

// How a solve uses the threads. Serial and parallel sweeps give bit-identical results.
enum class Threading {
  kAuto,      // the faster mode as measured during the run (parallel only when it pays)
  kParallel,  // always parallel when there are enough contacts
  kSerial,
};

struct NlgsSettings {
  Convergence rule = Convergence::kForceChange;
  double tol = 1e-4;           // alpha of kForceChange
  double velocity_tol = 0.0;   // kVelocityChange threshold (length / time)
  double static_tol = 1e-8;    // kStatic threshold (relative to F0 and P_ext)
  double F0 = 1.0;             // force unit for kStatic
  // Over-relaxation factor omega of projected SOR: R <- proj(R_old + omega (R_gs - R_old)).
  // 1 is plain NLGS (the dynamics); 1 < omega < 2 speeds up static solves, whose fixed
  // point is the same.
  double relax = 1.0;
  int min_sweeps = 1;
  int max_sweeps = 200;
  int check_every = 20;        // sweeps between two kStatic residual evaluations
  std::uint64_t seed = 0;      // colouring and colour order
  Threading threading = Threading::kAuto;
};

struct NlgsResult {
  int sweeps = 0;
  bool converged = false;
  double lambda = 0.0;         // cell strain rate at t + dt
  double P_in = 0.0;           // internal pressure at t + dt (contact + kinetic part)
  double max_dU = 0.0;         // largest relative-velocity change in the last sweep
  double max_residual_F0 = 0.0;  // kStatic: largest grain force/torque residual / F0
  int num_colors = 0;
};

// Solves the step. In: particles' velocities are the free velocities v(t) (no body forces),
// contacts hold the warm-start forces. Out: velocities at t + dt, forces at t + dt.
NlgsResult solve_nlgs(const StepProblem& problem, const NlgsSettings& settings,
                      Contacts& contacts, Particles& particles);

}  // namespace unjam
