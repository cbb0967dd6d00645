#include "unjam/probe/probe_result.hpp"

namespace unjam {

double contact_opening(const Packing& packing, const ProbeResult& r, int k) {
  const Contact& c = packing.contacts[k];
  return (r.u[c.b] - r.u[c.a]).dot(c.n) + r.lambda_dt * c.l.norm();
}

}  // namespace unjam
