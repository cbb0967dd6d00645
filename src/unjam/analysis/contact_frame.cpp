#include "unjam/analysis/contact_frame.hpp"

#include <stdexcept>

namespace unjam {

ContactFrame contact_frame(const Particles& particles, const Contact& c) {
  ContactFrame f;
  f.n = c.n;
  f.t = tangent(c.n);
  f.origin = particles.position(c.a) + particles.radius[c.a] * c.n;
  return f;
}

void to_contact_frame(const ContactFrame& frame, const Cell& cell, std::span<const double> x,
                      std::span<const double> y, std::span<const Vec2> u, FrameField& out) {
  const std::size_t N = x.size();
  if (y.size() != N || u.size() != N)
    throw std::invalid_argument("to_contact_frame: positions and displacements differ in length");
  out.x.resize(N);
  out.y.resize(N);
  out.ux.resize(N);
  out.uy.resize(N);
  for (std::size_t i = 0; i < N; ++i) {
    const Vec2 d = frame.position(cell, Vec2(x[i], y[i]));
    const Vec2 u_frame = frame.rotate(u[i]);
    out.x[i] = d.x();
    out.y[i] = d.y();
    out.ux[i] = u_frame.x();
    out.uy[i] = u_frame.y();
  }
}

}  // namespace unjam
