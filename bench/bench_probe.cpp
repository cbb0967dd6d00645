// Benchmarks of the fast probe and of the force-bounds LPs on the static scenes (mu = 0.1,
// seed 1; bench/scenes.hpp). Each checks its result (SkipWithError on failure);
// docs/benchmarks.md has the numbers and the commands.
//
//   BM_KinematicProbe/N   KinematicProbe::probe on kProbes contacts spread over the packing
//                         (one thread): s per probe; F_crit >= F_cont (the LP maximum is at
//                         least the packing's own force), the field opens the pair by g with
//                         no unilateral violation. Counter model_s: building the LP model.
//   BM_CdPath/N/start/qs  probe_cd_path (the exact CD step, --method cd) on the same contacts,
//                         one thread, CPU time, from the static network (start 0) or by the
//                         compliant continuation (start 1, --cd-start compliant) or from
//                         the interior-point iterate (start 2, --cd-start interior), at
//                         dt = 1e-3 (qs 0) or the quasi-static default dt (qs 1,
//                         default_probe_dt: 1e-2 at g = 1e-9): s per
//                         probe; counters exact (residual <= 1e-6 g),
//                         no_solution, pieces and factorizations per probe; every solution
//                         returned must pass kMaxPathResidual and open the pair by g to
//                         within its residual (at least 1e-6).
//   BM_ForceLp/N          ForceLP min and max of fn on the same contacts (barrier, one
//                         thread): s per LP; fn_min <= fn <= fn_max.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "scenes.hpp"
#include "unjam/contact/equilibrium_matrix.hpp"
#include "unjam/lp/force_lp.hpp"
#include "unjam/probe/cd_path.hpp"
#include "unjam/probe/kinematic_probe.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace {

using namespace unjam;
using Clock = std::chrono::steady_clock;

constexpr double kMu = 0.1;
constexpr int kProbes = 8;  // contacts per benchmark, spread evenly over the contact list

// kProbes force-carrying contacts (fn > 0.1 F0), evenly spaced in the contact list.
std::vector<int> probed_contacts(const Packing& p) {
  std::vector<int> loaded;
  for (int k = 0; k < static_cast<int>(p.contacts.size()); ++k)
    if (p.contacts[k].fn > 0.1 * p.force_unit()) loaded.push_back(k);
  std::vector<int> picked;
  for (int i = 0; i < kProbes; ++i)
    picked.push_back(loaded[loaded.size() * i / kProbes]);
  return picked;
}

void BM_KinematicProbe(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const Packing& p = bench::static_scene(N, kMu);
  const std::vector<int> contacts = probed_contacts(p);
  omp_set_num_threads(1);
  const auto t0 = Clock::now();
  KinematicProbe probe(p, {});
  state.counters["model_s"] = std::chrono::duration<double>(Clock::now() - t0).count();
  std::vector<ProbeResult> results;
  for (auto _ : state) {
    results.clear();
    for (const int k : contacts) results.push_back(probe.probe(k));
  }
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const ProbeResult& r = results[i];
    const double open = contact_opening(p, r, contacts[i]) / r.g;
    if (!(r.f_crit >= r.f_cont * (1.0 - 1e-6)) || r.violations != 0 || !(std::abs(open - 1.0) < 0.1)) {
      state.SkipWithError(("probe of contact " + std::to_string(contacts[i]) + " fails its check")
                              .c_str());
      return;
    }
  }
  state.counters["probes"] = kProbes;
  state.counters["s_per_probe"] =
      benchmark::Counter(kProbes, benchmark::Counter::kIsIterationInvariantRate |
                                      benchmark::Counter::kInvert);
  state.counters["contacts"] = static_cast<double>(probe.system().num_contacts());
  state.counters["rows"] = static_cast<double>(probe.system().A.rows());
}
BENCHMARK(BM_KinematicProbe)
    ->ArgName("N")->Arg(500)->Arg(2000)->Arg(8000)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);

void BM_CdPath(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const Packing& p = bench::static_scene(N, kMu);
  const std::vector<int> contacts = probed_contacts(p);
  omp_set_num_threads(1);
  CdPathSettings ps;
  if (state.range(1) == 1) ps.start = CdPathStart::compliant;
  if (state.range(1) == 2) ps.start = CdPathStart::interior_point;
  ProbeSettings step;
  if (state.range(2) == 1) step.dt = default_probe_dt(ProbeMethod::kCd, step.g);
  std::vector<CdStepSolution> results;
  std::vector<CdPathStats> stats(contacts.size());
  for (auto _ : state) {
    results.clear();
    for (std::size_t i = 0; i < contacts.size(); ++i)
      results.push_back(probe_cd_path(p, contacts[i], step, ps, &stats[i]));
  }
  int exact = 0, none = 0, pieces = 0, factorizations = 0, interior = 0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const ProbeResult& r = results[i].result;
    pieces += stats[i].pieces;
    interior += stats[i].interior_iterations;
    factorizations += stats[i].factorizations;
    if (r.residual == kNoSolution) {
      ++none;
      continue;
    }
    if (r.converged) ++exact;
    const double open = contact_opening(p, r, contacts[i]) / r.g;
    if (!(r.residual <= kMaxPathResidual) || !(std::abs(open - 1.0) <= std::max(1e-6, r.residual))) {
      state.SkipWithError(("probe of contact " + std::to_string(contacts[i]) + " fails its check").c_str());
      return;
    }
  }
  state.counters["probes"] = kProbes;
  state.counters["exact"] = exact;
  state.counters["no_solution"] = none;
  state.counters["pieces"] = static_cast<double>(pieces) / kProbes;
  state.counters["factorizations"] = static_cast<double>(factorizations) / kProbes;
  if (interior > 0) state.counters["interior_iterations"] = static_cast<double>(interior) / kProbes;
  state.counters["s_per_probe"] =
      benchmark::Counter(kProbes, benchmark::Counter::kIsIterationInvariantRate |
                                      benchmark::Counter::kInvert);
}
BENCHMARK(BM_CdPath)
    ->ArgNames({"N", "start", "qs"})->Args({500, 0, 0})->Args({500, 1, 0})->Args({500, 1, 1})
    ->Args({500, 2, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

void BM_ForceLp(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const Packing& p = bench::static_scene(N, kMu);
  const std::vector<int> contacts = probed_contacts(p);
  const EquilibriumSystem sys = build_equilibrium_system(p);
  std::vector<int> column(p.contacts.size(), -1);
  for (int k = 0; k < sys.num_contacts(); ++k) column[sys.contacts[k]] = k;
  ForceLP lp(sys);
  std::vector<double> lo, hi;
  for (auto _ : state) {
    lo.clear();
    hi.clear();
    for (const int k : contacts) {
      lo.push_back(lp.min_fn(column[k]));
      hi.push_back(lp.max_fn(column[k]));
    }
  }
  const double tol = 1e-7 * p.force_unit();
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const double fn = p.contacts[contacts[i]].fn;
    if (column[contacts[i]] < 0 || !(lo[i] <= fn + tol) || !(hi[i] >= fn - tol)) {
      state.SkipWithError(("interval of contact " + std::to_string(contacts[i]) +
                           " does not hold the packing's force").c_str());
      return;
    }
  }
  state.counters["lps"] = 2 * kProbes;
  state.counters["s_per_lp"] =
      benchmark::Counter(2 * kProbes, benchmark::Counter::kIsIterationInvariantRate |
                                          benchmark::Counter::kInvert);
  state.counters["rows"] = static_cast<double>(sys.A.rows());
}
BENCHMARK(BM_ForceLp)
    ->ArgName("N")->Arg(500)->Arg(2000)->Arg(8000)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);

}  // namespace
