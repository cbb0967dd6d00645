#pragma once
// The contact model of a packing and the one rule that says which of its contacts count
// (docs/method.md, "Which contacts count").
//
// Every contact problem of a packing (the static solve, the probes, the LP bounds, the
// samplers) is built from the same physical parameters, its ContactModel, and classifies the
// packing's contacts by the same rule, classify_contact. Where consumers differ, they differ
// only in the named arguments they pass to it (a touch tolerance, a force threshold).
#include <algorithm>

#include "unjam/packing/contact.hpp"

namespace unjam {

struct ContactModel {
  double mu = 0.0;          // Coulomb friction coefficient
  double P_ext = 1.0;       // external pressure of the bath (pressure unit)
  double M_lambda = 100.0;  // bath mass (mass per area; docs/method.md, "The cell strain rate")
  double touch_gap = 1e-6;  // a pair with gap < touch_gap touches (length, units of R_max)

  friend bool operator==(const ContactModel&, const ContactModel&) = default;
};

// `model` with another touch tolerance (length, units of R_max): the model of a consumer that
// counts contacts by its own gap option (bounds, ensemble: --gap-tol).
inline ContactModel with_touch_gap(ContactModel model, double touch_gap) {
  model.touch_gap = touch_gap;
  return model;
}

// The state of one contact of a static packing:
//   touching:  gap < touch_gap (overlaps, gap < 0, included): it may carry force without the
//              grains moving (g_eff = 0 in a step, docs/method.md, "Touching pairs");
//   loaded:    fn > fn_min (force units): it carries force in the packing's network.
struct ContactClass {
  bool touching = false;
  bool loaded = false;
};

inline ContactClass classify_contact(const Contact& c, double touch_gap, double fn_min) {
  return {c.gap < touch_gap, c.fn > fn_min};
}

// The touch tolerance under which every contact of `set` touches: touch_gap, or twice the
// largest gap of the set if that is larger (a solve restricted to an admissible set, such as
// the random walk's, must let every contact of the set carry force).
inline double touch_gap_covering(const Contacts& set, double touch_gap) {
  double max_gap = 0.0;
  for (const Contact& c : set) max_gap = std::max(max_gap, c.gap);
  return std::max(touch_gap, 2.0 * max_gap);
}

}  // namespace unjam
