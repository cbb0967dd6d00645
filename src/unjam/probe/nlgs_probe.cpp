#include "unjam/probe/nlgs_probe.hpp"

#include <algorithm>

#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/error.hpp"
#include "unjam/solver/nlgs.hpp"

namespace unjam {

ProbeResult probe_nlgs(const Packing& packing, int contact, const ProbeSettings& set) {
  Eigen::VectorXd f;
  return probe_nlgs(packing, contact, set, f);
}

ProbeResult probe_nlgs(const Packing& packing, int contact, const ProbeSettings& set,
                       Eigen::VectorXd& f) {
  if (contact < 0 || contact >= static_cast<int>(packing.contacts.size()))
    throw Error("contact " + std::to_string(contact) + " does not exist (the packing has " +
                std::to_string(packing.contacts.size()) + ")");
  if (set.window != 0.0)  // the setting of the exact steps (build_cd_step), not of this one
    throw Error("the nlgs probe solves the whole packing's step; a window applies to the exact methods (cd, lemke)");
  Contacts contacts = packing.contacts;
  Particles particles = packing.particles;

  const ContactProblem problem =
      build_contact_problem(packing, contact_model_of(packing, set.model), set.dt);
  StepProblem pb = step_problem(problem);
  pb.bath.enabled = set.bath;
  pb.g_eff[contact] = -set.g;
  const double dt = pb.dt;  // set.dt, as build_contact_problem took it: the one dt of the step

  NlgsSettings nlgs;
  nlgs.rule = Convergence::kVelocityChange;
  nlgs.velocity_tol = set.velocity_tol * set.g / dt;
  nlgs.min_sweeps = set.min_sweeps;
  nlgs.seed = set.seed;
  nlgs.cancel = set.cancel;

  ProbeResult r;
  r.contact = contact;
  r.a = contacts[contact].a;
  r.b = contacts[contact].b;
  r.f_cont = contacts[contact].fn;
  r.g = set.g;
  // NLGS sweeps are counted in int: run in chunks, each warm-started from the last, with
  // the velocities reset to the free velocities (zero) before every chunk.
  constexpr int kChunk = 1'000'000;
  NlgsThreading threading;  // the probe's chunks share the measurements of Threading::kAuto
  NlgsResult res;
  while (r.sweeps < set.max_sweeps) {
    particles.stop();
    nlgs.max_sweeps = static_cast<int>(std::min<long long>(kChunk, set.max_sweeps - r.sweeps));
    nlgs.seed = set.seed + static_cast<std::uint64_t>(r.sweeps);
    res = solve_nlgs(pb, nlgs, contacts, particles, threading);
    r.sweeps += res.sweeps;
    if (res.converged) break;
  }
  r.converged = res.converged;
  r.residual = res.max_dU / (set.g / dt);
  r.f_crit = contacts[contact].fn;
  r.lambda_dt = res.lambda * dt;
  f.resize(2 * static_cast<Eigen::Index>(contacts.size()));
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    f[2 * k] = contacts[k].fn;
    f[2 * k + 1] = contacts[k].ft;
  }
  r.u.resize(particles.size());
  r.u_rot.resize(particles.size());
  for (std::size_t i = 0; i < particles.size(); ++i) {
    r.u[i] = dt * particles.velocity(i);
    r.u_rot[i] = dt * particles.omega[i];
  }
  r.f_inertia = step_inertia_force(packing, r, dt);
  return r;
}

}  // namespace unjam
