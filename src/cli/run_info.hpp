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

// While alive, Ctrl-C (SIGINT) and SIGTERM do not kill the process but set a flag that long
// runs poll, so they stop at a clean point and save their state. The default handlers come
// back when it goes out of scope, also when the run throws.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static bool requested();
};

}  // namespace unjam::cli
