#pragma once
// Named, seeded scenes for the benchmarks (docs/benchmarks.md). Every scene is built by the
// library itself, from a seed, so a benchmark names exactly what it measures:
//
//   gas(N, seed)                  make_gas: N disks at phi = 0.3, at rest (GasSettings defaults)
//   static_packing(N, mu, seed)   the gas compacted by compact() to a static packing with the
//                                 default CompactionSettings (the same as `unjam pack`);
//                                 cached on disk, verified before use
//   compressing(N, seed, phi)     the gas (mu = 0.1) integrated under the bath with the
//                                 compaction's dynamics until its packing fraction first
//                                 reaches phi: a dense, still compressing state
//
// The static packings are cached under $UNJAM_BENCH_CACHE (default /tmp/unjam-bench-cache) as
// packing directories named static-n<N>-mu<mu>-seed<seed>, so repeated bench runs do not
// recompact. A cached packing is used only if compute_packing_stats confirms it is static
// (force and torque residual < 1e-8 F0, |P_in / P_ext - 1| < 1e-8, no tension, no Coulomb
// violation) and it is the scene asked for (N, mu, seed); otherwise it is recompacted.
// `unjam pack --n N --mu MU --seed S --out $UNJAM_BENCH_CACHE/static-nN-muMU-seedS` fills the
// cache with the same packing (same library call, same defaults).
#include <cstdint>
#include <filesystem>
#include <string>

#include <omp.h>

#include "unjam/analysis/packing_stats.hpp"
#include "unjam/packing/packing.hpp"

namespace unjam::bench {

// Directory of the on-disk cache of static packings.
std::filesystem::path cache_dir();

// Directory name of a static packing in the cache, e.g. "static-n2000-mu0.1-seed1".
std::string static_packing_name(int N, double mu, std::uint64_t seed);

Packing gas(int N, std::uint64_t seed);

// Static packing (cached). Throws unjam::Error if the compaction does not reach a static
// packing or the result fails verify_static.
Packing static_packing(int N, double mu, std::uint64_t seed);

// static_packing built (or loaded) once per process, with one OpenMP thread; the same
// reference for every benchmark that asks for it.
const Packing& static_scene(int N, double mu, std::uint64_t seed = 1);

// Runs f with one OpenMP thread (scene building and references: the results do not depend
// on the thread count, and one thread is never slowed down by a busy machine's scheduling
// of the other thread), then restores the thread count.
template <class F>
auto with_one_thread(F&& f) {
  struct Restore {
    int n;
    ~Restore() { omp_set_num_threads(n); }
  } restore{omp_get_max_threads()};
  omp_set_num_threads(1);
  return f();
}

// The gas (mu = 0.1) advanced by the compaction dynamics (default CompactionSettings) until
// phi >= phi_target (not cached: cheap). Throws unjam::Error if not reached in 10^6 steps.
Packing compressing(int N, std::uint64_t seed, double phi_target);

// Packing fraction sum(pi R^2) / V.
double packing_fraction(const Packing& p);

// Empty if the packing is a verified static packing of the scene (N, mu, seed); else the
// reason it is not.
std::string verify_static(const Packing& p, int N, double mu, std::uint64_t seed,
                          PackingStats* stats = nullptr);

// (L / d)^2 with d the mean diameter: the NLGS sweep scale (docs/method.md, "The static solve").
double L_over_d_squared(const Packing& p);

}  // namespace unjam::bench
