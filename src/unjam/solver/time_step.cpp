#include "unjam/solver/time_step.hpp"

#include <algorithm>
#include <cmath>

#include "unjam/contact/detection.hpp"

namespace unjam {

StepReport advance(Packing& p, const DynamicsSettings& set) {
  NlgsThreading threading;
  return advance(p, set, threading);
}

StepReport advance(Packing& p, const DynamicsSettings& set, NlgsThreading& threading) {
  Particles& P = p.particles;
  const double dt = set.dt;
  const std::size_t n = P.size();

  // Detection distance: twice the largest approach of two grains within one step, so no
  // pair can close unseen; the affine part |lambda| l and its change within the step count.
  double v_max = 0.0;
  for (std::size_t i = 0; i < n; ++i) v_max = std::max(v_max, std::hypot(P.vx[i], P.vy[i]));
  const double R_max = *std::max_element(P.radius.begin(), P.radius.end());
  const double lambda_bound = std::abs(p.state.lambda) + dt * set.bath.P_ext / set.bath.M_lambda;
  const double approach = 2.0 * v_max + lambda_bound * (2.0 * R_max + set.min_detection);
  StepReport rep;
  rep.detection = std::max(set.min_detection, 2.0 * dt * approach);
  p.contacts = detect_contacts(P, p.cell, rep.detection, p.contacts);

  StepProblem pb{p.cell, dt, p.meta.contact.mu, set.bath, p.state.lambda, positive_gaps(p.contacts)};
  NlgsSettings nlgs = set.nlgs;
  nlgs.seed = set.nlgs.seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(p.state.step);
  const NlgsResult res = solve_nlgs(pb, nlgs, p.contacts, P, threading);

  // Affine scaling of the cell and of every position, then the peculiar displacement.
  const double scale = 1.0 + res.lambda * dt;
  p.cell.Lx *= scale;
  p.cell.Ly *= scale;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 r = p.cell.wrap({P.x[i] * scale + dt * P.vx[i], P.y[i] * scale + dt * P.vy[i]});
    P.x[i] = r.x();
    P.y[i] = r.y();
  }
  p.state.lambda = res.lambda;
  p.state.time += dt;
  ++p.state.step;

  rep.sweeps = res.sweeps;
  rep.converged = res.converged;
  rep.P_in = res.P_in;
  rep.num_contacts = static_cast<int>(p.contacts.size());
  rep.num_colors = res.num_colors;
  return rep;
}

}  // namespace unjam
