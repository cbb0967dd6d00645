#include "unjam/ensemble/force_bounds.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <omp.h>

#include "unjam/core/error.hpp"
#include "unjam/core/work_source.hpp"

namespace unjam {

namespace {

// One LP's outcome as it travels to the gathering process: its optimum, the solver's
// iterations, whether it was loosened, finished by simplex or solved again unscaled, the
// contacts its optimal network opens (fn <= open_tol; only from LPs solved at the requested
// tolerance), and the whole network if asked for.
struct LpOutcome {
  bool skipped = false;  // phase 2: the contact was already known to open, no LP
  double value = 0.0;
  long long iterations = 0;
  bool loosened = false;
  bool simplex_finished = false, unscaled = false;
  std::vector<int> opened;
  std::vector<double> fn, ft;  // keep_networks_at_max
};

std::string encode(const LpOutcome& o) {
  ByteWriter w;
  w.put(o.skipped).put(o.value).put(o.iterations).put(o.loosened).put(o.simplex_finished).put(o.unscaled);
  w.put_array(o.opened.data(), o.opened.size());
  w.put_array(o.fn.data(), o.fn.size()).put_array(o.ft.data(), o.ft.size());
  return w.take();
}

LpOutcome decode(const std::string& bytes) {
  ByteReader r(bytes);
  LpOutcome o;
  o.skipped = r.get<bool>();
  o.value = r.get<double>();
  o.iterations = r.get<long long>();
  o.loosened = r.get<bool>();
  o.simplex_finished = r.get<bool>();
  o.unscaled = r.get<bool>();
  o.opened = r.get_array<int>();
  o.fn = r.get_array<double>();
  o.ft = r.get_array<double>();
  return o;
}

// Solves one LP with `lp` (solve returns its optimum) and describes the outcome.
template <class Solve>
LpOutcome solve_lp(ForceLP& lp, double open_tol, bool keep_network, Solve solve) {
  const long long before = lp.iterations(), finishes = lp.simplex_finishes(), unscaled = lp.unscaled_solves();
  LpOutcome o;
  o.value = solve(lp);
  o.iterations = lp.iterations() - before;
  o.simplex_finished = lp.simplex_finishes() > finishes;
  o.unscaled = lp.unscaled_solves() > unscaled;
  o.loosened = lp.last_solve_loosened();
  if (o.loosened && !keep_network) return o;
  const ForceNetwork net = lp.network();
  if (!o.loosened)
    for (Eigen::Index j = 0; j < net.fn.size(); ++j)
      if (net.fn[j] <= open_tol) o.opened.push_back(static_cast<int>(j));
  if (keep_network) {
    o.fn.assign(net.fn.data(), net.fn.data() + net.fn.size());
    o.ft.assign(net.ft.data(), net.ft.data() + net.ft.size());
  }
  return o;
}

}  // namespace

void check_force_bounds_options(const ForceBoundsOptions& options) {
  check_lp_tolerance(options.tolerance, "force bounds: ");
  char why[96];
  if (!(options.open_tol_F0 > 0.0 && options.open_tol_F0 <= kMaxOpenTolF0)) {
    std::snprintf(why, sizeof why, "the open tolerance must be in (0, %g] F0 (got %g)", kMaxOpenTolF0,
                  options.open_tol_F0);
    throw Error(std::string("force bounds: ") + why);
  }
}

ForceBounds compute_force_bounds(const EquilibriumSystem& system,
                                 const ForceBoundsOptions& options) {
  LocalDistributor local;
  return compute_force_bounds(system, options, local);
}

ForceBounds compute_force_bounds(const EquilibriumSystem& system, const ForceBoundsOptions& options,
                                 WorkDistributor& distributor) {
  check_force_bounds_options(options);
  const auto t_start = std::chrono::steady_clock::now();
  const int Nc = system.num_contacts();
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  ForceBounds bounds;
  bounds.fn_min = Eigen::VectorXd::Constant(Nc, unknown);
  bounds.fn_max = Eigen::VectorXd::Constant(Nc, unknown);
  if (options.keep_networks_at_max) bounds.network_at_max.resize(Nc);
  const double open_tol = options.open_tol_F0 * system.F0;
  const ForceBounds* resume = options.resume;
  if (resume && (options.keep_networks_at_max || resume->fn_min.size() != Nc || resume->fn_max.size() != Nc))
    throw Error("force bounds: the partial result to resume from is of another contact set");

  const ForceLP base(system, options.method, options.tolerance);  // throws if the set is empty
  bounds.iterations = base.iterations();
  int done = 0;
  if (resume) {
    bounds.fn_min = resume->fn_min;
    bounds.fn_max = resume->fn_max;
    bounds.iterations = resume->iterations;
    bounds.loosened_solves = resume->loosened_solves;
    bounds.simplex_finishes = resume->simplex_finishes;
    bounds.unscaled_solves = resume->unscaled_solves;
    bounds.min_lps_skipped = resume->min_lps_skipped;
    done = static_cast<int>(Nc - bounds.fn_min.array().isNaN().count() + Nc - bounds.fn_max.array().isNaN().count());
  }
  const int total = 2 * Nc;  // LPs, the minima certified without one counted as done
  const int threads = std::max(1, options.threads);
  // Contiguous chunks for the simplex (neighbouring contacts share grains: the previous
  // optimum is a good start); one LP at a time for the barrier, which starts from scratch.
  const int chunk = options.method == LpMethod::simplex ? 16 : 1;
  // `opened`: contacts some admissible network (an LP optimum at the requested tolerance)
  // leaves open, fn <= open_tol: their fn_min is 0 without an LP of their own. The gathering
  // process knows every network; each process also marks those of its own LPs, so that it
  // skips them before the gathering process could tell it.
  std::vector<char> opened(Nc, 0);
  for (int k = 0; k < Nc; ++k) opened[k] = bounds.fn_min[k] == 0.0;
  std::vector<std::atomic<char>> opened_here(Nc);
  for (std::atomic<char>& o : opened_here) o = 0;
  const auto mark = [&](const LpOutcome& o) {
    for (const int j : o.opened) opened[j] = 1;
  };
  // What a resume needs: the values known, and fn_min = 0 where a network opened the contact.
  const auto partial = [&] {
    ForceBounds p = bounds;
    for (int k = 0; k < Nc; ++k)
      if (opened[k] && std::isnan(p.fn_min[k])) {
        p.fn_min[k] = 0.0;
        ++p.min_lps_skipped;
      }
    p.complete = false;
    return p;
  };
  const auto count = [&](const LpOutcome& o) {
    bounds.iterations += o.iterations;
    bounds.loosened_solves += o.loosened;
    bounds.simplex_finishes += o.simplex_finished;
    bounds.unscaled_solves += o.unscaled;
    if (options.progress) options.progress(++done, total);
    if (options.checkpoint) options.checkpoint(partial());
  };
  const auto make_lp = [&] { return ForceLP(base); };  // own model and basis per thread

  // Phase 1: fn_max of every contact; each argmax network certifies the contacts it opens.
  std::vector<int> all, maxima_todo;
  if (distributor.gathers())
    for (int k = 0; k < Nc; ++k) {
      all.push_back(k);
      if (std::isnan(bounds.fn_max[k])) maxima_todo.push_back(k);
    }
  WorkLoop maxima;
  maxima.should_stop = options.should_stop;
  maxima.work = [&](WorkSource& source) {
    work_off(source, threads, chunk, make_lp, [&](ForceLP& lp, int k) {
      return encode(solve_lp(lp, open_tol, options.keep_networks_at_max,
                             [k](ForceLP& l) { return l.max_fn(k); }));
    });
  };
  maxima.gather = [&](std::vector<TaskResult>& results) {
    for (const TaskResult& r : results) {
      LpOutcome o = decode(r.bytes);
      bounds.fn_max[r.task] = o.value;
      mark(o);
      count(o);
      if (options.keep_networks_at_max)
        bounds.network_at_max[r.task] = {Eigen::Map<const Eigen::VectorXd>(o.fn.data(), Nc),
                                         Eigen::Map<const Eigen::VectorXd>(o.ft.data(), Nc)};
    }
  };
  bool complete = distributor.run(maxima_todo, maxima);

  // Phase 2: the min LP of every other contact, in order; each optimal network may open
  // contacts still queued, whose LPs are then skipped (which ones depends on the order, the
  // values do not: a minimum at or below open_tol is reported as 0).
  // (Run also after a stop, which hands out nothing: every process takes part in each loop.)
  std::vector<int> todo;
  for (const int k : all) {
    if (!std::isnan(bounds.fn_min[k])) continue;  // known from the run resumed
    if (opened[k]) {
      bounds.fn_min[k] = 0.0;
      ++bounds.min_lps_skipped;
      done += 1;
    } else {
      todo.push_back(k);
    }
  }
  WorkLoop minima;
  minima.should_stop = options.should_stop;
  minima.skip = [&](int k) {
    if (!opened[k]) return false;
    bounds.fn_min[k] = 0.0;
    ++bounds.min_lps_skipped;
    if (options.progress) options.progress(++done, total);
    return true;
  };
  minima.work = [&](WorkSource& source) {
    work_off(source, threads, chunk, make_lp, [&](ForceLP& lp, int k) {
      LpOutcome o;
      o.skipped = opened_here[k].load(std::memory_order_relaxed);
      if (!o.skipped) o = solve_lp(lp, open_tol, false, [k](ForceLP& l) { return l.min_fn(k); });
      for (const int j : o.opened) opened_here[j].store(1, std::memory_order_relaxed);
      return encode(o);
    });
  };
  minima.gather = [&](std::vector<TaskResult>& results) {
    for (const TaskResult& r : results) {
      const LpOutcome o = decode(r.bytes);
      bounds.fn_min[r.task] = o.skipped || o.value <= open_tol ? 0.0 : o.value;
      bounds.min_lps_skipped += o.skipped;
      mark(o);
      count(o);
    }
  };
  complete = distributor.run(todo, minima) && complete;
  if (distributor.gathers() && !complete) bounds = partial();
  if (options.progress && distributor.gathers() && complete) options.progress(total, total);
  bounds.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return bounds;
}

}  // namespace unjam
