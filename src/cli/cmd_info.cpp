// `unjam info DIR`: reads a packing and prints its statistics and static checks
// (PackingStats), as aligned text or, with --json, as one JSON object.
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

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

nlohmann::ordered_json stats_json(const std::string& dir, const Packing& p, const PackingStats& s,
                                  const GeometryReport& g, double threshold) {
  nlohmann::ordered_json j = {
      {"packing", dir},
      {"program_version", p.meta.program_version},
      {"seed", p.meta.seed},
      {"N", s.N},
      {"Lx", p.cell.Lx},
      {"Ly", p.cell.Ly},
      {"P_ext", p.meta.P_ext},
      {"mu", s.mu},
      {"F0", s.F0},
      {"phi", s.phi},
      {"z", s.z},
      {"rattlers", s.rattlers},
      {"N_prime", s.N_prime},
      {"force_threshold_F0", threshold},
      {"contacts_force_carrying", s.N_c},
      {"contacts_listed", s.contacts},
      {"F_cont_over_F0", s.F_cont},
      {"F_mean_listed_over_F0", s.F_mean_listed},
      {"max_overlap", s.max_overlap},
      {"mean_overlap", s.mean_overlap},
      {"max_force_residual_over_F0", s.max_force_residual},
      {"mean_force_residual_over_F0", s.mean_force_residual},
      {"max_torque_residual_over_F0R", s.max_torque_residual},
      {"P_in", s.P_in},
      {"P_in_over_P_ext", s.pressure_ratio},
      {"max_coulomb_violation_over_F0", s.max_coulomb_violation},
      {"max_tension_over_F0", s.max_tension},
      {"geometry_max_branch_mismatch", g.max_branch_mismatch},
      {"geometry_max_normal_mismatch", g.max_normal_mismatch},
      {"geometry_max_gap_mismatch", g.max_gap_mismatch},
      {"geometry_worst_over_tolerance", g.worst_ratio},
  };
  if (s.isostatic_excess) j["isostatic_excess"] = *s.isostatic_excess;
  return j;
}

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
  row("P_ext", num(p.meta.P_ext));
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
      std::printf("%s\n", stats_json(opt->dir, p, s, g, opt->threshold).dump(2).c_str());
    else
      print_text(opt->dir, p, s, g, opt->threshold);
  });
}

}  // namespace unjam::cli
