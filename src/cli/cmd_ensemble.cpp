// PLACEHOLDER: replaced by the real command.
#include "cli/commands.hpp"
namespace unjam::cli {
void add_ensemble_command(CLI::App& app) { app.add_subcommand("ensemble", "(not yet built)"); }
}  // namespace unjam::cli
