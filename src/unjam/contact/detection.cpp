#include "unjam/contact/detection.hpp"

#include <algorithm>

#include "unjam/contact/neighbor_grid.hpp"

namespace unjam {
namespace {

void set_geometry(const Particles& p, const Cell& cell, Contact& c) {
  c.l = cell.min_image(p.position(c.b) - p.position(c.a));
  const double len = c.l.norm();
  c.n = c.l / len;
  c.gap = len - p.radius[c.a] - p.radius[c.b];
}

}  // namespace

Contacts detect_contacts(const Particles& particles, const Cell& cell, double max_gap,
                         const Contacts& previous) {
  const auto pairs = find_near_pairs(particles, cell, max_gap);
  Contacts contacts(pairs.size());
  auto old = previous.begin();
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    Contact& c = contacts[k];
    c.a = pairs[k].first;
    c.b = pairs[k].second;
    set_geometry(particles, cell, c);
    // Merge walk over the two sorted lists: carry the force of a surviving pair.
    while (old != previous.end() && std::make_pair(old->a, old->b) < pairs[k]) ++old;
    if (old != previous.end() && old->a == c.a && old->b == c.b) {
      c.fn = old->fn;
      c.ft = old->ft;
    }
  }
  return contacts;
}

void update_contact_geometry(const Particles& particles, const Cell& cell, Contacts& contacts) {
  for (Contact& c : contacts) set_geometry(particles, cell, c);
}

}  // namespace unjam
