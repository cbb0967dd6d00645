#include "scenes.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <tuple>
#include <sstream>

#include "unjam/core/error.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/protocol/settings_json.hpp"
#include "unjam/solver/time_step.hpp"

namespace unjam::bench {

std::filesystem::path cache_dir() {
  const char* env = std::getenv("UNJAM_BENCH_CACHE");
  return (env != nullptr && *env != '\0') ? std::filesystem::path(env)
                                          : std::filesystem::path("/tmp/unjam-bench-cache");
}

std::string static_packing_name(int N, double mu, std::uint64_t seed) {
  std::ostringstream s;
  s << "static-n" << N << "-mu" << mu << "-seed" << seed;
  return s.str();
}

Packing gas(int N, std::uint64_t seed) {
  GasSettings g;
  g.N = N;
  g.seed = seed;
  return make_gas(g);
}

std::string verify_static(const Packing& p, int N, double mu, std::uint64_t seed,
                          PackingStats* out) {
  if (static_cast<int>(p.size()) != N) return "N = " + std::to_string(p.size());
  if (p.meta.contact.mu != mu) return "mu = " + std::to_string(p.meta.contact.mu);
  if (p.meta.seed != seed) return "seed = " + std::to_string(p.meta.seed);
  if (!p.state.is_static) return "not marked static";
  const PackingStats s = compute_packing_stats(p);
  if (out != nullptr) *out = s;
  std::ostringstream why;
  if (!(s.max_force_residual < 1e-8)) why << "force residual " << s.max_force_residual << " F0; ";
  if (!(s.max_torque_residual < 1e-8)) why << "torque residual " << s.max_torque_residual << " F0; ";
  if (!(std::abs(s.pressure_ratio - 1.0) < 1e-8)) why << "P_in/P_ext " << s.pressure_ratio << "; ";
  if (!(s.max_tension <= 0.0)) why << "tension " << s.max_tension << " F0; ";
  if (!(s.max_coulomb_violation < 1e-8)) why << "Coulomb violation " << s.max_coulomb_violation << "; ";
  if (s.N_c == 0) why << "no force-carrying contact; ";
  return why.str();
}

Packing static_packing(int N, double mu, std::uint64_t seed) {
  const std::filesystem::path dir = cache_dir() / static_packing_name(N, mu, seed);
  if (std::filesystem::exists(dir / "meta.json")) {
    try {
      Packing p = read_packing(dir);
      const std::string why = verify_static(p, N, mu, seed);
      if (why.empty()) return p;
      std::fprintf(stderr, "bench cache: %s rejected (%s); recompacting\n", dir.c_str(), why.c_str());
    } catch (const Error& e) {
      std::fprintf(stderr, "bench cache: %s unreadable (%s); recompacting\n", dir.c_str(), e.what());
    }
  }
  std::fprintf(stderr, "bench cache: compacting %s ...\n", dir.filename().c_str());
  GasSettings g;
  g.N = N;
  g.seed = seed;
  Packing p = make_gas(g);
  p.meta.contact.mu = mu;
  CompactionSettings cs;
  p.meta.settings = to_json(cs, g);
  p.meta.command = "unjam_bench scene " + static_packing_name(N, mu, seed);
  const CompactionResult r = compact(p, cs);
  if (!r.is_static)
    throw Error("bench scene " + static_packing_name(N, mu, seed) + ": compaction not static");
  const std::string why = verify_static(p, N, mu, seed);
  if (!why.empty()) throw Error("bench scene " + static_packing_name(N, mu, seed) + ": " + why);
  std::fprintf(stderr, "bench cache: %s static after %lld steps, %.1f s; written to %s\n",
               dir.filename().c_str(), static_cast<long long>(r.steps), r.wall_s, dir.c_str());
  write_packing(dir, p);
  return p;
}


Packing compressing(int N, std::uint64_t seed, double phi_target) {
  Packing p = gas(N, seed);
  p.meta.contact.mu = 0.1;
  const CompactionSettings cs;  // the dynamics of the compaction
  NlgsThreading threading;
  while (p.packing_fraction() < phi_target) {
    if (p.state.step >= 1'000'000) throw Error("bench scene compressing: phi not reached");
    advance(p, cs.dynamics, threading);
  }
  return p;
}

double L_over_d_squared(const Packing& p) {
  const double L_over_d = std::sqrt(p.cell.area()) / (2.0 * p.mean_radius());
  return L_over_d * L_over_d;
}

const Packing& static_scene(int N, double mu, std::uint64_t seed) {
  static std::map<std::tuple<int, double, std::uint64_t>, Packing> cache;
  auto it = cache.find({N, mu, seed});
  if (it == cache.end())
    it = cache.emplace(std::tuple{N, mu, seed},
                       with_one_thread([&] { return static_packing(N, mu, seed); }))
             .first;
  return it->second;
}

}  // namespace unjam::bench
