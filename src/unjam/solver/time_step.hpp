#pragma once
// One Moreau-Jean time step of the packing (docs/method.md, "One time step"):
//   detect contacts at r(t) -> solve the contact problem (NLGS) for the forces at t+dt,
//   v(t+dt) and lambda(t+dt) -> L(t+dt) = L(t) (1 + lambda dt),
//   r(t+dt) = r(t) (1 + lambda(t+dt) dt) + dt v(t+dt).
#include "unjam/packing/packing.hpp"
#include "unjam/solver/nlgs.hpp"

namespace unjam {

struct DynamicsSettings {
  double dt = 0.01;             // the compaction's time step (simulation time units; pack --dt)
  Bath bath;
  NlgsSettings nlgs;            // its seed is mixed with the step number every step
  double min_detection = 0.01;  // smallest detection distance (units of R_max)
};

struct StepReport {
  int sweeps = 0;
  bool converged = false;
  double P_in = 0.0;
  double detection = 0.0;       // detection distance used
  int num_contacts = 0;         // pairs in the solver's list
  int num_colors = 0;
};

// Advances the packing by one step; packing.contacts holds the contact list of the step
// (geometry at t, forces at t+dt) afterwards. `threading` holds the measurements of
// Threading::kAuto (nlgs.hpp); a loop of steps passes the same object to every step.
StepReport advance(Packing& packing, const DynamicsSettings& settings, NlgsThreading& threading);
// One step with measurements of its own (kAuto learns within the step only).
StepReport advance(Packing& packing, const DynamicsSettings& settings);

}  // namespace unjam
