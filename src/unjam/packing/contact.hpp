#pragma once
// One contact of the packing: the plain data shared by the solvers, the static checks,
// the linear programs and the probe (one row of contacts.csv).
//
// Sign conventions (docs/method.md, "Model and units"):
//   l = r_b - r_a (minimum image), n = l / |l|, t = (-n_y, n_x),
//   gap = |l| - R_a - R_b (negative: overlap),
//   the force on b is fn n + ft t, the force on a is -(fn n + ft t); fn >= 0 is compressive,
//   torques: T_a = -R_a ft, T_b = -R_b ft.
#include <cmath>
#include <vector>

#include "unjam/core/vec2.hpp"

namespace unjam {

struct Contact {
  int a = 0, b = 0;
  Vec2 n = Vec2::Zero();
  Vec2 l = Vec2::Zero();
  double gap = 0.0;
  double fn = 0.0;
  double ft = 0.0;

  Vec2 t() const { return tangent(n); }
  Vec2 force_on_b() const { return fn * n + ft * t(); }
};

using Contacts = std::vector<Contact>;

// State of a contact with forces (fn, ft): open (fn = 0), sliding (mu > 0 and |ft| = mu fn > 0)
// or closed (fn > 0 and |ft| < mu fn, or mu = 0). `tol` is an absolute force tolerance: open
// if fn <= tol, sliding if mu fn - |ft| <= tol. The one classification of a contact in a force
// network: the polish's active set (solver/force_polish), the kinematic probe's (through
// lp/force_lp's contact_states) and the export's state column take it; a sliding contact's
// direction is the sign of ft.
enum class ContactState { closed, sliding, open };

inline ContactState contact_state(double fn, double ft, double mu, double tol) {
  if (fn <= tol) return ContactState::open;
  if (mu > 0.0 && mu * fn - std::abs(ft) <= tol) return ContactState::sliding;
  return ContactState::closed;
}

}  // namespace unjam
