#include "unjam/solver/static_solve.hpp"

#include <algorithm>
#include <cmath>

#include "unjam/contact/detection.hpp"
#include "unjam/solver/force_polish.hpp"
#include "unjam/solver/nlgs.hpp"

namespace unjam {
namespace {

void set_at_rest(Packing& p) {
  p.particles.stop();
  p.state.lambda = 0.0;
}

}  // namespace

StaticSolveReport solve_static(Packing& p, const Bath& bath, const StaticSolveSettings& set) {
  NlgsThreading threading;
  return solve_static(p, bath, set, threading);
}

StaticSolveReport solve_static(Packing& p, const Bath& bath, const StaticSolveSettings& set,
                               NlgsThreading& threading) {
  update_contact_geometry(p.particles, p.cell, p.contacts);
  const StepProblem pb{p.cell, set.dt, p.meta.contact.mu, bath, 0.0, touching_gaps(p.contacts, set.touch_gap)};

  NlgsSettings nlgs;
  nlgs.rule = Convergence::kStatic;
  nlgs.F0 = p.force_unit();
  nlgs.check_every = set.check_every;
  nlgs.relax = set.relax;

  StaticSolveReport rep;
  double target = set.polish_from > 0.0 ? std::max(set.polish_from, set.tol) : set.tol;
  for (int round = 0; rep.sweeps < set.max_sweeps; ++round) {
    set_at_rest(p);  // v_free = 0; the forces of the last round are the warm start
    nlgs.static_tol = target;
    nlgs.max_sweeps = set.max_sweeps - rep.sweeps;
    nlgs.seed = set.seed + static_cast<std::uint64_t>(round);
    const NlgsResult res = solve_nlgs(pb, nlgs, p.contacts, p.particles, threading);
    rep.sweeps += res.sweeps;
    rep.max_residual_F0 = res.max_residual_F0;
    rep.pressure_error = std::abs(res.P_in / bath.P_ext - 1.0);
    if (!res.converged) break;
    if (target <= set.tol) {
      rep.converged = true;
      break;
    }
    if (set.polish_from > 0.0) {
      const PolishResult pol =
          polish_forces(p, set.tol, with_touch_gap(p.meta.contact, set.touch_gap));
      if (pol.success) {
        rep.converged = rep.polished = true;
        rep.max_residual_F0 = pol.max_residual_F0;
        rep.pressure_error = pol.pressure_error;
        break;
      }
    }
    target = std::max(set.tol, 0.1 * target);
  }
  set_at_rest(p);
  return rep;
}

}  // namespace unjam
