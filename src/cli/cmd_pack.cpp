// `unjam pack`: compacts a gas of disks under the pressure bath into a static packing
// (docs/method.md, "Compaction"), or continues from an existing packing: resume a stopped run
// in place (--resume DIR) or re-relax a packing at another mu or P_ext (--from DIR --out NEW).
#include <omp.h>

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/run_info.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/protocol/compaction.hpp"
#include "unjam/protocol/gas.hpp"
#include "unjam/protocol/pack_run.hpp"
#include "unjam/protocol/settings_json.hpp"

namespace unjam::cli {
namespace {

struct PackOptions {
  GasSettings gas;
  CompactionSettings compaction;
  double mu = 0.1;
  double P_ext = 1.0;
  std::string out;
  std::string from;
  std::string resume;
  int threads = 0;
  double checkpoint_s = 60.0;
  double max_memory_gb = 0.0;  // 0: the machine's physical memory
  bool quiet = false;
  std::string command;
};

void print_progress(const CompactionProgress& pr) {
  std::string eta = pr.eta_s >= 0.0 ? format_duration(pr.eta_s) : "?";
  std::fprintf(stderr,
               "step %8lld  t %9.2f  phi %.4f  P_in/P_ext %.4f  <v> %.2e  sweeps/step %6.1f  "
               "contacts %6d  static tries %d  elapsed %s  ETA ~%s\n",
               static_cast<long long>(pr.step), pr.time, pr.phi, pr.P_ratio, pr.v_mean,
               pr.sweeps_per_step, pr.contacts, pr.static_attempts,
               format_duration(pr.elapsed_s).c_str(), eta.c_str());
}

// Refuses a run whose memory estimate (protocol/compaction.hpp) exceeds --max-memory (by
// default the machine's physical memory) before anything is allocated.
void check_memory(const PackOptions& o, std::size_t N) {
  const double need = static_cast<double>(estimated_memory_bytes(N));
  const double limit = o.max_memory_gb > 0.0 ? o.max_memory_gb * 1e9 : physical_memory_bytes();
  if (need > limit)
    throw Error("N = " + std::to_string(N) + " needs about " + format_bytes(need) + " of memory, more than " +
                (o.max_memory_gb > 0.0 ? "--max-memory " : "this machine's ") + format_bytes(limit) +
                "; use fewer disks or raise --max-memory");
  if (!o.quiet && need > 1e9) std::fprintf(stderr, "memory estimate: %s\n", format_bytes(need).c_str());
}

// The packing to compact and where it goes; nullopt if a run to resume is already static.
std::optional<Packing> start_packing(PackOptions& o, std::filesystem::path& out) {
  out = o.out;
  if (o.resume.empty() && o.from.empty()) check_memory(o, static_cast<std::size_t>(std::max(o.gas.N, 0)));
  Packing p;
  if (!o.resume.empty()) {
    // Continue in place with the settings the run was started with.
    p = stopped_packing(o.resume, o.compaction, o.gas);
    out = o.resume;
    if (p.state.is_static) {
      std::fprintf(stderr, "%s is already static; nothing to do\n", o.resume.c_str());
      return std::nullopt;
    }
  } else {
    if (o.out.empty()) throw Error("--out is required (or --resume DIR)");
    if (!o.from.empty()) {
      p = read_packing(o.from);
      prepare_relaxation(p, o.mu, o.P_ext, o.compaction, o.gas);
    } else {
      p = gas_packing(o.gas, o.mu, o.P_ext);
    }
  }
  prepare_compaction(p, o.compaction, o.gas, o.command);
  return p;
}

CompactionHooks compaction_hooks(const PackOptions& o, const std::filesystem::path& out) {
  CompactionHooks hooks;
  if (!o.quiet) {
    hooks.progress = print_progress;
    hooks.attempt = [](std::int64_t step, double v, const StaticSolveReport& r) {
      if (r.converged) return;
      std::fprintf(stderr,
                   "step %lld: static solve attempt (<v> %.1e): not static yet (residual %.1e F0 "
                   "after %d sweeps); dynamics goes on\n",
                   static_cast<long long>(step), v, r.max_residual_F0, r.sweeps);
    };
  }
  hooks.checkpoint = [out](const Packing& q) { write_packing(out, q); };
  hooks.checkpoint_s = o.checkpoint_s;
  hooks.should_stop = InterruptGuard::requested;
  return hooks;
}

void print_report(const std::filesystem::path& out, const CompactionResult& r, const PackReport& report) {
  const PackingStats& s = report.stats;
  std::printf("static packing written to %s\n", out.c_str());
  std::printf("  N %zu  mu %g  phi %.4f  z %.3f  rattlers %zu  contacts carrying force %zu\n", s.N,
              s.mu, s.phi, s.z, s.rattlers, s.N_c);
  std::printf("  <F_cont>/F0 %.4f  max overlap %.2e  max residual %.1e F0  P_in/P_ext %.12f\n",
              s.F_cont, s.max_overlap, s.max_force_residual, s.pressure_ratio);
  if (s.isostatic_excess) {
    std::printf("  isostatic count (contacts - (2N'-1)): %lld\n", static_cast<long long>(*s.isostatic_excess));
    // Redundant contacts of a frictionless packing come from overlaps of ~tol (docs/method.md):
    // its force network is then not unique, and F_crit can exceed F_cont.
    if (*s.isostatic_excess > 0)
      std::printf("  %lld redundant contact(s), from overlaps up to %.1e: tighter dynamics "
                  "(--tol 1e-6 --max-sweeps 2000) leave fewer (docs/method.md)\n",
                  static_cast<long long>(*s.isostatic_excess), s.max_overlap);
  }
  std::printf("  %lld steps, %lld sweeps (%.1f per step), %d static solve attempt(s), %s wall, "
              "%.1f M contact updates/s\n",
              static_cast<long long>(r.steps), static_cast<long long>(r.sweeps), report.sweeps_per_step,
              r.static_attempts, format_duration(r.wall_s).c_str(), report.updates_per_s / 1e6);
}

void run(PackOptions& o) {
  std::filesystem::path out;
  std::optional<Packing> start = start_packing(o, out);
  if (!start) return;
  Packing& p = *start;
  if (o.threads > 0) omp_set_num_threads(o.threads);

  const DirLock lock(out, o.command);
  const CompactionHooks hooks = compaction_hooks(o, out);
  const InterruptGuard interrupts;
  std::fprintf(stderr, "unjam pack: N = %zu, mu = %g, P_ext = %g, threads = %d -> %s\n", p.size(),
               p.meta.contact.mu, p.meta.contact.P_ext, omp_get_max_threads(), out.c_str());
  const CompactionResult r = compact(p, o.compaction, hooks);
  write_packing(out, p);

  if (!r.is_static) {
    std::fprintf(stderr,
                 "%s after %lld steps; the packing is not static yet and was saved to %s\n"
                 "resume with: unjam pack --resume %s\n",
                 r.stopped ? "stopped" : "step limit reached", static_cast<long long>(r.steps),
                 out.c_str(), out.c_str());
    if (r.stopped) throw Interrupted("state saved to " + out.string() + "; resume with: unjam pack --resume " + out.string());
    throw Error("no static packing within --max-steps");
  }
  print_report(out, r, pack_report(p, r));
}

}  // namespace

void add_pack_command(CLI::App& app) {
  auto o = std::make_shared<PackOptions>();
  CLI::App* cmd = app.add_subcommand(
      "pack", "compact a gas of disks into a static packing (or continue from a packing)");
  auto& d = o->compaction.dynamics;
  auto& st = o->compaction;
  cmd->add_option("--n", o->gas.N, "number of disks (radii uniform in [0.5, 1]; at least 8)")->capture_default_str();
  cmd->add_option("--mu", o->mu, "Coulomb friction coefficient")->capture_default_str();
  cmd->add_option("--seed", o->gas.seed, "seed of the random gas")->capture_default_str()->check(seed_value());
  cmd->add_option("--out", o->out, "output packing directory");
  cmd->add_option("--from", o->from, "start from this packing (re-relax at --mu / --p-ext) instead of a gas");
  cmd->add_option("--resume", o->resume, "continue a stopped compaction in place, with its settings");
  cmd->add_option("--p-ext", o->P_ext, "external pressure P_ext (pressure unit)")->capture_default_str();
  cmd->add_option("--phi-gas", o->gas.phi, "packing fraction of the initial gas")->capture_default_str();
  cmd->add_option("--dt", d.dt, "time step (t0 = R_max sqrt(rho/P_ext) at P_ext = 1)")->capture_default_str()->check(positive_number());
  cmd->add_option("--m-lambda", d.bath.M_lambda, "bath mass M_lambda")->capture_default_str()->check(positive_number());
  cmd->add_option("--tol", d.nlgs.tol, "NLGS tolerance alpha of the dynamics (force-change criterion)")->capture_default_str()->check(positive_number());
  cmd->add_option("--max-sweeps", d.nlgs.max_sweeps, "NLGS max sweeps per step of the dynamics")->capture_default_str()->check(positive_number());
  cmd->add_option("--detect", d.min_detection, "smallest contact detection distance (R_max)")->capture_default_str()->check(positive_number());
  cmd->add_option("--v-static", st.v_static, "try the static solve below this mean speed of loaded grains")->capture_default_str()->check(positive_number());
  cmd->add_option("--p-static", st.p_static, "... and when |P_in/P_ext - 1| is below this")->capture_default_str()->check(positive_number());
  cmd->add_option("--static-tol", st.final_solve.tol, "static residual target (force, torque / F0; pressure)")->capture_default_str()->check(positive_number());
  cmd->add_option("--touch-gap", st.final_solve.touch_gap, "pairs closer than this touch in the static solve (R_max)")->capture_default_str()->check(positive_number());
  cmd->add_option("--max-steps", st.max_steps, "give up after this many steps")->capture_default_str()->check(positive_number());
  cmd->add_option("--threads", o->threads, "OpenMP threads (0: all cores); results do not depend on it")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--checkpoint", o->checkpoint_s, "seconds between checkpoints written to --out")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--max-memory", o->max_memory_gb,
                  "refuse a run whose memory estimate exceeds this many GB (0: the physical memory)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_flag("--quiet", o->quiet, "no progress lines");
  cmd->callback([o] {
    o->command = command_line();
    run(*o);
  });
}

}  // namespace unjam::cli
