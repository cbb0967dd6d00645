#include "unjam/solver/coloring.hpp"

#include <algorithm>
#include <bit>
#include <numeric>
#include <random>

#include "unjam/core/error.hpp"

namespace unjam {

Coloring color_contacts(const Contacts& contacts, int num_grains, std::uint64_t seed) {
  const int nc = static_cast<int>(contacts.size());
  std::vector<int> visit(nc);
  std::iota(visit.begin(), visit.end(), 0);
  std::mt19937_64 rng(seed);
  std::shuffle(visit.begin(), visit.end(), rng);

  // used[i]: bit c set when grain i already has a contact of colour c.
  std::vector<std::uint64_t> used(num_grains, 0);
  std::vector<int> color(nc);
  int num_colors = 0;
  for (const int k : visit) {
    const Contact& c = contacts[k];
    const std::uint64_t taken = used[c.a] | used[c.b];
    if (taken == ~std::uint64_t{0}) throw Error("contact colouring: a grain has more than 64 near neighbours");
    const int col = std::countr_one(taken);
    color[k] = col;
    used[c.a] |= std::uint64_t{1} << col;
    used[c.b] |= std::uint64_t{1} << col;
    num_colors = std::max(num_colors, col + 1);
  }

  Coloring out;
  out.color_start.assign(num_colors + 1, 0);
  for (int k = 0; k < nc; ++k) ++out.color_start[color[k] + 1];
  std::partial_sum(out.color_start.begin(), out.color_start.end(), out.color_start.begin());
  out.order.resize(nc);
  std::vector<int> fill(out.color_start.begin(), out.color_start.end() - 1);
  for (int k = 0; k < nc; ++k) out.order[fill[color[k]]++] = k;  // k ascending: sorted by (a, b)
  return out;
}

}  // namespace unjam
