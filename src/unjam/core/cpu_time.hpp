#pragma once
// CPU time of the calling thread, for reports of where a computation spent its time. Never
// part of a result: it differs from run to run (docs/benchmarks.md, "Machine and conditions").
#include <ctime>

namespace unjam {

// Seconds of CPU the calling thread has used (CLOCK_THREAD_CPUTIME_ID; 0 where unavailable).
inline double thread_cpu_seconds() {
  timespec t{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t) != 0) return 0.0;
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace unjam
