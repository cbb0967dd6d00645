// Benchmarks of the contact-dynamics engine on named, seeded scenes (bench/scenes.hpp).
// Every benchmark checks its result and reports an error (SkipWithError) if the check fails;
// docs/benchmarks.md has the numbers and the commands.
//
//   BM_NlgsKernel/N/threads      solve_nlgs, static problem from zero forces, fixed sweeps:
//                                ns per contact update; forces bit-identical to 1 thread
//   BM_NlgsSetup/N/threads       the same with one sweep: colouring + setup cost
//   BM_AdvanceStep/N/threads     advance() on a gas compressed to phi = 0.80: time and sweeps per step;
//                                state bit-identical to 1 thread
//   BM_DetectContacts/N          detect_contacts on a static packing: pair count = brute force
//   BM_StaticSweeps/N/seed/tol   solve_static from zero forces to 1e-tol F0 (1 thread): sweeps vs (L/d)^2
//   BM_StaticScene/N/seed        verifies the cached static packings (residual, P_in/P_ext)
//
// Wall-clock time (UseRealTime): the solver runs OpenMP threads; the counters add the process
// CPU time (cpu_ns_per_update, cpu_ms_per_step), which a busy machine does not inflate for one
// thread. Two-thread rows need two free cores: with another runnable process on the machine
// libgomp's spinning barriers make them 10-1000x slower (docs/benchmarks.md, section 6);
// OMP_WAIT_POLICY=passive avoids the collapse. Static packings are cached, see scenes.hpp.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "scenes.hpp"
#include "unjam/analysis/packing_stats.hpp"
#include "unjam/contact/detection.hpp"
#include "unjam/core/error.hpp"
#include "unjam/solver/coloring.hpp"
#include "unjam/solver/nlgs.hpp"
#include "unjam/solver/static_solve.hpp"
#include "unjam/solver/time_step.hpp"
#include "unjam/protocol/compaction.hpp"

namespace {

using namespace unjam;
using Clock = std::chrono::steady_clock;

constexpr double kMu = 0.1;
constexpr int kKernelSweeps = 200;   // fixed sweeps of the kernel benchmark
constexpr int kBlock = 128;          // contacts per parallel block in nlgs.cpp (for reporting)
constexpr double kCompressPhi = 0.80;  // packing fraction of the compressing scene
constexpr int kStepsPerIter = 10;    // steps timed per iteration of BM_AdvanceStep

double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// CPU time of the whole process (all threads), seconds: with other jobs on the machine the
// wall time of a one-thread run includes waiting for a core, its CPU time does not.
double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Scenes are built once per process.
const Packing& compressing_scene(int N) {
  static std::map<int, Packing> cache;
  auto it = cache.find(N);
  if (it == cache.end())
    it = cache.emplace(N, bench::with_one_thread([&] { return bench::compressing(N, 1, kCompressPhi); })).first;
  return it->second;
}

bool bit_identical(const Contacts& x, const Contacts& y) {
  if (x.size() != y.size()) return false;
  for (std::size_t k = 0; k < x.size(); ++k)
    if (std::memcmp(&x[k].fn, &y[k].fn, sizeof(double)) != 0 ||
        std::memcmp(&x[k].ft, &y[k].ft, sizeof(double)) != 0)
      return false;
  return true;
}

bool bit_identical(const std::vector<double>& x, const std::vector<double>& y) {
  return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(double)) == 0;
}

// ---- NLGS kernel -------------------------------------------------------------------------

// The static problem of a packing (as solve_static sets it up): zero velocities, lambda_t = 0,
// the bath on, touching pairs (gap < 1e-6) closable, all forces zero.
struct KernelInput {
  StepProblem pb;
  Contacts contacts;
  Particles particles;
  NlgsSettings set;
};

KernelInput kernel_input(const Packing& p, int sweeps) {
  KernelInput in{StepProblem{p.cell, 0.01, p.meta.contact.mu, Bath{}, 0.0, {}}, p.contacts, p.particles, {}};
  for (Contact& c : in.contacts) c.fn = c.ft = 0.0;
  in.pb.g_eff.resize(in.contacts.size());
  for (std::size_t k = 0; k < in.contacts.size(); ++k)
    in.pb.g_eff[k] = in.contacts[k].gap < 1e-6 ? 0.0 : in.contacts[k].gap;
  for (auto* v : {&in.particles.vx, &in.particles.vy, &in.particles.omega})
    std::fill(v->begin(), v->end(), 0.0);
  in.set.rule = Convergence::kStatic;
  in.set.static_tol = 1e-300;  // never met: exactly `sweeps` sweeps
  in.set.F0 = p.force_unit();
  in.set.min_sweeps = in.set.max_sweeps = sweeps;
  in.set.check_every = sweeps;  // residual evaluated once, after the last sweep
  in.set.seed = 1;
  return in;
}

struct KernelOutput {
  Contacts contacts;
  NlgsResult res;
};

KernelOutput run_kernel(const KernelInput& in, NlgsThreading& threading) {
  KernelOutput out{in.contacts, {}};
  Particles particles = in.particles;
  out.res = solve_nlgs(in.pb, in.set, out.contacts, particles, threading);
  return out;
}

// One-thread reference of the kernel: forces after kKernelSweeps (determinism check), and
// the residual after kKernelSweeps / 4 and kKernelSweeps (convergence check).
struct KernelReference {
  Contacts forces;
  double residual_quarter = 0.0, residual = 0.0;
  double perr_quarter = 0.0, perr = 0.0;
};

const KernelReference& kernel_reference(int N, int sweeps) {
  static std::map<std::pair<int, int>, KernelReference> cache;
  auto it = cache.find({N, sweeps});
  if (it != cache.end()) return it->second;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Packing& p = bench::static_scene(N, kMu);
  KernelReference ref;
  NlgsThreading threading;
  const KernelOutput f = run_kernel(kernel_input(p, sweeps), threading);
  if (sweeps >= 4) {
    const KernelOutput q = run_kernel(kernel_input(p, sweeps / 4), threading);
    ref.residual_quarter = q.res.max_residual_F0;
    ref.perr_quarter = std::abs(q.res.P_in - 1.0);
  }
  omp_set_num_threads(threads);
  ref.forces = f.contacts;
  ref.residual = f.res.max_residual_F0;
  ref.perr = std::abs(f.res.P_in - 1.0);
  return cache.emplace(std::pair{N, sweeps}, std::move(ref)).first->second;
}

void kernel_benchmark(benchmark::State& state, int sweeps) {
  const int N = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const Packing* p = nullptr;
  try {
    p = &bench::static_scene(N, kMu);
  } catch (const Error& e) {
    state.SkipWithError(e.what());
    return;
  }
  const KernelReference& ref = kernel_reference(N, sweeps);
  omp_set_num_threads(threads);
  const KernelInput in = kernel_input(*p, sweeps);
  const std::int64_t nc = static_cast<std::int64_t>(in.contacts.size());

  KernelOutput out;
  NlgsThreading threading;  // the iterations' solves share the measurements of Threading::kAuto
  double solve_s = 0.0, cpu_s = 0.0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const double c0 = process_cpu_s();
    out = run_kernel(in, threading);
    cpu_s += process_cpu_s() - c0;
    solve_s += seconds(t0, Clock::now());
    benchmark::DoNotOptimize(out.contacts.data());
  }
  const std::int64_t updates = state.iterations() * out.res.sweeps * nc;
  state.SetItemsProcessed(updates);

  // Checks: exactly `sweeps` sweeps; forces bit-identical to the one-thread run; the
  // residual and the pressure error fall between sweeps / 4 and sweeps.
  if (out.res.sweeps != sweeps) {
    state.SkipWithError(("ran " + std::to_string(out.res.sweeps) + " sweeps").c_str());
    return;
  }
  if (!bit_identical(out.contacts, ref.forces)) {
    state.SkipWithError("forces differ from the one-thread run (determinism broken)");
    return;
  }
  if (sweeps >= 4 && !(ref.residual < ref.residual_quarter && ref.perr < ref.perr_quarter &&
                       std::isfinite(ref.residual))) {
    state.SkipWithError("static residual did not decrease over the sweeps");
    return;
  }
  const Coloring col = color_contacts(in.contacts, N, in.set.seed);
  int blocks = 0;
  for (int c = 0; c < col.num_colors(); ++c)
    blocks += (col.color_start[c + 1] - col.color_start[c] + kBlock - 1) / kBlock;
  state.counters["contacts"] = static_cast<double>(nc);
  state.counters["colors"] = col.num_colors();
  state.counters["blocks"] = blocks;
  state.counters["parallel"] = (threads > 1 && blocks > 2 * col.num_colors()) ? 1 : 0;
  state.counters["sweeps"] = sweeps;
  state.counters["ns_per_update"] = 1e9 * solve_s / static_cast<double>(updates);
  state.counters["cpu_ns_per_update"] = 1e9 * cpu_s / static_cast<double>(updates);
  state.counters["Mupdates_per_s"] = static_cast<double>(updates) / solve_s / 1e6;
  state.counters["residual_F0"] = out.res.max_residual_F0;
  state.counters["P_err"] = std::abs(out.res.P_in - 1.0);
}

void BM_NlgsKernel(benchmark::State& state) { kernel_benchmark(state, kKernelSweeps); }
void BM_NlgsSetup(benchmark::State& state) { kernel_benchmark(state, 1); }

BENCHMARK(BM_NlgsKernel)
    ->ArgNames({"N", "threads"})
    ->ArgsProduct({{500, 2000, 8000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NlgsSetup)
    ->ArgNames({"N", "threads"})
    ->ArgsProduct({{500, 2000, 8000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

// ---- One dynamics step ---------------------------------------------------------------------

struct StepReference {
  std::vector<double> x, y, vx;
  std::int64_t sweeps = 0;
};

Packing run_steps(const Packing& from, int steps, std::int64_t& sweeps, std::int64_t& updates) {
  Packing p = from;
  const CompactionSettings cs;
  NlgsThreading threading;
  for (int s = 0; s < steps; ++s) {
    const StepReport r = advance(p, cs.dynamics, threading);
    sweeps += r.sweeps;
    updates += static_cast<std::int64_t>(r.sweeps) * r.num_contacts;
  }
  return p;
}

const StepReference& step_reference(int N) {
  static std::map<int, StepReference> cache;
  auto it = cache.find(N);
  if (it != cache.end()) return it->second;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  std::int64_t sweeps = 0, updates = 0;
  const Packing p = run_steps(compressing_scene(N), kStepsPerIter, sweeps, updates);
  omp_set_num_threads(threads);
  return cache.emplace(N, StepReference{p.particles.x, p.particles.y, p.particles.vx, sweeps})
      .first->second;
}

void BM_AdvanceStep(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  const Packing& scene = compressing_scene(N);
  const StepReference& ref = step_reference(N);
  omp_set_num_threads(threads);
  std::int64_t sweeps = 0, updates = 0;
  double step_s = 0.0, cpu_s = 0.0;
  Packing last;
  NlgsThreading threading;  // the iterations' steps share the measurements of Threading::kAuto
  for (auto _ : state) {
    state.PauseTiming();
    Packing p = scene;
    state.ResumeTiming();
    const auto t0 = Clock::now();
    const double c0 = process_cpu_s();
    const CompactionSettings cs;
    for (int s = 0; s < kStepsPerIter; ++s) {
      const StepReport r = advance(p, cs.dynamics, threading);
      sweeps += r.sweeps;
      updates += static_cast<std::int64_t>(r.sweeps) * r.num_contacts;
    }
    step_s += seconds(t0, Clock::now());
    cpu_s += process_cpu_s() - c0;
    state.PauseTiming();
    last = std::move(p);
    state.ResumeTiming();
  }
  const double steps = static_cast<double>(state.iterations() * kStepsPerIter);
  if (sweeps != ref.sweeps * state.iterations() || !bit_identical(last.particles.x, ref.x) ||
      !bit_identical(last.particles.y, ref.y) || !bit_identical(last.particles.vx, ref.vx)) {
    state.SkipWithError("state after the steps differs from the one-thread run");
    return;
  }
  const PackingStats st = compute_packing_stats(last);
  if (!(st.max_tension <= 0.0) || !(st.max_coulomb_violation < 1e-9) || !std::isfinite(st.P_in)) {
    state.SkipWithError("step produced tension, a Coulomb violation or a non-finite pressure");
    return;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(steps));
  state.counters["phi"] = st.phi;
  state.counters["scene_step"] = static_cast<double>(scene.state.step);
  state.counters["contacts"] = static_cast<double>(last.contacts.size());
  state.counters["P_ratio"] = st.pressure_ratio;
  state.counters["sweeps_per_step"] = static_cast<double>(sweeps) / steps;
  state.counters["ms_per_step"] = 1e3 * step_s / steps;
  state.counters["cpu_ms_per_step"] = 1e3 * cpu_s / steps;
  state.counters["ns_per_update"] = 1e9 * step_s / static_cast<double>(updates);
}
BENCHMARK(BM_AdvanceStep)
    ->ArgNames({"N", "threads"})
    ->ArgsProduct({{2000, 8000}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// ---- Contact detection ---------------------------------------------------------------------

std::size_t brute_force_pair_count(const Packing& p, double max_gap) {
  const auto& P = p.particles;
  std::size_t count = 0;
  for (std::size_t i = 0; i < P.size(); ++i)
    for (std::size_t j = i + 1; j < P.size(); ++j) {
      const Vec2 l = p.cell.min_image(P.position(j) - P.position(i));
      if (l.norm() - P.radius[i] - P.radius[j] < max_gap) ++count;
    }
  return count;
}

void BM_DetectContacts(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const Packing& p = bench::static_scene(N, kMu);
  const double max_gap = DynamicsSettings{}.min_detection;
  const std::size_t expected = brute_force_pair_count(p, max_gap);
  Contacts found;
  for (auto _ : state) {
    found = detect_contacts(p.particles, p.cell, max_gap, p.contacts);
    benchmark::DoNotOptimize(found.data());
  }
  if (found.size() != expected) {
    state.SkipWithError(("found " + std::to_string(found.size()) + " pairs, brute force " +
                         std::to_string(expected)).c_str());
    return;
  }
  state.SetItemsProcessed(state.iterations() * N);
  state.counters["pairs"] = static_cast<double>(found.size());
}
BENCHMARK(BM_DetectContacts)->ArgName("N")->Arg(2000)->Arg(8000)->Unit(benchmark::kMicrosecond);

// ---- Sweeps to a static network: growth with N ---------------------------------------------

void BM_StaticSweeps(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const auto seed = static_cast<std::uint64_t>(state.range(1));
  const double tol = std::pow(10.0, -static_cast<double>(state.range(2)));
  const Packing& scene = bench::static_scene(N, kMu, seed);
  omp_set_num_threads(1);  // the sweep count does not depend on the thread count
  StaticSolveSettings ss;
  ss.tol = tol;
  ss.polish_from = 0.0;  // NLGS only
  ss.check_every = 10;
  ss.seed = 1;
  StaticSolveReport rep;
  for (auto _ : state) {
    state.PauseTiming();
    Packing p = scene;
    for (Contact& c : p.contacts) c.fn = c.ft = 0.0;
    state.ResumeTiming();
    rep = solve_static(p, Bath{}, ss);
  }
  if (!rep.converged || !(rep.max_residual_F0 < tol) || !(rep.pressure_error < tol)) {
    state.SkipWithError("static solve did not reach the residual target");
    return;
  }
  const double Ld2 = bench::L_over_d_squared(scene);
  state.counters["sweeps"] = rep.sweeps;
  state.counters["L_over_d_sq"] = Ld2;
  state.counters["sweeps_per_Ld2"] = rep.sweeps / Ld2;
  state.counters["contacts"] = static_cast<double>(scene.contacts.size());
}
// Args: N, seed, -log10(residual target / F0).
BENCHMARK(BM_StaticSweeps)
    ->ArgNames({"N", "seed", "tol_exp"})
    ->Args({500, 1, 2})->Args({500, 2, 2})->Args({500, 3, 2})
    ->Args({2000, 1, 2})->Args({2000, 2, 2})->Args({2000, 3, 2})
    ->Args({8000, 1, 2})
    ->Args({500, 1, 4})->Args({500, 2, 4})->Args({500, 3, 4})
    ->Args({2000, 1, 4})->Args({2000, 2, 4})->Args({2000, 3, 4})
    ->Args({8000, 1, 4})
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// ---- The static scenes themselves ----------------------------------------------------------

void BM_StaticScene(benchmark::State& state) {
  const int N = static_cast<int>(state.range(0));
  const auto seed = static_cast<std::uint64_t>(state.range(1));
  const Packing& p = bench::static_scene(N, kMu, seed);
  PackingStats st;
  std::string why;
  for (auto _ : state) why = bench::verify_static(p, N, kMu, seed, &st);
  if (!why.empty()) {
    state.SkipWithError(why.c_str());
    return;
  }
  state.counters["phi"] = st.phi;
  state.counters["z"] = st.z;
  state.counters["residual_F0"] = std::max(st.max_force_residual, st.max_torque_residual);
  state.counters["P_ratio_m1"] = st.pressure_ratio - 1.0;
  state.counters["rattlers"] = static_cast<double>(st.rattlers);
}
BENCHMARK(BM_StaticScene)
    ->ArgNames({"N", "seed"})
    ->Args({500, 1})->Args({500, 2})->Args({500, 3})
    ->Args({2000, 1})->Args({2000, 2})->Args({2000, 3})
    ->Args({8000, 1})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
