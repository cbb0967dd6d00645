#include "unjam/probe/probe_result.hpp"

#include <algorithm>

namespace unjam {

double contact_opening(const Packing& packing, const ProbeResult& r, int k) {
  const Contact& c = packing.contacts[k];
  return (r.u[c.b] - r.u[c.a]).dot(c.n) + r.lambda_dt * c.l.norm();
}

double step_inertia_force(const Packing& packing, const ProbeResult& r, double dt) {
  if (r.u.size() != packing.size() || r.residual == kNoSolution) return std::numeric_limits<double>::quiet_NaN();
  double f = 0.0;
  for (std::size_t i = 0; i < r.u.size(); ++i) f = std::max(f, packing.particles.mass(i) * r.u[i].norm());
  return f / (dt * dt);
}

GrainDisplacement grain_displacement(const ProbeResult& r) {
  GrainDisplacement f;
  f.u = r.u;
  f.rot = r.u_rot;
  f.contact = r.contact;
  for (const Vec2& u : r.u) f.u_over_g.push_back(u / r.g);
  return f;
}

}  // namespace unjam
