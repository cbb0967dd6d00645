#pragma once
// The contact frame of a probed contact (docs/analysis.md, "Contact frame"; the
// paper's Fig. 1).
//
// For the probed contact c = (a, b) with normal n (from a to b, the direction in which the
// probe separates the pair) and tangent t = (-n_y, n_x):
//   origin  r_c = r_a + R_a n   (the point of a's surface facing b; with an overlap delta
//                                the centre of the overlap lies delta/2 closer to a, a shift
//                                of O(1e-9) that no bin resolves),
//   x axis  along n,  y axis along t  (a right-handed frame: n x t = 1).
// A grain at lab position r_i with lab displacement u_i has frame coordinates
//   d_i = min_image(r_i - r_c),   x_i = d_i . n,   y_i = d_i . t,
//   ux_i = u_i . n,               uy_i = u_i . t.
// Grain a sits at (-R_a, 0), grain b at (|l| - R_a, 0), so x > 0 is b's side.
#include <span>
#include <vector>

#include "unjam/core/cell.hpp"
#include "unjam/core/vec2.hpp"
#include "unjam/packing/contact.hpp"
#include "unjam/packing/particles.hpp"

namespace unjam {

struct ContactFrame {
  Vec2 origin = Vec2::Zero();  // r_c, lab frame (need not lie inside the cell)
  Vec2 n = Vec2::UnitX();      // frame x axis, unit
  Vec2 t = Vec2::UnitY();      // frame y axis, t = (-n_y, n_x)

  // Components (v . n, v . t) of a lab vector v: a rotation by -angle(n).
  Vec2 rotate(const Vec2& v) const { return {v.dot(n), v.dot(t)}; }
  // Frame coordinates of a lab position r: rotate(min_image(r - r_c)).
  Vec2 position(const Cell& cell, const Vec2& r) const { return rotate(cell.min_image(r - origin)); }
};

// The frame of contact c: origin r_a + R_a n, axes c.n and t(c.n) (c.n as stored, unit).
ContactFrame contact_frame(const Particles& particles, const Contact& c);

// Every grain of one probe in the contact frame, structure of arrays: position (x, y)
// relative to r_c (length units, R_max = 1) and displacement (ux, uy) (the units of the input).
struct FrameField {
  std::vector<double> x, y;
  std::vector<double> ux, uy;

  std::size_t size() const { return x.size(); }
};

// Maps grains i = 0 .. x.size()-1 (lab positions (x[i], y[i]), e.g. Particles::x and y; lab
// displacements u[i], e.g. ProbeResult::u) into `frame`; `out` is resized and overwritten
// (reuse it across probes to avoid allocations). Throws std::invalid_argument if the spans
// differ in length.
void to_contact_frame(const ContactFrame& frame, const Cell& cell, std::span<const double> x,
                      std::span<const double> y, std::span<const Vec2> u, FrameField& out);

}  // namespace unjam
