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
    g[k] = classify_contact(contacts[k], touch_gap, 0.0).touching ? 0.0 : contacts[k].gap;
  return g;
}

StepProblem step_problem(const ContactProblem& problem) {
  StepProblem pb;
  pb.cell = problem.cell;
  pb.dt = problem.dt;
  pb.mu = problem.model.mu;
  pb.bath = bath_of(problem.model);
  pb.lambda_t = 0.0;
  pb.g_eff.assign(problem.g_eff.data(), problem.g_eff.data() + problem.g_eff.size());
  return pb;
}

}  // namespace unjam
