// PLACEHOLDER: replaced by the real command.
#include "cli/commands.hpp"
namespace unjam::cli {
void add_info_command(CLI::App& app) { app.add_subcommand("info", "(not yet built)"); }
}  // namespace unjam::cli
