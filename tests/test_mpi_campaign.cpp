// Campaigns spread over processes, end to end with the real executable: `mpirun -n 2` and
// `-n 3` (oversubscribed on any machine), a run stopped (--stop-after) or killed (SIGKILL)
// and resumed with another number of ranks, and a job array of shards joined by `unjam merge`,
// each against one plain process on the p50 fixture (the kill: a 200-disk packing, slow
// enough to kill): the same bytes (docs/ARCHITECTURE.md, "Campaigns").
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {
namespace {

namespace fs = std::filesystem;

const fs::path kP50 = fs::path(UNJAM_FIXTURES_DIR) / "p50-mu0.1";

using CommandResult = testing::ToolRun;

CommandResult shell(const std::string& cmd) { return testing::run_command(cmd); }

// Every file of `dir` by name with its contents: what `merge --status` must leave as it was.
std::string listing(const fs::path& dir) {
  std::string names;
  for (const auto& e : fs::directory_iterator(dir)) names += e.path().filename().string() + " " + read_file(e.path());
  return names;
}

std::string unjam(int ranks, const std::string& args) {
  const std::string bin = std::string("'") + UNJAM_BINARY + "' " + args;
  if (ranks == 0) return bin;
  // CI runs as root, which Open MPI refuses without these two variables.
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe -n " +
         std::to_string(ranks) + " " + bin;
}

// probe_summary.json without what records the run itself (its duration and per-rank loads).
std::string summary_of_results(const fs::path& dir) {
  nlohmann::json j = nlohmann::json::parse(read_file(dir / "probe_summary.json"));
  j.erase("wall_seconds");
  j.erase("ranks");
  j.erase("all_runs");
  j.erase("cpu_per_probe");  // measurements, like the times above
  j.erase("command");
  return j.dump(2);
}

class Distributed : public ::testing::Test {
 protected:
  void SetUp() override {
#if !UNJAM_TEST_MPI
    GTEST_SKIP() << "built without MPI (UNJAM_MPI off)";
#endif
    root_ = fs::temp_directory_path() / ("unjam-mpi-" + std::to_string(std::random_device{}()));
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // `unjam probe p50 --all` into OUT/name with `ranks` MPI ranks (0: no mpirun), one thread each.
  fs::path probe(const std::string& name, int ranks, const std::string& extra = "", int expect_code = 0) {
    const fs::path out = root_ / name;
    fs::create_directories(out);
    const CommandResult r = shell(unjam(ranks, "probe '" + kP50.string() + "' --all --method lp --threads 1 --quiet --out '" +
                                         out.string() + "' " + extra));
    EXPECT_EQ(r.exit_code, expect_code) << r.output;
    return out;
  }

  void expect_same_probe_outputs(const fs::path& a, const fs::path& b) {
    for (const char* f : {"probes.csv", "response_profile.csv", "response_field.csv"})
      EXPECT_EQ(read_file(a / f), read_file(b / f)) << f << " of " << b;
    EXPECT_EQ(summary_of_results(a), summary_of_results(b)) << b;
  }

  fs::path root_;
};

TEST_F(Distributed, ProbeOverTwoAndThreeRanksWritesTheBytesOfOneProcess) {
  const fs::path one = probe("one", 0);
  ASSERT_TRUE(fs::exists(one / "probes.csv"));
  const fs::path two = probe("two", 2), three = probe("three", 3);
  expect_same_probe_outputs(one, two);
  expect_same_probe_outputs(one, three);
  // The other ranks probed some contacts (how many depends on timing), and the loads add up.
  const auto ranks = nlohmann::json::parse(read_file(three / "probe_summary.json")).at("ranks");
  ASSERT_EQ(ranks.size(), 3u);
  long long probes = 0;
  for (const auto& r : ranks) probes += r.at("probes").get<long long>();
  EXPECT_GT(probes - ranks.at(0).at("probes").get<long long>(), 0) << ranks.dump();
  EXPECT_EQ(probes, nlohmann::json::parse(read_file(three / "probe_summary.json")).at("probes").get<long long>());
}

TEST_F(Distributed, ProbeStoppedOnTwoRanksResumesOnThree) {
  const fs::path one = probe("one", 0);
  const fs::path out = probe("resumed", 2, "--stop-after 20", 3);
  ASSERT_TRUE(fs::exists(out / "probe_checkpoint.json"));
  ASSERT_FALSE(fs::exists(out / "probes.csv"));
  const auto saved = nlohmann::json::parse(read_file(out / "probe_checkpoint.json"));
  const std::size_t done = saved.at("state").at("rows").size();
  EXPECT_GE(done, 20u);
  EXPECT_LT(done, 81u);
  probe("resumed", 3);
  EXPECT_FALSE(fs::exists(out / "probe_checkpoint.json"));
  expect_same_probe_outputs(one, out);
}

// Rows in OUT/probe_checkpoint.json (written atomically: whole or absent), 0 if none yet.
std::size_t checkpointed_rows(const fs::path& out) {
  const fs::path file = out / "probe_checkpoint.json";
  if (!fs::exists(file)) return 0;
  return nlohmann::json::parse(read_file(file)).at("state").at("rows").size();
}

// Starts `/bin/sh -c job` in a session of its own; its pid (the session's id), or -1. Open MPI
// puts each rank in a process group of its own, so killing mpirun's group would leave the
// ranks running; the session holds them all (session_processes).
pid_t spawn_in_own_session(const std::string& job) {
  const char* argv[] = {"/bin/sh", "-c", job.c_str(), nullptr};
  posix_spawnattr_t attr;
  if (::posix_spawnattr_init(&attr) != 0) return -1;
  pid_t pid = -1;
  if (::posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSID) != 0 ||
      ::posix_spawn(&pid, "/bin/sh", nullptr, &attr, const_cast<char**>(argv), environ) != 0)
    pid = -1;
  ::posix_spawnattr_destroy(&attr);
  return pid;
}

// The live (not zombie) processes of session `sid`, from /proc.
std::vector<pid_t> session_processes(pid_t sid) {
  std::vector<pid_t> pids;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t p = static_cast<pid_t>(std::stol(name));
    if (::getsid(p) != sid) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    std::getline(stat, line);
    const auto close = line.rfind(')');  // state follows the command name "(...)"
    if (close != std::string::npos && close + 2 < line.size() && line[close + 2] == 'Z') continue;
    pids.push_back(p);
  }
  return pids;
}

// A job killed outright (SIGKILL of mpirun and of every rank at once, as a node failure or a
// scheduler past its limit) in the middle of a campaign, then run again on another number of
// ranks: the bytes of one process.
TEST_F(Distributed, ProbeKilledOnTwoRanksResumesOnThree) {
  const fs::path packing = root_ / "p200";
  ASSERT_EQ(shell(unjam(0, "pack --n 200 --mu 0.1 --seed 1 --threads 1 --quiet --out '" + packing.string() + "'")).exit_code, 0);
  // 300 of the ~335 contacts: the job runs for seconds after the 10th row, so it is killed
  // mid-campaign even on a loaded machine.
  const std::string args = "probe '" + packing.string() + "' --sample 300 --seed 5 --method lp --threads 1 --quiet --out '";
  const fs::path one = root_ / "one", out = root_ / "killed";
  fs::create_directories(one);
  fs::create_directories(out);
  ASSERT_EQ(shell(unjam(0, args + one.string() + "'")).exit_code, 0);

  const pid_t pid = spawn_in_own_session("exec env " + unjam(2, args + out.string() + "' --checkpoint 0") + " >/dev/null 2>&1");
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (checkpointed_rows(out) < 10 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  // Kill every process of the session until none is left (a rank started meanwhile included).
  for (auto alive = session_processes(pid); !alive.empty() && std::chrono::steady_clock::now() < deadline;
       alive = session_processes(pid)) {
    for (const pid_t p : alive) ::kill(p, SIGKILL);
    ::waitpid(pid, nullptr, WNOHANG);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::waitpid(pid, nullptr, 0);
  ASSERT_TRUE(session_processes(pid).empty()) << "the job's processes outlived SIGKILL";
  const std::size_t done = checkpointed_rows(out);
  ASSERT_FALSE(fs::exists(out / "probes.csv")) << "the job ended before it was killed";
  ASSERT_GE(done, 10u);
  ASSERT_LT(done, 300u);

  const CommandResult resumed = shell(unjam(3, args + out.string() + "'"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resuming: " + std::to_string(done)), std::string::npos) << resumed.output;
  expect_same_probe_outputs(one, out);
}

// SIGTERM to mpirun while every rank is inside a long probe (nlgs, 1.5e6 sweeps that do not
// converge: seconds each). Open MPI 4.1's mpirun passes SIGTERM on to the ranks (about 2 s
// later) and SIGKILLs them a little after: each rank abandons its probe at once, and rank 0
// saves the checkpoint (without the abandoned probes) before the job is gone. (Waiting for the
// probes instead, the ranks were killed first and nothing was saved.) The same command again,
// here in one process, gives the bytes of an uninterrupted run.
TEST_F(Distributed, ProbeSigtermOfMpirunAbandonsTheRunningProbesAndResumes) {
  const std::string args = "probe '" + kP50.string() +
                           "' --sample 2 --seed 3 --method nlgs --velocity-tol 1e-14 --max-sweeps 1500000 "
                           "--checkpoint 0 --out '";
  const fs::path one = root_ / "one", out = root_ / "stopped", log = root_ / "log.txt";
  fs::create_directories(one);
  fs::create_directories(out);
  const CommandResult whole = shell(unjam(0, args + one.string() + "' --threads 2"));
  ASSERT_EQ(whole.exit_code, 0) << whole.output;

  const pid_t pid = spawn_in_own_session("exec env " + unjam(2, args + out.string() + "' --threads 1") + " >'" +
                                         log.string() + "' 2>&1");
  ASSERT_GT(pid, 0);
  const auto text = [&] {
    std::ifstream in(log);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const auto started = std::chrono::steady_clock::now();
  while (text().find("unjam probe:") == std::string::npos && std::chrono::steady_clock::now() - started < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // every rank in its probe
  ASSERT_EQ(::kill(pid, SIGTERM), 0);  // pid: mpirun (sh and env exec it)
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  for (auto alive = session_processes(pid); !alive.empty() && std::chrono::steady_clock::now() < deadline + std::chrono::seconds(5);
       alive = session_processes(pid)) {
    for (const pid_t p : alive) ::kill(p, SIGKILL);
    ::waitpid(pid, nullptr, WNOHANG);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::string output = text();
  ASSERT_LT(std::chrono::steady_clock::now(), deadline) << "the job did not end after SIGTERM\n" << output;
  EXPECT_NE(output.find("unjam: interrupted: stopped after"), std::string::npos) << output;
  ASSERT_FALSE(fs::exists(out / "probes.csv")) << output;
  ASSERT_TRUE(fs::exists(out / "probe_checkpoint.json")) << output;
  EXPECT_LT(checkpointed_rows(out), 2u);

  const CommandResult resumed = shell(unjam(0, args + out.string() + "' --threads 2"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resuming: "), std::string::npos) << resumed.output;
  for (const char* f : {"probes.csv", "response_profile.csv", "response_field.csv"})
    EXPECT_EQ(read_file(out / f), read_file(one / f)) << f;
}

TEST_F(Distributed, ShardsMergedGiveTheBytesOfOneProcess) {
  const fs::path one = probe("one", 0);
  const fs::path out = root_ / "shards";
  for (int i = 0; i < 3; ++i) probe("shards", 0, "--shard " + std::to_string(i) + "/3");
  ASSERT_FALSE(fs::exists(out / "probes.csv"));
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(fs::exists(out / ("probe_shard-" + std::to_string(i) + "-of-3.json")));
  fs::remove(out / "probe_shard-1-of-3.json");
  const CommandResult missing = shell(unjam(0, "merge '" + kP50.string() + "' --out '" + out.string() + "'"));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("shard 1/3 is missing"), std::string::npos) << missing.output;
  probe("shards", 0, "--shard 1/3");
  const CommandResult merged = shell(unjam(0, "merge '" + kP50.string() + "' --out '" + out.string() + "'"));
  ASSERT_EQ(merged.exit_code, 0) << merged.output;
  expect_same_probe_outputs(one, out);
  // The shards hold the targets in turn by place: their rows differ in number by at most 1.
  std::vector<std::size_t> rows;
  for (int i = 0; i < 3; ++i)
    rows.push_back(nlohmann::json::parse(read_file(out / ("probe_shard-" + std::to_string(i) + "-of-3.json")))
                       .at("state").at("rows").size());
  EXPECT_LE(*std::max_element(rows.begin(), rows.end()) - *std::min_element(rows.begin(), rows.end()), 1u);

  // The summary's all_runs: the shards' runs summed; a shard file without them (written
  // before they were recorded) has its probes untimed.
  double busy = 0.0;
  int rows_2 = 0;
  for (int i = 0; i < 3; ++i) {
    const auto shard = nlohmann::json::parse(read_file(out / ("probe_shard-" + std::to_string(i) + "-of-3.json")));
    EXPECT_EQ(shard.at("all_runs").at("runs").get<int>(), 1);
    busy += shard.at("all_runs").at("busy_seconds").get<double>();
    if (i == 2) rows_2 = static_cast<int>(shard.at("state").at("rows").size());
  }
  const nlohmann::json all = nlohmann::json::parse(read_file(out / "probe_summary.json")).at("all_runs");
  EXPECT_EQ(all.at("runs").get<int>(), 3);
  EXPECT_EQ(all.at("untimed").get<int>(), 0);
  EXPECT_NEAR(all.at("busy_seconds").get<double>(), busy, 1e-9);
  const fs::path file_2 = out / "probe_shard-2-of-3.json";
  auto shard_2 = nlohmann::json::parse(read_file(file_2));
  shard_2.erase("all_runs");
  write_file_atomic(file_2, shard_2.dump());
  ASSERT_EQ(shell(unjam(0, "merge '" + kP50.string() + "' --out '" + out.string() + "'")).exit_code, 0);
  const nlohmann::json old = nlohmann::json::parse(read_file(out / "probe_summary.json")).at("all_runs");
  EXPECT_EQ(old.at("runs").get<int>(), 2);
  EXPECT_EQ(old.at("untimed").get<int>(), rows_2);
  EXPECT_GT(rows_2, 0);
}

TEST_F(Distributed, ShardsMergedKeepTheLargestInertiaOfTheirRuns) {
  // --max-inertia travels with the shards: the merged outputs are one process's, with the
  // same probes left out of the averages and the means.
  const auto cd = [&](const std::string& name, const std::string& extra) {
    fs::create_directories(root_ / name);
    const CommandResult r = shell(unjam(0, "probe '" + kP50.string() + "' --sample 6 --method cd --max-inertia 1.5e-5 "
                                           "--threads 1 --quiet --out '" + (root_ / name).string() + "' " + extra));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return root_ / name;
  };
  const fs::path one = cd("cd-one", "");
  for (int i = 0; i < 2; ++i) cd("cd-shards", "--shard " + std::to_string(i) + "/2");
  const fs::path out = root_ / "cd-shards";
  // The threshold is stored once, in the shard's campaign settings, where merge reads it.
  const auto shard = nlohmann::json::parse(read_file(out / "probe_shard-0-of-2.json"));
  EXPECT_EQ(shard.at("settings").at("max_inertia_F0").get<double>(), 1.5e-5);
  EXPECT_FALSE(shard.at("options").contains("max_inertia"));
  // The shards hold the sample in turn by place, 3 each (by contact number, k mod 2, all 6 of
  // this sample fell in shard 0).
  EXPECT_EQ(shard.at("state").at("rows").size(), 3u);
  EXPECT_EQ(nlohmann::json::parse(read_file(out / "probe_shard-1-of-2.json")).at("state").at("rows").size(), 3u);
  const CommandResult merged = shell(unjam(0, "merge '" + kP50.string() + "' --out '" + out.string() + "'"));
  ASSERT_EQ(merged.exit_code, 0) << merged.output;
  expect_same_probe_outputs(one, out);
  const auto a = nlohmann::json::parse(read_file(one / "probe_summary.json")),
             b = nlohmann::json::parse(read_file(out / "probe_summary.json"));
  EXPECT_EQ(a.at("inertial"), b.at("inertial"));
  EXPECT_GT(a.at("inertial").get<int>(), 0);
  EXPECT_LT(a.at("inertial").get<int>(), 6);
}

TEST_F(Distributed, AShardRefusesACheckpointHoldingAnotherShardsProbes) {
  // What a shard's checkpoint from an unjam that split the targets by contact number looks like
  // to this one: probes of another shard. Resuming it would probe some contacts twice and leave
  // others out, so it is refused with the way out, and kept.
  const fs::path out = probe("split", 0, "--shard 1/2 --stop-after 1", 3);
  const fs::path other = out / "probe_checkpoint-shard-0-of-2.json";
  fs::rename(out / "probe_checkpoint-shard-1-of-2.json", other);
  const std::string saved = read_file(other);
  const CommandResult r = shell(unjam(0, "probe '" + kP50.string() + "' --all --method lp --threads 1 --quiet --out '" +
                                         out.string() + "' --shard 0/2"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("which is not in shard 0/2"), std::string::npos) << r.output;
  EXPECT_EQ(read_file(other), saved);
  EXPECT_FALSE(fs::exists(out / "probe_shard-0-of-2.json"));
}

TEST_F(Distributed, MergeStatusSaysHowFarEachShardHasGotAndChangesNothing) {
  // A job array of 3: shard 0 finished, shard 1 stopped after 2 probes, shard 2 not started.
  // `merge --status` reads their files: each shard's share (every third target by place), the
  // probes done, the state of each job; it writes nothing. A damaged checkpoint is named as
  // unreadable, the others still reported; a whole campaign's checkpoint is read too, and a
  // finished one is said to be.
  const fs::path one = probe("one", 0);
  const CsvTable whole = CsvTable::read(one / "probes.csv");
  const int total = static_cast<int>(whole.rows());
  ASSERT_GE(total, 9);
  const auto share = [&](int i) { return (total - i + 2) / 3; };
  const fs::path out = probe("status", 0, "--shard 0/3");
  probe("status", 0, "--shard 1/3 --stop-after 2", 3);
  const std::string before = listing(out);
  const std::string status = "merge '" + kP50.string() + "' --status --out '" + out.string() + "'";
  CommandResult r = shell(unjam(0, status));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string& line :
       {"probe campaign of " + kP50.string() + " in " + out.string() + ": " + std::to_string(total) +
            " probes (method lp), 3 shards",
        "shard 0/3: finished, " + std::to_string(share(0)) + " of " + std::to_string(share(0)) + " probes, 1 run",
        "shard 1/3: 2 of " + std::to_string(share(1)) + " probes, 1 run",
        "shard 2/3: not started (" + std::to_string(share(2)) + " probes)",
        "done " + std::to_string(share(0) + 2) + " of " + std::to_string(total) + " probes",
        std::string("1 shard finished, 1 started, 1 not started"),
        "the " + std::to_string(total - share(0) - 2) + " left: ~"})
    EXPECT_NE(r.output.find(line), std::string::npos) << line << "\n" << r.output;
  EXPECT_EQ(r.output.find("every shard has finished"), std::string::npos) << r.output;
  EXPECT_EQ(listing(out), before);

  const fs::path checkpoint_1 = out / "probe_checkpoint-shard-1-of-3.json";
  const std::string saved = read_file(checkpoint_1);
  write_file_atomic(checkpoint_1, "{");
  r = shell(unjam(0, status));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("shard 1/3: unreadable (probe_checkpoint-shard-1-of-3.json is not valid JSON"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("shard 0/3: finished"), std::string::npos) << r.output;
  write_file_atomic(checkpoint_1, saved);

  probe("status", 0, "--shard 1/3");
  probe("status", 0, "--shard 2/3");
  r = shell(unjam(0, status));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("done " + std::to_string(total) + " of " + std::to_string(total)), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("every shard has finished"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(" left: "), std::string::npos) << r.output;

  const fs::path stopped = probe("whole", 0, "--stop-after 3", 3);
  r = shell(unjam(0, "merge '" + kP50.string() + "' --status --out '" + stopped.string() + "'"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("campaign: 3 of " + std::to_string(total) + " probes, 1 run"), std::string::npos)
      << r.output;
  r = shell(unjam(0, "merge '" + kP50.string() + "' --status --out '" + one.string() + "'"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("has finished: its outputs are there"), std::string::npos) << r.output;
  fs::create_directories(root_ / "empty");
  r = shell(unjam(0, "merge '" + kP50.string() + "' --status --out '" + (root_ / "empty").string() + "'"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no probe campaign or force bounds in"), std::string::npos) << r.output;
}

TEST_F(Distributed, MergeStatusSaysHowFarTheBoundsShardsHaveGot) {
  // `unjam bounds --shard i/K` as a job array of 3: shard 0 finished, shard 1 stopped after 6
  // LPs, shard 2 not started. `merge --status` counts LP values (fn_min and fn_max of each
  // contact; shard i holds the contacts k with k mod 3 = i) and writes nothing; a damaged
  // checkpoint and one of another shard are named unreadable; a whole run's checkpoint is read
  // too, and finished bounds are said to be.
  const auto bounds = [&](const std::string& name, const std::string& extra, int expect_code) {
    fs::create_directories(root_ / name);
    const CommandResult r = shell(unjam(0, "bounds '" + kP50.string() + "' --threads 1 --out '" +
                                               (root_ / name / "bounds.csv").string() + "' " + extra));
    EXPECT_EQ(r.exit_code, expect_code) << r.output;
    return root_ / name;
  };
  const fs::path one = bounds("one", "", 0);
  const int contacts = static_cast<int>(CsvTable::read(one / "bounds.csv").rows());
  ASSERT_GE(contacts, 9);
  const auto share = [&](int i) { return 2 * ((contacts - i + 2) / 3); };
  const fs::path out = bounds("shards", "--shard 0/3", 0);
  bounds("shards", "--shard 1/3 --stop-after 6", 3);
  const std::string before = listing(out);
  const std::string status = "merge '" + kP50.string() + "' --status --out '" + out.string() + "'";
  CommandResult r = shell(unjam(0, status));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto saved = nlohmann::json::parse(read_file(out / "bounds_checkpoint-shard-1-of-3.json"));
  int known = 0;
  for (const char* end : {"fn_min", "fn_max"})
    for (const auto& v : saved.at(end)) known += !v.is_null();
  ASSERT_GE(known, 6);
  ASSERT_LT(known, share(1));
  for (const std::string& line :
       {"force bounds of " + kP50.string() + " in " + out.string() + ": " + std::to_string(contacts) + " contacts, " +
            std::to_string(2 * contacts) + " LP values (method barrier), 3 shards",
        "shard 0/3: finished, " + std::to_string(share(0)) + " of " + std::to_string(share(0)) + " LP values, 1 run",
        "shard 1/3: " + std::to_string(known) + " of " + std::to_string(share(1)) + " LP values, 1 run",
        "shard 2/3: not started (" + std::to_string(share(2)) + " LP values)",
        "done " + std::to_string(share(0) + known) + " of " + std::to_string(2 * contacts) + " LP values",
        std::string("1 shard finished, 1 started, 1 not started"),
        "the " + std::to_string(2 * contacts - share(0) - known) + " left: ~"})
    EXPECT_NE(r.output.find(line), std::string::npos) << line << "\n" << r.output;
  EXPECT_EQ(r.output.find("probe campaign"), std::string::npos) << r.output;
  EXPECT_EQ(listing(out), before);

  // a damaged checkpoint, then another shard's checkpoint in its place: named, the others reported
  const fs::path checkpoint_1 = out / "bounds_checkpoint-shard-1-of-3.json";
  const std::string kept = read_file(checkpoint_1);
  write_file_atomic(checkpoint_1, "{");
  r = shell(unjam(0, status));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("shard 1/3: unreadable (not a JSON object)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("shard 0/3: finished"), std::string::npos) << r.output;
  write_file_atomic(out / "bounds_checkpoint-shard-2-of-3.json", kept);
  write_file_atomic(checkpoint_1, kept);
  r = shell(unjam(0, status));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("shard 2/3: unreadable (saved by shard 1/3, not 2/3)"), std::string::npos) << r.output;
  fs::remove(out / "bounds_checkpoint-shard-2-of-3.json");

  bounds("shards", "--shard 1/3", 0);
  bounds("shards", "--shard 2/3", 0);
  r = shell(unjam(0, status));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("done " + std::to_string(2 * contacts) + " of " + std::to_string(2 * contacts)),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("every shard has finished: `unjam merge " + kP50.string() + " --out " + out.string() +
                          "` writes bounds.csv and bounds.json"),
            std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(" left: "), std::string::npos) << r.output;

  const fs::path stopped = bounds("whole", "--stop-after 5", 3);
  r = shell(unjam(0, "merge '" + kP50.string() + "' --status --out '" + stopped.string() + "'"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("  run: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" of " + std::to_string(2 * contacts) + " LP values, 1 run"), std::string::npos) << r.output;
  r = shell(unjam(0, "merge '" + kP50.string() + "' --status --out '" + one.string() + "'"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the force bounds in " + one.string() + " have finished"), std::string::npos) << r.output;
}

TEST_F(Distributed, BoundsStoppedOnTwoRanksResumeOnThree) {
  const auto bounds = [&](const std::string& name, int ranks, const std::string& extra, int expect_code) {
    fs::create_directories(root_ / name);
    const CommandResult r = shell(unjam(ranks, "bounds '" + kP50.string() + "' --threads 1 --out '" +
                                               (root_ / name / "bounds.csv").string() + "' " + extra));
    EXPECT_EQ(r.exit_code, expect_code) << r.output;
    return root_ / name;
  };
  const fs::path one = bounds("one", 0, "", 0);
  const fs::path out = bounds("resumed", 2, "--stop-after 40", 3);
  ASSERT_FALSE(fs::exists(out / "bounds.csv"));
  const auto saved = nlohmann::json::parse(read_file(out / "bounds_checkpoint.json"));
  int known = 0;
  for (const auto& v : saved.at("fn_max")) known += !v.is_null();
  EXPECT_GE(known, 40);
  EXPECT_LT(known, 81);
  // The checkpoint records the stopped run's time; bounds.json all the runs' (docs/probe.md,
  // "Campaigns": the time of every run), over 2 and then 3 ranks.
  const nlohmann::json first = saved.at("runs");
  EXPECT_EQ(first.at("runs").get<int>(), 1);
  EXPECT_EQ(first.at("untimed").get<int>(), 0);
  EXPECT_GT(first.at("busy_seconds").get<double>(), 0.0);
  bounds("resumed", 3, "", 0);
  EXPECT_FALSE(fs::exists(out / "bounds_checkpoint.json"));
  EXPECT_EQ(read_file(one / "bounds.csv"), read_file(out / "bounds.csv"));
  const auto summary = nlohmann::json::parse(read_file(out / "bounds.json"));
  const nlohmann::json& all = summary.at("all_runs");
  EXPECT_EQ(all.at("runs").get<int>(), 2);
  EXPECT_EQ(all.at("untimed").get<int>(), 0);
  double last = 0.0;
  for (const auto& r : summary.at("ranks")) last += r.at("busy_seconds").get<double>();
  EXPECT_NEAR(all.at("busy_seconds").get<double>(), first.at("busy_seconds").get<double>() + last, 1e-9);
  EXPECT_EQ(nlohmann::json::parse(read_file(one / "bounds.json")).at("all_runs").at("runs").get<int>(), 1);
}

TEST_F(Distributed, BoundsOverRanksAndShardsWriteTheBytesOfOneProcess) {
  const auto bounds = [&](const std::string& name, int ranks, const std::string& extra = "") {
    fs::create_directories(root_ / name);
    const fs::path csv = root_ / name / "bounds.csv";
    const CommandResult r = shell(unjam(ranks, "bounds '" + kP50.string() + "' --threads 1 --out '" + csv.string() + "' " + extra));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return csv;
  };
  const std::string one = read_file(bounds("one", 0));
  EXPECT_EQ(one, read_file(bounds("two", 2)));
  EXPECT_EQ(one, read_file(bounds("three", 3)));
  for (int i = 0; i < 2; ++i) bounds("shards", 0, "--shard " + std::to_string(i) + "/2");
  const CommandResult merged = shell(unjam(0, "merge '" + kP50.string() + "' --out '" + (root_ / "shards").string() + "'"));
  ASSERT_EQ(merged.exit_code, 0) << merged.output;
  EXPECT_EQ(one, read_file(root_ / "shards" / "bounds.csv"));
  const auto ranks = nlohmann::json::parse(read_file(root_ / "three" / "bounds.json")).at("ranks");
  EXPECT_EQ(ranks.size(), 3u);
  EXPECT_EQ(nlohmann::json::parse(read_file(root_ / "shards" / "bounds.json")).at("all_runs").at("runs").get<int>(), 2);
}

}  // namespace
}  // namespace unjam
