// PLACEHOLDER: replaced by the real command.
#include "cli/commands.hpp"
namespace unjam::cli {
void add_pack_command(CLI::App& app) { app.add_subcommand("pack", "(not yet built)"); }
}  // namespace unjam::cli
