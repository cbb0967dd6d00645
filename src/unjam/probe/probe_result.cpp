#include "unjam/probe/probe_result.hpp"

namespace unjam {

double contact_opening(const Packing& packing, const ProbeResult& r, int k) {
  const Contact& c = packing.contacts[k];
  return (r.u[c.b] - r.u[c.a]).dot(c.n) + r.lambda_dt * c.l.norm();
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
