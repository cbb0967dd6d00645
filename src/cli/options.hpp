#pragma once
// Checks of option values shared by the subcommands, applied by CLI11 to the text given on
// the command line, before it is converted: a seed is an unsigned decimal integer (no sign,
// at most 2^64 - 1: a negative one would wrap round), a count or duration is a finite number
// >= 0, a tolerance or step a finite number > 0 (never nan or inf).
#include <CLI/CLI.hpp>

namespace unjam {
struct CdPathSettings;
}

namespace unjam::cli {

CLI::Validator seed_value();            // 0 .. 18446744073709551615
CLI::Validator non_negative_number();   // finite, >= 0
CLI::Validator positive_number();       // finite, > 0

// --gap-tol and --fn-tol of the commands over the admissible set (bounds, threshold, ensemble):
// which contacts enter it (docs/ensemble.md, "Which contacts and rows enter").
void add_contact_selection_options(CLI::App* cmd, double& gap_tol, double& fn_tol);

// --lp-tol: ForceLP's tolerance in [kMinLpTolerance, kMaxLpTolerance] (lp/force_lp.hpp;
// docs/ensemble.md, "The LP's tolerances"), for every command that solves the LP (bounds,
// ensemble, probe --method lp); `applies` heads its help (e.g. "lp: ").
void add_lp_tol_option(CLI::App* cmd, double& lp_tol, const std::string& applies = "");

// --lp-tol and --open-tol of the commands that compute the force bounds (bounds, ensemble):
// add_lp_tol_option and ForceBoundsOptions::open_tol_F0 in (0, kMaxOpenTolF0]
// (ensemble/force_bounds.hpp).
void add_lp_tolerance_options(CLI::App* cmd, double& lp_tol, double& open_tol);

// --cd-start (into `start`: a name of cd_start_from_name) and the other --cd-* options of the
// exact probe (into `cd`'s fields; docs/probe.md), for every command that runs it (probe,
// ensemble --probe cd).
void add_cd_path_options(CLI::App* cmd, CdPathSettings& cd, std::string& start);

}  // namespace unjam::cli
