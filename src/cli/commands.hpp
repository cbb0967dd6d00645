#pragma once
// The subcommands of the `unjam` tool; each lives in its own cmd_*.cpp and registers its
// options and its callback on the application.
#include <CLI/CLI.hpp>

namespace unjam::cli {

void add_pack_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_probe_command(CLI::App& app);
void add_bounds_command(CLI::App& app);
void add_threshold_command(CLI::App& app);
void add_ensemble_command(CLI::App& app);
void add_merge_command(CLI::App& app);
void add_export_command(CLI::App& app);

}  // namespace unjam::cli
