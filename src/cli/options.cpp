#include "cli/options.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include "unjam/ensemble/force_bounds.hpp"
#include "unjam/probe/cd_path.hpp"

namespace unjam::cli {
namespace {

std::optional<double> finite_number(const std::string& s) {
  std::string_view v(s);
  if (!v.empty() && v.front() == '+') v.remove_prefix(1);
  double x = 0.0;
  const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
  if (v.empty() || ec != std::errc() || ptr != v.data() + v.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

}  // namespace

CLI::Validator seed_value() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        std::uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || s.front() == '-' || s.front() == '+' || ec != std::errc() || ptr != s.data() + s.size())
          return "a seed is an integer from 0 to 18446744073709551615, got '" + s + "'";
        return {};
      },
      "SEED");
}

namespace {

// A finite number > 0 (positive) or >= 0.
CLI::Validator finite_number_check(bool positive) {
  const std::string bound = positive ? "> 0" : ">= 0";
  return CLI::Validator(
      [positive, bound](std::string& s) -> std::string {
        const auto v = finite_number(s);
        if (!v || (positive ? !(*v > 0.0) : !(*v >= 0.0))) return "must be a finite number " + bound + ", got '" + s + "'";
        return {};
      },
      "NUMBER " + bound);
}

}  // namespace

CLI::Validator non_negative_number() { return finite_number_check(false); }

CLI::Validator positive_number() { return finite_number_check(true); }

void add_contact_selection_options(CLI::App* cmd, double& gap_tol, double& fn_tol) {
  cmd->add_option("--gap-tol", gap_tol, "touching contacts: gap < gap-tol (R_max)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--fn-tol", fn_tol, "force-carrying contacts: fn > fn-tol F0")
      ->capture_default_str()->check(non_negative_number());
}

void add_lp_tol_option(CLI::App* cmd, double& lp_tol, const std::string& applies) {
  cmd->add_option("--lp-tol", lp_tol,
                  applies + "CLP's primal and dual feasibility tolerance (docs/ensemble.md, \"The LP's tolerances\")")
      ->capture_default_str()->check(positive_number() & CLI::Range(kMinLpTolerance, kMaxLpTolerance));
}

void add_lp_tolerance_options(CLI::App* cmd, double& lp_tol, double& open_tol) {
  add_lp_tol_option(cmd, lp_tol);
  cmd->add_option("--open-tol", open_tol,
                  "a contact some admissible network loads with fn <= open-tol F0 can open: its fn_min is 0")
      ->capture_default_str()->check(positive_number() & CLI::Range(0.0, kMaxOpenTolF0));
}

void add_cd_path_options(CLI::App* cmd, CdPathSettings& cd, std::string& start) {
  cmd->add_option("--cd-start", start,
                  "cd: where the path starts: static (the static network; the solution the step's "
                  "dynamics from rest reach) or lp (the lp probe's optimum; finds another solution "
                  "where the step has several, on small packings: it fails at 500 disks) or compliant (the static network "
                  "at a soft compliance, lowered to the rigid step: the rigid limit of stiff contacts; fast, but at 500 "
                  "disks another solution than static's) or interior (the iterate of an interior-point method on the step: "
                  "fewer pieces at low friction; docs/probe.md, \"Where the path starts\", \"An interior-point start\") or "
                  "inertial (the interior start on the step at a tenth of dt, more inertia, continued in dt to the "
                  "quasi-static step: the limit of vanishing inertia; another selection, which solves some probes the "
                  "others do not and loses others under a budget; docs/probe.md, \"The quasi-static step as the limit of vanishing inertia\") "
                  "or interior-inertial (the interior start within --cd-interior-share of the budget, then the inertial start's "
                  "continuation in dt where it is not exact)")
      ->capture_default_str();
  cmd->add_option(
      "--cd-softer-starts", cd.softer_starts,
      "cd, compliant and interior starts: where the continuation (the interior start's fallback) ends without an "
      "exact solution, follow it again from 10x "
      "and then 100x ... its starting compliance, this many times (0: one start; docs/probe.md, \"Where the path "
      "starts\")")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--cd-compliant-start", cd.compliant_start,
                  "cd, compliant and interior starts: the compliance (a fraction of g / (dt^2 F0)) at which the "
                  "compliant continuation's first path is followed from the static network before it is lowered to "
                  "the rigid step; lower is closer to the static branch and, at 1000 disks with mu = 1, solves more "
                  "probes (docs/probe.md, \"Where the continuation starts\")")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--cd-interior-states-pieces", cd.interior_states_pieces,
                  "cd, interior start: the first path starts from the interior-point iterate's own states and is cut "
                  "after this many pieces per contact of the step (0: no such path, only the paths from the states of "
                  "the iterate's forces; docs/probe.md, \"The iterate's own states\")")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--cd-interior-states-stall", cd.interior_states_stall,
                  "cd, interior start: cut the path from the iterate's own states where its opening has not passed "
                  "the largest one it reached for this many pieces (0: no such cut; docs/probe.md, \"The iterate's "
                  "own states\")")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--cd-interior-states-retries", cd.interior_states_retries,
                  "cd, interior start: where the path from the iterate's own states is not exact, follow it again at "
                  "10x its compliance, this many times, each at 10x the last (0: no retry; docs/probe.md, "
                  "\"The iterate's own states\")")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--cd-interior-iterations", cd.interior_max_iterations,
                  "cd, interior start: at most this many iterations of the interior-point method (its own tests "
                  "end it at 40-50 at 500-2000 disks; docs/probe.md, \"The interior-point method's iterations\")")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--cd-interior-neighbourhood", cd.interior_neighbourhood,
                  "cd, interior start: where the interior-point method ends at a natural residual above 1e-3, run "
                  "it again with every pair's z w kept above this fraction of their mean, and start from the "
                  "iterate with the lower residual, then from the other (0: no second run; e.g. 1e-3; in [0, 1); "
                  "docs/probe.md, \"Keeping the iterates centred\")")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--cd-interior-share", cd.interior_share,
                  "cd, interior-inertial start: the fraction of --cd-max-pieces the interior start may take "
                  "before the inertial start's continuation in dt takes the rest (in (0, 1); docs/probe.md, "
                  "\"The interior start first, the continuation in dt where it fails\")")
      ->capture_default_str();
  // The continuation in dt of the inertial and interior-inertial starts (CdPathSettings::
  // inertial_factor to inertial_jumps; docs/probe.md, "The quasi-static step as the limit of
  // vanishing inertia"). Their ranges are checked by validate(CdPathSettings), as the library's.
  cmd->add_option("--cd-inertial-factor", cd.inertial_factor,
                  "cd, inertial and interior-inertial starts: the continuation in dt starts from the step at dt / "
                  "this (this^2 times the inertia of its grains), > 1")
      ->capture_default_str();
  cmd->add_option("--cd-inertial-stages", cd.inertial_stages,
                  "cd, inertial and interior-inertial starts: the continuation advances log dt by at most "
                  "log(--cd-inertial-factor) / this per stage, >= 1")
      ->capture_default_str();
  cmd->add_option("--cd-inertial-halvings", cd.inertial_halvings,
                  "cd, inertial and interior-inertial starts: a stage that is not exact is tried again with half "
                  "its step in dt, up to this many times in a row before the branch counts as folded, >= 0")
      ->capture_default_str();
  cmd->add_option("--cd-inertial-retries", cd.inertial_retries,
                  "cd, inertial and interior-inertial starts: where the first stage is not exact, start again at "
                  "sqrt(10) times less dt, this many times, >= 0")
      ->capture_default_str();
  cmd->add_option("--cd-inertial-jumps", cd.inertial_jumps,
                  "cd, inertial and interior-inertial starts: past a fold in dt, the interior start at the next dt "
                  "jumps to another branch, at most this many times per probe, >= 0")
      ->capture_default_str();
  cmd->add_option("--cd-max-pieces", cd.max_probe_pieces,
                  "cd: stop a probe once its paths together have taken this many pieces, keeping the best "
                  "solution met so far (if any; counted as stopped by the budget). Deterministic, so a campaign "
                  "gives the same bytes with any number of threads (docs/probe.md, \"A budget of pieces per probe\"; "
                  "0: no limit)")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--cd-accept-residual", cd.accept_residual,
                  "cd: stop a probe's search at the first solution with a residual at most this (in g; from 1e-6, "
                  "where only an exact solution stops it, to 1e-3); such a probe is near-exact, not converged, and "
                  "enters the means as near-exact probes do. The paths after a near-exact solution take most of a "
                  "near-exact probe's pieces at 1000 disks (docs/probe.md, \"Accepting a near-exact solution\")")
      ->capture_default_str()
      ->check(positive_number());
  cmd->add_option("--cd-settle-compliance", cd.settle_compliance,
                  "cd: end a path at its first exact solution once its compliance (a fraction of g / (dt^2 F0)) is "
                  "at or below this, instead of lowering it on to the rigid step (0: never, the path's rigid limit). "
                  "At low friction the forces have settled by 1e-5 and the last lowerings can spend a probe's budget; "
                  "at mu = 1 it may return another of the step's exact solutions (docs/probe.md, \"Settling at an "
                  "exact solution\")")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--cd-lost-factor", cd.lost_factor,
                  "cd: drop a path whose forces at the full opening have a residual above this factor times its "
                  "compliance (at least 1e-3) in g: its solves went through nearly singular state sets and lost "
                  "their digits. It is not lowered, and the compliant continuation goes on to its next softer "
                  "start instead of restarting below it (0: off, such a path is lowered and restarted as any other; "
                  "e.g. 1e3; docs/probe.md, \"Paths that lose their digits\")")
      ->capture_default_str()
      ->check(non_negative_number());
  cmd->add_option("--cd-restart-floor", cd.restart_floor,
                  "cd, compliant and interior starts: follow no restart of the compliant continuation below this "
                  "compliance (a fraction of g / (dt^2 F0)); the next softer start is followed instead (0: every "
                  "restart; docs/probe.md, \"Restarts below a floor\")")
      ->capture_default_str()
      ->check(non_negative_number());
}

}  // namespace unjam::cli
