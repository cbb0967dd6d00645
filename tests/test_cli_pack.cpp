// `unjam pack` end to end: invalid parameters are refused with a clear message, a run
// interrupted midway leaves a complete (resumable) packing, and --resume / --from continue.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "cli_run.hpp"
#include "unjam/analysis/packing_stats.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam {
namespace {

namespace fs = std::filesystem;

using CommandRun = testing::ToolRun;
CommandRun unjam(const std::string& args) { return testing::run_tool(args); }

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("unjam-cli-pack-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

TEST(CliPack, InvalidParametersAreRefused) {
  const fs::path out = fresh_dir("invalid");
  const struct {
    std::string args, phrase;
  } cases[] = {
      {"--n 1", "at least 8"},
      {"--mu -0.1", "mu must be a finite number >= 0"},
      {"--p-ext 0", "P_ext must be a finite number > 0"},
      {"--dt -1", "--dt: must be a finite number > 0, got '-1'"},
      {"--phi-gas 0.9", "gas packing fraction"},
      {"--m-lambda 0", "--m-lambda: must be a finite number > 0, got '0'"},
  };
  for (const auto& c : cases) {
    const CommandRun r = unjam("pack " + c.args + " --out " + out.string() + " --quiet");
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.phrase), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out / "meta.json")) << "nothing written for " << c.args;
  }
  EXPECT_EQ(unjam("pack --from " + (out / "missing").string() + " --out " + out.string()).exit_code, 1);
}

TEST(CliPack, FrictionlessPackingReportsItsRedundantContacts) {
  // Seed 3 of a 60-disk frictionless packing ends with one contact more than isostatic (an
  // overlap of ~tol makes a pair touch); seed 1 ends isostatic. Only the first gets the hint
  // to pack with tighter dynamics.
  const fs::path out = fresh_dir("mu0");
  const CommandRun redundant = unjam("pack --n 60 --mu 0 --seed 3 --out " + out.string() + " --quiet");
  ASSERT_EQ(redundant.exit_code, 0) << redundant.output;
  EXPECT_NE(redundant.output.find("isostatic count (contacts - (2N'-1)): 1"), std::string::npos)
      << redundant.output;
  EXPECT_NE(redundant.output.find("1 redundant contact(s)"), std::string::npos) << redundant.output;
  EXPECT_NE(redundant.output.find("--tol 1e-6 --max-sweeps 2000"), std::string::npos)
      << redundant.output;
  const CommandRun isostatic = unjam("pack --n 60 --mu 0 --seed 1 --out " + out.string() + " --quiet");
  ASSERT_EQ(isostatic.exit_code, 0) << isostatic.output;
  EXPECT_NE(isostatic.output.find("isostatic count (contacts - (2N'-1)): 0"), std::string::npos)
      << isostatic.output;
  EXPECT_EQ(isostatic.output.find("redundant contact"), std::string::npos) << isostatic.output;
  fs::remove_all(out);
}

TEST(CliPack, InterruptedRunLeavesAResumablePacking) {
  const fs::path out = fresh_dir("interrupt");
  const std::string args = "pack --n 800 --mu 0.1 --seed 2 --threads 1 --quiet --out " + out.string();
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", (std::string("exec ") + UNJAM_BINARY + " " + args + " >/dev/null 2>&1").c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  ::kill(pid, SIGINT);  // as Ctrl-C
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3) << "an interrupted run exits 3: stopped, resumable (README)";

  // The saved state is a complete packing, not yet static, with no temporary files left.
  const Packing stopped = read_packing(out);
  EXPECT_FALSE(stopped.state.is_static);
  EXPECT_GT(stopped.state.step, 0);
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << e.path();

  // Resuming finishes the compaction in place, from the saved step on.
  const CommandRun resumed = unjam("pack --resume " + out.string() + " --quiet");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const Packing done = read_packing(out);
  EXPECT_TRUE(done.state.is_static);
  EXPECT_GT(done.state.step, stopped.state.step);
  const PackingStats s = compute_packing_stats(done);
  EXPECT_LT(s.max_force_residual, 1e-8);
  EXPECT_NEAR(s.pressure_ratio, 1.0, 1e-8);
  fs::remove_all(out);
}

TEST(CliPack, ReRelaxAtHigherFrictionKeepsTheOriginal) {
  const fs::path base = fresh_dir("base"), higher = fresh_dir("higher");
  ASSERT_EQ(unjam("pack --n 120 --mu 0 --seed 3 --quiet --out " + base.string()).exit_code, 0);
  const std::string before = read_packing(base).meta.command;
  const CommandRun r = unjam("pack --from " + base.string() + " --mu 0.5 --quiet --out " + higher.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Packing p = read_packing(higher);
  EXPECT_TRUE(p.state.is_static);
  EXPECT_DOUBLE_EQ(p.meta.contact.mu, 0.5);
  EXPECT_EQ(read_packing(base).meta.command, before) << "the source packing is untouched";
  const PackingStats s = compute_packing_stats(p);
  EXPECT_EQ(s.max_coulomb_violation, 0.0);
  EXPECT_LT(s.max_force_residual, 1e-8);
  fs::remove_all(base);
  fs::remove_all(higher);
}

}  // namespace
}  // namespace unjam
