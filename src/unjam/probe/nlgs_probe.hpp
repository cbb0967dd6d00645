#pragma once
// The paper's probe by plain contact dynamics (docs/probe.md, "The reference
// method"): one time step from
// the static packing (velocities zero, forces R0 as warm start, pressure bath on) in which
// the probed contact's Signorini condition is shifted by g: its surfaces must separate by g
// during the step (g_eff = -g; friction as usual). Every other touching pair keeps
// g_eff = 0 (gap below the contact model's touch_gap), the rest their gap.
// F_crit is the probed contact's normal force once the step has converged; convergence is
// judged on the largest change of a contact's relative velocity in a sweep against g / dt,
// since forces change by only ~1e-9 relative at first. This is the reference method: its
// cost grows like (L/d)^2 sweeps and more, see kinematic_probe.hpp for the fast route.
#include <cstdint>
#include <functional>
#include <optional>

#include <Eigen/Core>

#include "unjam/packing/contact_model.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/probe/probe_result.hpp"

namespace unjam {

struct ProbeSettings {
  double g = 1e-9;             // prescribed opening (R_max)
  // The probe step's time step (t0; probe --dt): inertia ~ m g / dt^2 is its error. The
  // nlgs, lemke and cd probes take it once, into ContactProblem::dt (build_contact_problem).
  double dt = 1e-3;
  double velocity_tol = 1e-6;  // converged when max |dU| in a sweep < velocity_tol g / dt
  long long max_sweeps = 10'000'000;
  int min_sweeps = 100;
  bool bath = true;            // the pressure bath stays on during the probe
  std::uint64_t seed = 0;
  // mu, P_ext, M_lambda, touch_gap of the step; empty: the packing's own (packing.meta.contact)
  std::optional<ContactModel> model;
  // > 0 (lemke and cd only): the step restricted to a window, the grains within `window`
  // mean diameters of the probed pair's midpoint, every other grain clamped to the cell
  // (probe/cd_step.hpp, window_step; docs/probe.md, "A window around the probed pair"). It
  // changes what is measured: F_crit of the clamped window, not of the packing. 0: the whole
  // packing (the nlgs probe refuses any other value).
  double window = 0.0;
  // Polled by the long probes at cheap points (nlgs: every 16 sweeps; cd: every piece of its
  // path); once it returns true the probe throws Cancelled (core/error.hpp). Called from the
  // probe's thread: thread safe where probes run in parallel. Empty: never. Not a setting of
  // the step (not recorded with the others).
  std::function<bool()> cancel;
};

// Probes contact `contact` of a static packing (not modified). The step is the packing's
// ContactProblem (contact/contact_problem.hpp) under contact_model_of(packing,
// settings.model) and time step settings.dt, with g_eff = -settings.g on the probed contact.
// Throws Cancelled once settings.cancel returns true.
ProbeResult probe_nlgs(const Packing& packing, int contact, const ProbeSettings& settings);

// The same, and the forces of the step's solution in f = (fn_0, ft_0, fn_1, ...), in the
// order of packing.contacts (the columns of the ContactProblem), for step_residual.
ProbeResult probe_nlgs(const Packing& packing, int contact, const ProbeSettings& settings,
                       Eigen::VectorXd& f);

}  // namespace unjam
