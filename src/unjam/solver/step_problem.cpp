#include "unjam/solver/step_problem.hpp"

#include <algorithm>

namespace unjam {

std::vector<double> positive_gaps(const Contacts& contacts) {
  std::vector<double> g(contacts.size());
  for (std::size_t k = 0; k < contacts.size(); ++k) g[k] = std::max(contacts[k].gap, 0.0);
  return g;
}

std::vector<double> touching_gaps(const Contacts& contacts, double touch_gap) {
  std::vector<double> g(contacts.size());
  for (std::size_t k = 0; k < contacts.size(); ++k)
    g[k] = contacts[k].gap < touch_gap ? 0.0 : contacts[k].gap;
  return g;
}

}  // namespace unjam
