#include "unjam/ensemble/random_walk.hpp"

#include <algorithm>
#include <limits>
#include <random>

#include "unjam/contact/contact_problem.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/contact_model.hpp"
#include "unjam/solver/static_solve.hpp"
#include "unjam/solver/step_problem.hpp"

namespace unjam {

RandomWalkResult sample_random_walk(const Packing& packing, const EquilibriumSystem& system,
                                    const RandomWalkOptions& options) {
  if (options.samples < 1) throw Error("random walk: samples must be at least 1");
  if (!(options.kick >= 0.0)) throw Error("random walk: the kick amplitude must be >= 0");
  const int Nc = system.num_contacts();

  // The copy the solver relaxes: the same grains and cell, only the contacts of the set, in
  // the order of system.contacts (solve_static keeps the order), under the walk's contact
  // model (solve_static takes mu from the copy's metadata, P_ext and M_lambda from its bath).
  // Every contact of the set touches: the solve's touch gap covers the set
  // (touch_gap_covering).
  const ContactModel model = contact_model_of(packing, options.model);
  Packing work = packing;
  work.meta.contact = model;
  work.contacts.clear();
  for (const int c : system.contacts) work.contacts.push_back(packing.contacts[c]);
  StaticSolveSettings solve;
  solve.tol = options.tol;
  solve.max_sweeps = options.max_sweeps;
  solve.touch_gap = touch_gap_covering(work.contacts, model.touch_gap);
  const Bath bath = bath_of(model);
  NlgsThreading threading;  // measurements of Threading::kAuto, shared by the walk's solves

  RandomWalkResult result;
  double mean_fn0 = 0.0;  // <F_n> of the packing's network over the set
  for (const Contact& c : work.contacts) mean_fn0 += c.fn;
  mean_fn0 = Nc > 0 ? mean_fn0 / Nc : 0.0;
  result.kick_amplitude = options.kick * mean_fn0;

  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> kick(-result.kick_amplitude, result.kick_amplitude);
  ForceNetwork state{Eigen::VectorXd(Nc), Eigen::VectorXd(Nc)};
  for (int k = 0; k < Nc; ++k) {
    state.fn[k] = work.contacts[k].fn;
    state.ft[k] = work.contacts[k].ft;
  }

  // Welford running mean and variance of fn per contact.
  SampledForcesAccumulator stats(Nc);
  for (int step = 0; step < options.samples; ++step) {
    for (int k = 0; k < Nc; ++k) {
      work.contacts[k].fn = state.fn[k] + kick(rng);
      work.contacts[k].ft = state.ft[k] + kick(rng);
    }
    solve.seed = rng();
    const StaticSolveReport rep = solve_static(work, bath, solve, threading);
    result.sweeps += rep.sweeps;
    if (rep.converged) {
      for (int k = 0; k < Nc; ++k) {
        state.fn[k] = work.contacts[k].fn;
        state.ft[k] = work.contacts[k].ft;
      }
      ++result.samples;
      stats.add(state.fn);
      if (options.on_sample) options.on_sample(state);
    } else {
      ++result.failures;
    }
    if (options.progress) options.progress(step + 1, options.samples);
  }
  static_cast<SampledForces&>(result) = stats.result();
  return result;
}

}  // namespace unjam
