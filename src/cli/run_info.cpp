#include "cli/run_info.hpp"

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <thread>

#include <omp.h>
#include <pthread.h>
#include <unistd.h>

namespace unjam::cli {
namespace {
std::string g_command_line;
std::atomic<int> g_signal{0};  // the interrupt received while a guard was alive
std::atomic<int> g_guards{0};  // guards alive

// What an interrupt does: while a guard is alive it sets the flag the runs poll; otherwise it
// takes the signal's default action, ending the process as it would without the guard.
// Async-signal-safe (lock-free atomics, signal, raise): also the handler of the threads that
// do not block the interrupts (those a library starts before main, as OpenBLAS's pool).
extern "C" void on_signal(int sig) {
  if (g_guards > 0) {
    g_signal = sig;
    return;
  }
  std::signal(sig, SIG_DFL);
  ::raise(sig);
}

sigset_t interrupt_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  return set;
}

// The thread that receives SIGINT and SIGTERM in place of every thread made from main on
// (they block them). For the default action it unblocks the signal before raising it.
void listen() {
  const sigset_t set = interrupt_signals();
  for (;;) {
    int sig = 0;
    if (::sigwait(&set, &sig) != 0) continue;
    if (g_guards == 0) ::pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
    on_signal(sig);
  }
}
}  // namespace

void listen_for_interrupts() {
  // Not ignored (a shell's background job inherits SIGINT ignored): the guard's stop applies.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const sigset_t set = interrupt_signals();
  ::pthread_sigmask(SIG_BLOCK, &set, nullptr);  // inherited by every thread made from here on
  std::thread(listen).detach();
}

InterruptGuard::InterruptGuard() {
  g_signal = 0;
  ++g_guards;
}

InterruptGuard::~InterruptGuard() { --g_guards; }

bool InterruptGuard::requested() { return g_signal != 0; }

void set_command_line(int argc, char** argv) {
  g_command_line.clear();
  for (int i = 0; i < argc; ++i) {
    if (i > 0) g_command_line += ' ';
    g_command_line += argv[i];
  }
}

const std::string& command_line() { return g_command_line; }

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

double physical_memory_bytes() {
  return static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
}

std::string format_bytes(double bytes) {
  char buf[48];
  if (bytes < 1e9) std::snprintf(buf, sizeof buf, "%.0f MB", bytes / 1e6);
  else std::snprintf(buf, sizeof buf, "%.1f GB", bytes / 1e9);
  return buf;
}

std::string format_duration(double s) {
  char buf[48];
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 60) std::snprintf(buf, sizeof buf, "%.1f s", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%d min %02d s", int(s / 60), int(s) % 60);
  else std::snprintf(buf, sizeof buf, "%d h %02d min", int(s / 3600), int(s / 60) % 60);
  return buf;
}

std::string format_seconds(double s) {
  if (!std::isfinite(s) || s < 0 || s >= 60) return format_duration(s);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g s", s);
  return buf;
}

}  // namespace unjam::cli
