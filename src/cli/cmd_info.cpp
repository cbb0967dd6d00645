// `unjam info DIR`: reads a packing and prints its statistics and static checks
// (PackingStats), as aligned text or, with --json, as one JSON object.
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.hpp"
#include "unjam/analysis/packing_stats.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/geometry_check.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam::cli {

namespace {

struct InfoOptions {
  std::string dir;
  bool json = false;
  double threshold = 1e-9;  // force-carrying: fn > threshold * F0
};

void print_text(const std::string& dir, const Packing& p, const PackingStats& s, const GeometryReport& g,
                double threshold) {
  auto row = [](const char* label, const std::string& value) { std::printf("%-34s %s\n", label, value.c_str()); };
  auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return std::string(buf);
  };
  const std::string version = p.meta.program_version.empty() ? "(not recorded)" : p.meta.program_version;
  row("packing", dir);
  row("written by unjam", version);
  row("seed", std::to_string(p.meta.seed));
  row("N", std::to_string(s.N));
  row("cell Lx x Ly", num(p.cell.Lx) + " x " + num(p.cell.Ly));
  row("mu", num(s.mu));
  row("P_ext", num(p.meta.contact.P_ext));
  row("F0 = 2 R_avg P_ext", num(s.F0));
  row("phi", num(s.phi));
  row("z (rattlers excluded)", num(s.z));
  row("rattlers", std::to_string(s.rattlers) + " (N' = " + std::to_string(s.N_prime) + ")");
  row("contacts: carrying force / listed",
      std::to_string(s.N_c) + " / " + std::to_string(s.contacts) + "  (fn > " + num(threshold) + " F0)");
  row("<F_cont> / F0", num(s.F_cont) + "  (all listed: " + num(s.F_mean_listed) + ")");
  row("overlap: max / mean", num(s.max_overlap) + " / " + num(s.mean_overlap));
  row("force residual / F0: max / mean", num(s.max_force_residual) + " / " + num(s.mean_force_residual));
  row("torque residual / (F0 R): max", num(s.max_torque_residual));
  row("P_in / P_ext", num(s.pressure_ratio));
  row("Coulomb violation / F0: max", num(s.max_coulomb_violation));
  row("tension / F0: max", num(s.max_tension));
  if (s.isostatic_excess)
    row("isostatic count N_c - (2N' - 1)", std::to_string(*s.isostatic_excess));
  // The contact rows against the positions (packing/geometry_check.hpp).
  row("geometry mismatch: l / n / gap", num(g.max_branch_mismatch) + " / " + num(g.max_normal_mismatch) + " / " +
                                            num(g.max_gap_mismatch) + "  (worst " + num(g.worst_ratio) +
                                            " x tolerance" +
                                            (g.worst_contact ? ", contact " + std::to_string(*g.worst_contact) : "") + ")");
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto opt = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand("info", "print the statistics and static checks of a packing");
  cmd->add_option("dir", opt->dir, "Packing directory (meta.json, particles.csv, contacts.csv)")->required();
  cmd->add_flag("--json", opt->json, "Print one JSON object instead of text");
  cmd->add_option("--threshold", opt->threshold, "A contact carries force when fn > threshold * F0")
      ->capture_default_str();
  cmd->callback([opt] {
    if (!(opt->threshold >= 0.0)) throw Error("--threshold must be a non-negative number");
    const Packing p = read_packing(opt->dir);
    const PackingStats s = compute_packing_stats(p, opt->threshold);
    const GeometryReport g = check_geometry(p);
    if (opt->json)
      std::printf("%s\n", stats_json(p, s, opt->threshold, opt->dir).dump(2).c_str());
    else
      print_text(opt->dir, p, s, g, opt->threshold);
  });
}

}  // namespace unjam::cli
