#pragma once
// What a local perturbation probe measures (docs/probe.md, "The probe").
#include <limits>
#include <vector>

#include "unjam/core/vec2.hpp"
#include "unjam/packing/export.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam {

struct ProbeResult {
  int contact = -1;            // index into packing.contacts
  int a = -1, b = -1;          // its grains
  double f_cont = 0.0;         // normal force of the static packing (simulation units)
  double f_crit = 0.0;         // normal force needed to open the contact by g
  double g = 0.0;              // the prescribed opening
  double lambda_dt = 0.0;      // affine strain of the cell during the probe, lambda dt
  std::vector<Vec2> u;         // peculiar displacement of every grain (length units)
  std::vector<double> u_rot;   // rotation of every grain (radians)
  // nlgs: the convergence rule was met; lp: no unilateral condition left broken
  // (violations == 0); lemke and cd: the step's residual within its tolerance.
  bool converged = false;
  long long sweeps = 0;        // NLGS sweeps (0 for the kinematic probe)
  // nlgs: largest relative-velocity change of the last sweep / (g / dt);
  // lp: largest violation of the field's equality constraints / g (0: exactly compatible).
  double residual = 0.0;
  int violations = 0;          // lp: unilateral conditions its field still breaks
  // The largest net force on one grain over the step, max_i m_i |u_i| / dt^2 (simulation
  // force units): the load carried by the grains' inertia instead of by the contacts
  // (step_inertia_force). Quasi-static: ~ m g / dt^2, falling as dt^-2 with the field fixed;
  // a region that slides away carries an unbalanced force that does not fall with dt, and
  // its field grows as dt^2 (docs/probe.md, "The inertia of the step"). NaN for lp (no
  // dynamics) and for a probe without a solution.
  double f_inertia = std::numeric_limits<double>::quiet_NaN();
  // lemke and cd: of the contacts loaded in the packing (fn > 1e-6 F0, the probed one aside),
  // those the step opens and those it sets sliding (probe/cd_step, step_state_changes;
  // docs/probe.md, "Which contacts the step opens and sets sliding"). -1 where not known
  // (lp, nlgs, a probe without a solution).
  int opened = -1, sliding = -1;
  // CPU time the probe took on the thread that computed it (s; core/cpu_time), set by the
  // campaigns and probe lists (probe/probe_campaign); NaN where not measured. Never a result:
  // it differs from run to run, so it stays out of probes.csv and of a checkpoint's hashed
  // state (docs/probe.md, "Campaigns").
  double cpu_seconds = std::numeric_limits<double>::quiet_NaN();
};

// The residual of a probe whose solver found no solution (lemke: its path ended on a ray).
// Such a probe has no F_crit and no field: campaigns list it but leave it out of the means.
inline constexpr double kNoSolution = std::numeric_limits<double>::max();

// Normal opening of packing.contacts[k] over the probe: (u_b - u_a) . n + lambda dt |l|
// (the cell's affine strain stretches the branch vector l; length units). The probed pair
// must open by g, a touching pair must not go below zero.
double contact_opening(const Packing& packing, const ProbeResult& r, int k);

// max_i m_i |u_i| / dt^2 over the grains of the probe's field (ProbeResult::f_inertia); NaN
// for a probe without a field.
double step_inertia_force(const Packing& packing, const ProbeResult& r, double dt);

// The probe's field for the exports (packing/export.hpp): u, u / g and the rotations.
GrainDisplacement grain_displacement(const ProbeResult& r);

}  // namespace unjam
