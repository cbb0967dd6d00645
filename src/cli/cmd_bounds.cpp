// PLACEHOLDER: replaced by the real command.
#include "cli/commands.hpp"
namespace unjam::cli {
void add_bounds_command(CLI::App& app) { app.add_subcommand("bounds", "(not yet built)"); }
}  // namespace unjam::cli
