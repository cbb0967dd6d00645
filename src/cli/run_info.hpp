#pragma once
// What every command records and prints about its own run: the command line that started
// it (stored in every output), its thread count and durations in a readable form.
#include <string>

namespace unjam::cli {

void set_command_line(int argc, char** argv);
const std::string& command_line();

// Threads of a run from its --threads option: 0 means all cores (OpenMP's maximum).
int thread_count(int requested);

// The machine's physical memory (bytes).
double physical_memory_bytes();

// "512 MB", "3.2 GB", "8000 GB".
std::string format_bytes(double bytes);

// "42.0 s", "3 min 05 s", "2 h 10 min".
std::string format_duration(double seconds);
// A short time (CPU per probe, for instance) to three significant digits below a minute
// ("0.0123 s", "4.56 s"), as format_duration beyond.
std::string format_seconds(double seconds);

// Called first in main: SIGINT and SIGTERM are blocked in the main thread and in every
// thread made from it (OpenMP's, MPI's) and taken by one listening thread, so that no handler
// runs inside the computation (METIS installs its own for SIGTERM during its calls,
// core/nested_dissection). Threads a library made before main (OpenBLAS's pool) do not block
// them and run the same handler. Outside an InterruptGuard they end the process as by default.
void listen_for_interrupts();

// While alive, Ctrl-C (SIGINT) and SIGTERM do not kill the process but set a flag that long
// runs poll, so they stop at a clean point and save their state. Their default action comes
// back when it goes out of scope, also when the run throws. Needs listen_for_interrupts().
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static bool requested();
};

}  // namespace unjam::cli
