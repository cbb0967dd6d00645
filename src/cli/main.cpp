// unjam: mechanics of jammed packings of rigid frictional disks.
#include <cstdio>
#include <exception>

#include "cli/commands.hpp"
#include "cli/run_info.hpp"
#include "unjam/campaign/distributor.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"

int main(int argc, char** argv) {
  unjam::cli::listen_for_interrupts();  // before any thread: OpenMP's, MPI's
  CLI::App app{"unjam: jammed packings of rigid frictional disks (contact dynamics, local "
               "perturbation probe, force-network ensemble)"};
  app.set_version_flag("--version", unjam::kVersion);
  app.require_subcommand(1);
  unjam::cli::set_command_line(argc, argv);
  unjam::cli::add_pack_command(app);
  unjam::cli::add_info_command(app);
  unjam::cli::add_probe_command(app);
  unjam::cli::add_bounds_command(app);
  unjam::cli::add_threshold_command(app);
  unjam::cli::add_ensemble_command(app);
  unjam::cli::add_merge_command(app);
  unjam::cli::add_export_command(app);
  // Exit codes (README, "Exit codes"): 0 done, 1 error (bad input or parameters, a result
  // that is not valid), 2 internal error, 3 interrupted with the state saved (resumable).
  int code = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    code = app.exit(e) == 0 ? 0 : 1;  // --help and --version exit 0, CLI11's own codes are >= 100
  } catch (const unjam::Interrupted& e) {
    std::fprintf(stderr, "unjam: interrupted: %s\n", e.what());
    code = 3;
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
