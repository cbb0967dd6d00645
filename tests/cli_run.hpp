#pragma once
// Runs the built `unjam` tool (or any shell command: mpirun) through the shell and collects
// its exit code and output (stdout and stderr), for the end-to-end tests; and makes writable
// copies of the fixtures.
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace unjam::testing {

struct ToolRun {
  int exit_code;       // -1 if the tool did not exit normally
  std::string output;  // stdout and stderr
};

// Runs a shell command (stdout and stderr collected).
inline ToolRun run_command(const std::string& command) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return {-1, "popen failed"};
  std::string out;
  char buf[4096];
  while (const std::size_t n = std::fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// Runs the built tool with `args`.
inline ToolRun run_tool(const std::string& args) { return run_command(std::string("'") + UNJAM_BINARY + "' " + args); }

// A writable copy of the fixture packing `name` (tests/fixtures) as `to`/`as`.
inline std::filesystem::path copy_fixture(const std::string& name, const std::filesystem::path& to,
                                          const std::string& as = "") {
  namespace fs = std::filesystem;
  const fs::path dst = to / (as.empty() ? name : as);
  fs::copy(fs::path(UNJAM_FIXTURES_DIR) / name, dst, fs::copy_options::recursive);
  for (const auto& e : fs::directory_iterator(dst))
    fs::permissions(e.path(), fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::add);
  return dst;
}

}  // namespace unjam::testing
