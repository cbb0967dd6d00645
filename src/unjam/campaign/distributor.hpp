#pragma once
// Which WorkDistributor (core/work_source.hpp) a campaign runs on:
//   - launched by `mpirun -n K` (K > 1) in a build with MPI (CMake option UNJAM_MPI): the K
//     ranks of the job. Rank 0 hands out tasks on request from a server thread (a work
//     queue: one small message per request, dynamic load balance) and computes too; every
//     result travels to rank 0, which gathers it, writes checkpoints and the outputs.
//   - otherwise one process, or with --shard i/K the tasks at places p with p mod K == i of
//     the loop's whole list (core/work_source's in_shard), one job of a scheduler job array
//     (outputs merged afterwards by `unjam merge`).
// See docs/ARCHITECTURE.md ("Campaigns") and README ("On a cluster").
#include <memory>
#include <string>

#include "unjam/core/work_source.hpp"

namespace unjam {

// Whether an MPI launcher (mpirun, srun) started this process: its environment says so.
bool launched_by_mpi();
// Whether this build can run campaigns over MPI.
bool mpi_available();

// The distributor for a campaign (starting MPI on first use when launched by mpirun).
// Throws unjam::Error for --shard together with several MPI ranks, or for several ranks in a
// build without MPI (each would compute the whole campaign and write the same files).
std::unique_ptr<WorkDistributor> make_distributor(int shard = 0, int shards = 1);

// Parses "i/K" of --shard into (i, K); throws unjam::Error for anything else.
std::pair<int, int> parse_shard(const std::string& text);

// Ends the MPI job of this process, if one was started: MPI_Finalize once every rank is
// here; after a failure (exit_code != 0), MPI_Abort of every rank if they are not all here
// within 2 s (the others may wait for this one forever). Nothing without MPI.
void end_mpi_job(int exit_code);

}  // namespace unjam
