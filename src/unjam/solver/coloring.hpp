#pragma once
// Edge colouring of the contact graph. Contacts of one colour share no grain, so updating
// them one after the other or all at once gives the same result: a colour is a parallel
// batch that keeps the Gauss-Seidel character of the solver exactly, for any thread count.
#include <cstdint>
#include <vector>

#include "unjam/packing/contact.hpp"

namespace unjam {

struct Coloring {
  std::vector<int> order;        // contact indices grouped by colour
  std::vector<int> color_start;  // colour c holds order[color_start[c] .. color_start[c+1])
  int num_colors() const { return static_cast<int>(color_start.size()) - 1; }
};

// Greedy colouring: contacts are taken in a random order drawn from `seed` and each gets
// the lowest colour free at both of its grains. Within a colour, contacts are sorted by
// grain index for memory locality. Deterministic for a given seed.
Coloring color_contacts(const Contacts& contacts, int num_grains, std::uint64_t seed);

}  // namespace unjam
