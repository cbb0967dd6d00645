#pragma once
// Builds the contact list of a step: every near pair becomes a Contact with its current
// geometry (l, n, gap). Forces of pairs that were in the previous list are carried over,
// which warm-starts the solver; new pairs start at zero force.
#include "unjam/core/cell.hpp"
#include "unjam/packing/contact.hpp"
#include "unjam/packing/particles.hpp"

namespace unjam {

// Contacts for all pairs with gap < max_gap, sorted by (a, b) with a < b.
// `previous` must be sorted by (a, b) with a < b too (as this function returns it).
Contacts detect_contacts(const Particles& particles, const Cell& cell, double max_gap,
                         const Contacts& previous);

// Recomputes l, n and gap of existing contacts from the current positions (fixed list).
void update_contact_geometry(const Particles& particles, const Cell& cell, Contacts& contacts);

}  // namespace unjam
