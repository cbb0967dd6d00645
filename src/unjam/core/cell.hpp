#pragma once
// The simulation cell: a rectangle [0, Lx) x [0, Ly), periodic in x and y.
// The pressure bath scales it isotropically, so a square cell stays square.
#include <cmath>

#include "unjam/core/vec2.hpp"

namespace unjam {

struct Cell {
  double Lx = 1.0;  // side lengths (units of R_max)
  double Ly = 1.0;

  double area() const { return Lx * Ly; }

  // The minimum image of a separation vector d: each component in [-L/2, L/2].
  Vec2 min_image(Vec2 d) const {
    d.x() -= Lx * std::nearbyint(d.x() / Lx);
    d.y() -= Ly * std::nearbyint(d.y() / Ly);
    return d;
  }

  // A position folded back into [0, Lx) x [0, Ly).
  Vec2 wrap(Vec2 r) const {
    r.x() -= Lx * std::floor(r.x() / Lx);
    r.y() -= Ly * std::floor(r.y() / Ly);
    if (r.x() >= Lx) r.x() = 0.0;  // floor round-off for r just below 0
    if (r.y() >= Ly) r.y() = 0.0;
    return r;
  }
};

}  // namespace unjam
