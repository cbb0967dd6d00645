// unjam: mechanics of jammed packings of rigid frictional disks.
#include <cstdio>
#include <exception>

#include "cli/commands.hpp"
#include "cli/run_info.hpp"
#include "unjam/campaign/distributor.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"

int main(int argc, char** argv) {
  CLI::App app{"unjam: jammed packings of rigid frictional disks (contact dynamics, local "
               "perturbation probe, force-network ensemble)"};
  app.set_version_flag("--version", unjam::kVersion);
  app.require_subcommand(1);
  unjam::cli::set_command_line(argc, argv);
  unjam::cli::add_pack_command(app);
  unjam::cli::add_info_command(app);
  unjam::cli::add_probe_command(app);
  unjam::cli::add_bounds_command(app);
  unjam::cli::add_ensemble_command(app);
  unjam::cli::add_merge_command(app);
  unjam::cli::add_export_command(app);
  int code = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    code = app.exit(e);
  } catch (const unjam::Error& e) {
    std::fprintf(stderr, "unjam: error: %s\n", e.what());
    code = 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "unjam: internal error: %s\n", e.what());
    code = 2;
  }
  unjam::end_mpi_job(code);  // under mpirun: finalize, or stop every rank after a failure
  return code;
}
