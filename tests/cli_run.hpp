#pragma once
// Runs the built `unjam` tool through the shell and collects its exit code and output
// (stdout and stderr), for the end-to-end tests.
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace unjam::testing {

struct ToolRun {
  int exit_code;       // -1 if the tool did not exit normally
  std::string output;  // stdout and stderr
};

inline ToolRun run_tool(const std::string& args) {
  const std::string cmd = std::string("'") + UNJAM_BINARY + "' " + args + " 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  while (const std::size_t n = std::fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace unjam::testing
