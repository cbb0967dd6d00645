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
#include <functional>

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

// How a solve uses the threads (docs/method.md, "Threading of the sweeps"). Serial and
// parallel sweeps give bit-identical results, so the policy changes the run time only.
enum class Threading {
  kAuto,      // the faster mode as measured by the caller's NlgsThreading (parallel only when it pays)
  kParallel,  // always parallel when there are enough contacts
  kSerial,
};

// The measurements Threading::kAuto chooses from, owned by the caller (docs/method.md,
// "Threading of the sweeps"): the cost of one contact update in each mode, in ns, as
// exponential moving averages avg <- 0.7 avg + 0.3 ns (0 while unknown). A caller that runs
// many solves (a compaction's time steps and static attempts, a probe's chunks) passes the
// same object to all of them; solves given different objects do not influence each other.
// One object serves one thread at a time.
class NlgsThreading {
 public:
  // Parallel when it has been measured faster; each mode is measured first (parallel, then
  // serial), and the slower one is tried again every 32nd choice, since the load changes.
  bool choose_parallel();
  // Folds one measured cost per contact update (ns) into the mode's average.
  void record(bool parallel, double ns_per_update);
  // Parallel sweeps cost more than 1.5 times the serial ones measured before.
  bool parallel_is_slow() const;

 private:
  double ns_serial_ = 0.0, ns_parallel_ = 0.0;
  int choices_ = 0;
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
  // Polled every 16 sweeps, between the parallel regions; once it returns true, solve_nlgs
  // throws Cancelled (core/error.hpp) and the contacts and particles hold no result. Called
  // from the solving thread: thread safe if several solves share it. Empty: never.
  std::function<bool()> cancel;
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
// `threading` records the measured costs of every solve large enough to run in parallel
// (unless settings.threading is kSerial) and is read under kAuto only; the result does not
// depend on it. Throws Cancelled once settings.cancel returns true.
NlgsResult solve_nlgs(const StepProblem& problem, const NlgsSettings& settings,
                      Contacts& contacts, Particles& particles, NlgsThreading& threading);

}  // namespace unjam
