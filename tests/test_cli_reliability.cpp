// The tool end to end under the failures a user meets: a checkpoint left by another packing,
// a run killed during a write, two writers on one directory, impossible or out-of-range
// parameters, and the exit codes of README ("Exit codes").
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/checkpoint_settings.hpp"
#include "unjam/core/dir_lock.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam {
namespace {

namespace fs = std::filesystem;
using testing::run_tool;
using testing::ToolRun;


// A fresh directory under the temp dir, removed at the end of the test.
class CliReliability : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("unjam-cli-rel-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "-" +
             std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // A writable copy of a fixture packing.
  fs::path copy(const std::string& fixture, const std::string& as) { return testing::copy_fixture(fixture, root_, as); }

  fs::path root_;
};

// Starts `unjam ARGS` in the background (output discarded); returns its process id.
pid_t spawn(const std::string& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", (std::string("exec '") + UNJAM_BINARY + "' " + args + " >/dev/null 2>&1").c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int rows_of(const fs::path& csv) {
  std::ifstream in(csv);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty();
  return n - 1;  // without the header
}

// The text of `file`, empty if it cannot be read (yet).
std::string read_file_or_empty(const fs::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A checkpoint of `probe DIR --all`, as saved after a probe (the run is killed then).
std::string checkpoint_of(const fs::path& dir) {
  const fs::path ckpt = dir / "probe_checkpoint.json";
  const pid_t pid = spawn("probe " + dir.string() + " --all --checkpoint 0 --threads 1 --quiet");
  std::string saved;
  for (int i = 0; i < 20000 && saved.empty(); ++i) {  // written after each probe, removed at the end
    if (fs::exists(ckpt)) {
      try {
        saved = read_file(ckpt);
      } catch (const Error&) {
      }
    }
    if (saved.empty()) std::this_thread::sleep_for(std::chrono::microseconds(100));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  fs::remove(ckpt);
  return saved;
}

TEST(CheckpointSettings, OtherSettingsAreNamedWithBothValues) {
  // The check behind probe and bounds checkpoints: equal settings pass; otherwise every key
  // that differs is named with the checkpoint's and this run's value (a missing key: none).
  const nlohmann::json saved = {{"dt", 0.001}, {"g", 1e-9}, {"method", "cd"}};
  EXPECT_NO_THROW(require_same_settings(saved, saved, "c.json"));
  nlohmann::json now = saved;
  now["dt"] = 0.01;
  now["cd_start"] = "compliant";
  try {
    require_same_settings(saved, now, "c.json");
    FAIL() << "other settings accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "c.json belongs to a run with other settings (cd_start: none there, \"compliant\" here, "
              "dt: 0.001 there, 0.01 here); give its settings to resume it, or remove it to start over");
  }
  EXPECT_THROW(require_same_settings(nlohmann::json(), saved, "c.json"), Error);
}

TEST_F(CliReliability, ProbeCheckpointOfAnotherPackingIsSetAside) {
  // A checkpoint of packing A (probes of A's contacts), then packing B in the same directory:
  // `probe --all` used to resume A's probes on B and merge the two.
  const fs::path a = copy("p50-mu0.1", "a"), b = copy("p50-mu1", "b");
  const std::string saved = checkpoint_of(a);
  ASSERT_FALSE(saved.empty()) << "no checkpoint seen";
  write_file_atomic(b / "probe_checkpoint.json", saved);

  const ToolRun r = run_tool("probe " + b.string() + " --all --threads 1 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("saved from another packing"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(b / "probe_checkpoint.json.stale"));
  const auto summary = nlohmann::json::parse(read_file(b / "probe_summary.json"));
  // B's own run from scratch gives the same count.
  const fs::path b2 = copy("p50-mu1", "b2");
  ASSERT_EQ(run_tool("probe " + b2.string() + " --all --threads 1 --quiet").exit_code, 0);
  const auto fresh = nlohmann::json::parse(read_file(b2 / "probe_summary.json"));
  EXPECT_EQ(summary.at("probes"), fresh.at("probes"));
  EXPECT_EQ(rows_of(b / "probes.csv"), fresh.at("probes").get<int>());
  EXPECT_EQ(read_file(b / "response_profile.csv"), read_file(b2 / "response_profile.csv"));
}

TEST_F(CliReliability, DamagedProbeCheckpointsAreRefusedOrSetAside) {
  // Seeded random byte damage of a real checkpoint: every run either refuses it (exit 1, a
  // message) or starts over and gives the undamaged result; never a crash or a merge.
  const fs::path a = copy("p50-mu0.1", "a"), ref = copy("p50-mu0.1", "ref");
  const std::string saved = checkpoint_of(a);
  ASSERT_FALSE(saved.empty()) << "no checkpoint seen";
  ASSERT_EQ(run_tool("probe " + ref.string() + " --all --threads 1 --quiet").exit_code, 0);
  const std::string reference = read_file(ref / "response_profile.csv");
  std::mt19937_64 rng(16);
  int refused = 0;
  for (int trial = 0; trial < 24; ++trial) {
    std::string damaged = saved;
    const std::size_t at = std::uniform_int_distribution<std::size_t>(0, damaged.size() - 1)(rng);
    switch (trial % 3) {
      case 0: damaged[at] = static_cast<char>(std::uniform_int_distribution<int>(32, 126)(rng)); break;
      case 1: damaged.erase(at, 1); break;
      default: damaged.resize(at); break;
    }
    if (damaged == saved) continue;
    fs::remove(a / "probe_checkpoint.json.stale");
    write_file_atomic(a / "probe_checkpoint.json", damaged);
    const ToolRun r = run_tool("probe " + a.string() + " --all --threads 1 --quiet");
    SCOPED_TRACE("trial " + std::to_string(trial) + ", byte " + std::to_string(at));
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
    if (r.exit_code == 1) {
      ++refused;
      EXPECT_NE(r.output.find("unjam: error: "), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("remove it to start over"), std::string::npos) << r.output;
    } else {
      EXPECT_EQ(read_file(a / "response_profile.csv"), reference);
    }
  }
  EXPECT_GT(refused, 12);
}

TEST_F(CliReliability, ProbeCheckpointEditedWithItsHashIsCheckedAgainstThePacking) {
  // A checkpoint whose state was edited and its FNV-1a hash recomputed: the hash only catches
  // accidental damage, so the state itself must fit the packing. Each edit used to be resumed
  // (rows out of order or repeated went into probes.csv, a foreign grid into the averages).
  const fs::path a = copy("p50-mu0.1", "a");
  const std::string saved = checkpoint_of(a);
  ASSERT_FALSE(saved.empty()) << "no checkpoint seen";
  const auto original = nlohmann::json::parse(saved);
  ASSERT_GE(original.at("state").at("rows").size(), 1u);
  const std::vector<std::pair<std::string, std::function<void(nlohmann::json&)>>> edits = {
      {"row repeated", [](nlohmann::json& st) { st["rows"].push_back(st["rows"][0]); }},
      {"row of other grains", [](nlohmann::json& st) { st["rows"][0][1] = st["rows"][0][1].get<int>() + 1; }},
      {"contact out of range", [](nlohmann::json& st) { st["rows"][0][0] = 100000; }},
      {"other grid", [](nlohmann::json& st) { st["average"]["grid"]["r_max"] = 1.5 * st["average"]["grid"]["r_max"].get<double>(); }},
      {"integer field as a huge float", [](nlohmann::json& st) { st["rows"][0][6] = 1e300; }},
  };
  for (const auto& [what, edit] : edits) {
    SCOPED_TRACE(what);
    nlohmann::json j = original;
    edit(j["state"]);
    j["state_fnv1a64"] = fnv1a64_hex(j["state"].dump());
    write_file_atomic(a / "probe_checkpoint.json", j.dump());
    const ToolRun r = run_tool("probe " + a.string() + " --all --threads 1 --quiet");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("probe checkpoint is corrupt"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("remove it to start over"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(a / "probes.csv"));
  }
}

TEST_F(CliReliability, ASecondWriterIsRefusedNamingTheFirst) {
  const fs::path d = copy("p50-mu0.1", "d");
  {
    const DirLock held(d, "unjam probe held-by-the-test");
    const ToolRun r = run_tool("probe " + d.string() + " --contact 1");
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("is in use by process " + std::to_string(::getpid()) + " (unjam probe held-by-the-test)"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(d / "probe-1.csv"));
    const ToolRun bounds = run_tool("bounds " + d.string());
    EXPECT_EQ(bounds.exit_code, 1) << bounds.output;
    EXPECT_NE(bounds.output.find("is in use by process"), std::string::npos) << bounds.output;
  }
  // Released (also when a holder is killed: the kernel drops a dead process's flock).
  const ToolRun r = run_tool("probe " + d.string() + " --contact 1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(d / "probe-1.csv"));
}

TEST_F(CliReliability, PackKilledDuringCheckpointsResumes) {
  // SIGKILL at seeded random times while checkpoints are written every millisecond: the
  // directory always holds one complete version, and --resume finishes it.
  const fs::path s = root_ / "s";
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> delay_ms(150, 900);
  for (int kill = 0; kill < 6; ++kill) {
    const pid_t pid = spawn("pack --n 200 --mu 0.1 --seed 5 --threads 1 --checkpoint 0.001 --quiet --out " +
                            s.string() + (kill == 0 ? "" : " --resume " + s.string()));
    // The first run is killed only after its first checkpoint (a slow start, e.g. under the
    // sanitizers, would otherwise leave nothing to resume); up to 120 s.
    for (int wait = 0; kill == 0 && wait < 12000 && !fs::exists(s / "meta.json"); ++wait)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    if (!fs::exists(s / "meta.json") && !fs::exists(s / "meta.json.new")) continue;  // killed before any write
    const ToolRun info = run_tool("info " + s.string());
    ASSERT_EQ(info.exit_code, 0) << "after kill " << kill << ":\n" << info.output;
  }
  const ToolRun r = run_tool("pack --resume " + s.string() + " --threads 1 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(read_packing(s).state.is_static);
  for (const auto& e : fs::directory_iterator(s)) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
    EXPECT_EQ(name.find(".new"), std::string::npos) << name;
  }
}

TEST_F(CliReliability, ImpossibleOrOutOfRangeParametersAreRefusedBeforeAnythingRuns) {
  const fs::path out = root_ / "out";
  const fs::path fixture = copy("p50-mu1", "fixture");
  const struct {
    std::string args, phrase;
  } cases[] = {
      {"pack --n 2 --out " + out.string(), "the number of disks must be at least 8 (got 2)"},
      {"pack --n 4 --out " + out.string(), "fewer cannot jam in a periodic cell"},
      {"pack --n 1000000000 --out " + out.string(), "N = 1000000000 needs about 8000.0 GB"},
      {"pack --n 2000 --max-memory 0.01 --out " + out.string(), "more than --max-memory 10 MB"},
      {"pack --n 20 --seed -3 --out " + out.string(), "a seed is an integer from 0 to 18446744073709551615, got '-3'"},
      {"pack --n 20 --seed 18446744073709551616 --out " + out.string(), "a seed is an integer"},
      {"pack --n 20 --threads -1 --out " + out.string(), "must be a finite number >= 0, got '-1'"},
      {"pack --n 20 --checkpoint -1 --out " + out.string(), "must be a finite number >= 0"},
      {"pack --n 20 --mu inf --out " + out.string(), "mu must be a finite number >= 0"},
      {"pack --n 20 --dt nan --out " + out.string(), "must be a finite number > 0, got 'nan'"},
      {"probe " + fixture.string() + " --contact -1 --out " + out.string(), "must be a finite number >= 0"},
      {"probe " + fixture.string() + " --contact 1 --g nan --out " + out.string(), "must be a finite number > 0"},
      {"probe " + fixture.string() + " --contact 1 --dt inf --out " + out.string(), "must be a finite number > 0"},
      {"probe " + fixture.string() + " --sample 3 --seed -1 --out " + out.string(), "a seed is an integer"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start zero --out " + out.string(), "--cd-start must be static, lp, compliant, interior, inertial or interior-inertial (got 'zero')"},
      {"probe " + fixture.string() + " --contact 1 --cd-start lp --out " + out.string(), "the cd start 'lp' applies to the cd method only (the method is lp)"},
      {"probe " + fixture.string() + " --sample 3 --max-inertia 1e-3 --out " + out.string(), "a largest inertia applies to the methods with a time step (nlgs, lemke, cd), not to lp"},
      {"probe " + fixture.string() + " --sample 3 --method cd --max-inertia -1 --out " + out.string(), "must be a finite number > 0"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-softer-starts 1 --out " + out.string(), "--cd-softer-starts applies to the cd method's compliant and interior starts only"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start compliant --cd-softer-starts -1 --out " + out.string(), "must be a finite number >= 0"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-compliant-start 1e-3 --out " + out.string(), "--cd-compliant-start applies to the cd method's compliant and interior starts only"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start compliant --cd-compliant-start 0 --out " + out.string(), "must be a finite number > 0"},
      {"probe " + fixture.string() + " --contact 1 --cd-accept-residual 1e-4 --out " + out.string(), "--cd-accept-residual applies to the cd method, not to lp"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-accept-residual 1e-7 --out " + out.string(), "--cd-accept-residual must be in [1e-06, 0.001] g (got 1e-07)"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-accept-residual 0.01 --out " + out.string(), "--cd-accept-residual must be in [1e-06, 0.001] g (got 0.01)"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-accept-residual nan --out " + out.string(), "must be a finite number > 0"},
      {"probe " + fixture.string() + " --contact 1 --cd-settle-compliance 1e-5 --out " + out.string(), "--cd-settle-compliance applies to the cd method, not to lp"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-settle-compliance -1 --out " + out.string(), "--cd-settle-compliance"},
      {"probe " + fixture.string() + " --contact 1 --cd-lost-factor 1e3 --out " + out.string(), "--cd-lost-factor applies to the cd method, not to lp"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-lost-factor -1 --out " + out.string(), "--cd-lost-factor"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-restart-floor 1e-3 --out " + out.string(), "--cd-restart-floor applies to the cd method's compliant and interior starts only"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start compliant --cd-restart-floor -1 --out " + out.string(), "--cd-restart-floor"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-interior-share 0.7 --out " + out.string(), "--cd-interior-share applies to the cd method's interior-inertial start only"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start interior-inertial --cd-interior-share 1 --out " + out.string(), "--cd-interior-share must be in (0, 1) (got 1.0"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start interior-inertial --cd-interior-share nan --out " + out.string(), "--cd-interior-share must be in (0, 1)"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start interior --cd-inertial-factor 3 --out " + out.string(), "--cd-inertial-factor applies to the cd method's inertial and interior-inertial starts only"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start inertial --cd-inertial-factor 1 --out " + out.string(), "--cd-inertial-factor must be > 1 and finite (got 1.0"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start inertial --cd-inertial-factor inf --out " + out.string(), "--cd-inertial-factor must be > 1 and finite"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start interior-inertial --cd-inertial-stages 0 --out " + out.string(), "--cd-inertial-stages must be >= 1 (got 0)"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start inertial --cd-inertial-halvings -1 --out " + out.string(), "--cd-inertial-halvings must be >= 0 (got -1)"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start inertial --cd-inertial-retries -2 --out " + out.string(), "--cd-inertial-retries must be >= 0 (got -2)"},
      {"probe " + fixture.string() + " --contact 1 --method cd --cd-start inertial --cd-inertial-jumps -1 --out " + out.string(), "--cd-inertial-jumps must be >= 0 (got -1)"},
      {"probe " + fixture.string() + " --contact 1 --method lp --cd-inertial-jumps 2 --out " + out.string(), "--cd-inertial-jumps applies to the cd method's inertial and interior-inertial starts only"},
      {"probe " + fixture.string() + " --contact 1 --method cd --lp-tol 1e-8 --out " + out.string(), "--lp-tol applies to the lp method, not to cd"},
      {"probe " + fixture.string() + " --sample 3 --lp-tol 1e-13 --out " + out.string(), "not in range"},
      {"probe " + fixture.string() + " --sample 3 --lp-tol nan --out " + out.string(), "must be a finite number > 0"},
      {"ensemble " + fixture.string() + " --thin -1", "must be a finite number >= 0"},
      {"ensemble " + fixture.string() + " --probe lp --cd-max-pieces 10", "--cd-max-pieces applies to the cd method, not to lp"},
      {"ensemble " + fixture.string() + " --probe nlgs --cd-start interior", "the cd start 'interior' applies to the cd method only (the method is nlgs)"},
      {"ensemble " + fixture.string() + " --cd-start zero", "--cd-start must be static, lp, compliant, interior, inertial or interior-inertial (got 'zero')"},
      {"ensemble " + fixture.string() + " --burn-in -1", "must be a finite number >= 0"},
      {"ensemble " + fixture.string() + " --probe-g nan", "must be a finite number > 0"},
      {"ensemble " + fixture.string() + " --seed -1", "a seed is an integer"},
      {"ensemble " + fixture.string() + " --samples 0", "must be a finite number > 0"},
      {"ensemble " + fixture.string() + " --lp-tol 1e-5", "not in range"},
      {"ensemble " + fixture.string() + " --open-tol 0", "must be a finite number > 0"},
      {"ensemble " + fixture.string() + " --open-tol 2e-3", "not in range"},
      {"bounds " + fixture.string() + " --gap-tol nan --out " + (out / "b.csv").string(), "must be a finite number >= 0"},
      {"bounds " + fixture.string() + " --lp-tol 1e-3 --out " + (out / "b.csv").string(), "not in range"},
      {"bounds " + fixture.string() + " --lp-tol 1e-13 --out " + (out / "b.csv").string(), "not in range"},
      {"bounds " + fixture.string() + " --lp-tol nan --out " + (out / "b.csv").string(), "must be a finite number > 0"},
      {"bounds " + fixture.string() + " --open-tol 0 --out " + (out / "b.csv").string(), "must be a finite number > 0"},
      {"bounds " + fixture.string() + " --open-tol 0.5 --out " + (out / "b.csv").string(), "not in range"},
  };
  for (const auto& c : cases) {
    const ToolRun r = run_tool(c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.phrase), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_LT(r.output.size(), 400u) << "a short message: " << r.output;
    EXPECT_FALSE(fs::exists(out)) << "nothing written for " << c.args;
  }
  for (const char* file : {"ensemble.csv", "probes.csv", "bounds.csv", ".unjam.lock"})
    EXPECT_FALSE(fs::exists(fixture / file)) << file;
}

TEST_F(CliReliability, ExitCodesOfEverySubcommand) {
  const fs::path d = copy("p50-mu1", "d");
  EXPECT_EQ(run_tool("--help").exit_code, 0);
  EXPECT_EQ(run_tool("probe --help").exit_code, 0);
  EXPECT_EQ(run_tool("--version").exit_code, 0);
  EXPECT_EQ(run_tool("").exit_code, 1) << "no subcommand";
  EXPECT_EQ(run_tool("frobnicate").exit_code, 1);
  EXPECT_EQ(run_tool("pack --bogus").exit_code, 1);
  for (const char* cmd : {"info", "probe", "bounds", "ensemble"}) {
    const ToolRun missing = run_tool(std::string(cmd) + " " + (root_ / "missing").string() + " --all");
    EXPECT_EQ(missing.exit_code, 1) << cmd << ": " << missing.output;
  }
  // A file given for a packing directory.
  const ToolRun file = run_tool("info " + (d / "meta.json").string());
  EXPECT_EQ(file.exit_code, 1) << file.output;
  EXPECT_NE(file.output.find("is a file, not a packing directory"), std::string::npos) << file.output;
  // An nlgs probe that did not converge is not a result.
  const ToolRun nlgs = run_tool("probe " + d.string() + " --contact 1 --method nlgs --max-sweeps 5");
  EXPECT_EQ(nlgs.exit_code, 1) << nlgs.output;
  EXPECT_NE(nlgs.output.find("did not converge"), std::string::npos) << nlgs.output;
  EXPECT_NE(nlgs.output.find("raise --max-sweeps"), std::string::npos) << nlgs.output;
  // A cd probe without a solution (p50-mu1 at dt = 10, where the path finds none)
  // says so in words, not as a residual of 1.8e308 printed in full.
  const ToolRun cd = run_tool("probe " + d.string() + " --contact 1 --method cd --dt 10");
  EXPECT_EQ(cd.exit_code, 1) << cd.output;
  EXPECT_NE(cd.output.find("did not converge (method cd, no solution)"), std::string::npos) << cd.output;
  EXPECT_EQ(cd.output.find("179769"), std::string::npos) << cd.output;
}

// Bit `sig` of the signal mask `field` of process `pid`'s main thread (/proc/PID/status).
bool status_bit(pid_t pid, const std::string& field, int sig) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind(field, 0) == 0) return (std::stoull(line.substr(field.size()), nullptr, 16) >> (sig - 1)) & 1ULL;
  return false;
}

// Whether process `pid` catches `sig` (its handler installed, SigCgt).
bool catches(pid_t pid, int sig) { return status_bit(pid, "SigCgt:", sig); }

// Whether the main thread of process `pid` blocks `sig` (SigBlk): the tool takes SIGINT and
// SIGTERM in a listening thread by sigwait, so that no handler runs inside the computation
// (METIS installs its own for SIGTERM during its calls, core/nested_dissection).
bool blocks(pid_t pid, int sig) { return status_bit(pid, "SigBlk:", sig); }

// SIGTERM in the middle of a long probe (nlgs, 6e5 sweeps that do not converge: seconds of
// compute): the probe is abandoned at once, the run exits with the interrupt code 3 leaving a
// checkpoint without it, and the same command again probes it: the probes.csv of an
// uninterrupted run. (Were the probe finished instead, the run would end with code 0.)
TEST_F(CliReliability, SigtermAbandonsTheRunningProbeAndTheSameCommandRedoesIt) {
  const fs::path d = copy("p50-mu0.1", "d");
  const std::string args = "probe " + d.string() +
                           " --sample 1 --seed 3 --method nlgs --velocity-tol 1e-14 --max-sweeps 600000 "
                           "--threads 1 --checkpoint 0 --out ";
  const fs::path whole = root_ / "whole", out = root_ / "out";
  fs::create_directories(whole);
  const ToolRun uninterrupted = run_tool(args + whole.string());
  ASSERT_EQ(uninterrupted.exit_code, 0) << uninterrupted.output;

  // The run, its output in a file: SIGTERM once it has announced the campaign and catches
  // SIGTERM, a little later: inside the probe.
  fs::create_directories(out);
  const fs::path log = root_ / "log.txt";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c",
            ("exec '" + std::string(UNJAM_BINARY) + "' " + args + out.string() + " >'" + log.string() + "' 2>&1").c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_GT(pid, 0);
  const auto started = std::chrono::steady_clock::now();
  while ((read_file_or_empty(log).find("unjam probe:") == std::string::npos || !catches(pid, SIGTERM)) &&
         std::chrono::steady_clock::now() - started < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_TRUE(blocks(pid, SIGTERM));
  EXPECT_TRUE(blocks(pid, SIGINT));
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const auto signalled = std::chrono::steady_clock::now();
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  const double stop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
  const std::string output = read_file_or_empty(log);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 3) << output;
  EXPECT_LT(stop_s, 10.0) << "the stop waited for the probe";
  EXPECT_NE(output.find("stopped after 0 probes"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(out / "probes.csv"));
  ASSERT_TRUE(fs::exists(out / "probe_checkpoint.json"));
  EXPECT_EQ(nlohmann::json::parse(read_file(out / "probe_checkpoint.json")).at("state").at("rows").size(), 0u);

  const ToolRun resumed = run_tool(args + out.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resuming: 0 probes already done"), std::string::npos) << resumed.output;
  EXPECT_FALSE(fs::exists(out / "probe_checkpoint.json"));
  EXPECT_EQ(read_file(out / "probes.csv"), read_file(whole / "probes.csv"));
  EXPECT_EQ(read_file(out / "response_profile.csv"), read_file(whole / "response_profile.csv"));
}

// A command that saves no state to resume (`unjam ensemble`) is ended by SIGTERM as by the
// signal's default action, though the tool takes the signal in its listening thread.
TEST_F(CliReliability, SigtermEndsACommandWithoutAStateToSaveAsByDefault) {
  const fs::path d = copy("p50-mu1", "d");
  const fs::path log = root_ / "ensemble-log.txt";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c",
            ("exec '" + std::string(UNJAM_BINARY) + "' ensemble " + d.string() +
             " --method walk --samples 100000000 --probe none --threads 1 >'" + log.string() + "' 2>&1")
                .c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ASSERT_GT(pid, 0);
  const auto started = std::chrono::steady_clock::now();
  while (!blocks(pid, SIGTERM) && std::chrono::steady_clock::now() - started < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  int status = 0;
  const auto signalled = std::chrono::steady_clock::now();
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() - signalled > std::chrono::seconds(30)) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      FAIL() << "SIGTERM did not end the command within 30 s";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(WIFSIGNALED(status)) << read_file_or_empty(log);
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
}

TEST_F(CliReliability, ProbeAllWithNothingToProbeIsAnError) {
  const fs::path d = copy("p50-mu1", "d");
  // Every contact without force: no force-carrying contact.
  auto meta = nlohmann::json::parse(read_file(d / "meta.json"));
  std::string contacts = read_file(d / "contacts.csv");
  const auto header_end = contacts.find('\n');
  write_file_atomic(d / "contacts.csv", contacts.substr(0, header_end + 1));
  meta.erase("checksums");
  write_file_atomic(d / "meta.json", meta.dump());
  const ToolRun r = run_tool("probe " + d.string() + " --all --quiet");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no force-carrying contact"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(d / "probe_summary.json"));
}

// `unjam merge` refuses a damaged shard file with its name, the reason and the job to run again
// (exit code 1), and writes nothing: a contact out of range (written out of bounds before), one
// of another shard or listed twice, values missing or of the wrong type, counts that are not
// non-negative integers, negative times, a file that is not an object, files numbered beyond
// the job array, probe shards that leave a target out. The shards as written merge.
TEST_F(CliReliability, MergeRefusesDamagedShardsByNameAndWritesNothing) {
  const fs::path d = copy("p50-mu0.1", "d");
  const fs::path b = root_ / "bounds", pr = root_ / "probe";
  for (int i = 0; i < 2; ++i) {
    const std::string shard = " --shard " + std::to_string(i) + "/2 --threads 1";
    ASSERT_EQ(run_tool("bounds " + d.string() + " --out " + (b / "bounds.csv").string() + shard).exit_code, 0);
    ASSERT_EQ(run_tool("probe " + d.string() + " --sample 12 --quiet --out " + pr.string() + shard).exit_code, 0);
  }
  const auto damaged = [&](const fs::path& dir, const std::string& shard_file, const std::string& output,
                           const std::function<void(nlohmann::json&)>& edit, const std::string& why) {
    const fs::path file = dir / shard_file;
    const std::string saved = read_file(file);
    auto j = nlohmann::json::parse(saved);
    edit(j);
    write_file_atomic(file, j.dump());
    const ToolRun r = run_tool("merge " + d.string() + " --out " + dir.string());
    EXPECT_EQ(r.exit_code, 1) << why << "\n" << r.output;
    EXPECT_NE(r.output.find(why), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / output)) << why;
    write_file_atomic(file, saved);
  };
  const std::string bounds_1 = "bounds_shard-1-of-2.json", probe_1 = "probe_shard-1-of-2.json";
  const std::string named = (b / bounds_1).string() + " is damaged (";
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["contacts"][0] = -1; },
          named + "contact -1 is not one of the packing's 81); run shard 1/2's job again or remove it");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["contacts"][0] = 81; }, "contact 81 is not one");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["contacts"][0] = 2; },
          "contact 2 belongs to shard 0, not 1");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["contacts"][0] = 3; }, "contact 3 is listed twice");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["fn_min"][0] = nullptr; }, "type must be number");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["fn_max"].erase(0); }, "39 maxima");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["fn_min"][1] = -0.5; }, "a negative fn_min");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["iterations"] = 1e300; }, "iterations must be an integer");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["unscaled_solves"] = -2; }, "unscaled_solves is negative");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["busy_seconds"] = -1; }, "busy_seconds is -1, not >= 0");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j.erase("lp_seconds"); }, "lp_seconds");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j = nlohmann::json::array(); }, "is not a shard");
  damaged(b, "bounds_shard-0-of-2.json", "bounds.csv", [](nlohmann::json& j) { j["options"]["lp_tolerance"] = 1.0; },
          "is damaged (force bounds: the LP tolerance must be in [1e-12, 1e-06] (got 1)");
  damaged(b, bounds_1, "bounds.csv", [](nlohmann::json& j) { j["options"]["open_tol_F0"] = 1e-4; },
          "come from runs with other settings");
  damaged(pr, probe_1, "probes.csv", [](nlohmann::json& j) { j["wall_seconds"] = "x"; },
          (pr / probe_1).string() + " is damaged (");
  damaged(pr, probe_1, "probes.csv", [](nlohmann::json& j) { j["ranks"] = 5; }, "ranks is not an array");
  damaged(pr, probe_1, "probes.csv", [](nlohmann::json& j) { j["ranks"][0]["busy_seconds"] = -3; },
          "busy_seconds is -3, not >= 0");
  const auto state_0 = nlohmann::json::parse(read_file(pr / "probe_shard-0-of-2.json")).at("state");
  ASSERT_FALSE(state_0.at("rows").empty());
  damaged(pr, probe_1, "probes.csv", [&](nlohmann::json& j) { j["state"] = state_0; }, "belongs to shard 0, not 1");
  // shard 1 stopped after one probe: a consistent state, short of the shard's share
  const fs::path stopped = root_ / "stopped";
  ASSERT_EQ(run_tool("probe " + d.string() + " --sample 12 --quiet --threads 1 --shard 1/2 --stop-after 1 --out " +
                     stopped.string()).exit_code, 3);
  const auto one_probe = nlohmann::json::parse(read_file(stopped / "probe_checkpoint-shard-1-of-2.json")).at("state");
  ASSERT_EQ(one_probe.at("rows").size(), 1u);
  damaged(pr, probe_1, "probes.csv", [&](nlohmann::json& j) { j["state"] = one_probe; },
          "do not cover every probed contact");
  write_file_atomic(pr / "probe_shard-2-of-2.json", "{}");
  const ToolRun beyond = run_tool("merge " + d.string() + " --out " + pr.string());
  EXPECT_EQ(beyond.exit_code, 1) << beyond.output;
  EXPECT_NE(beyond.output.find("numbered beyond its 2 shards"), std::string::npos) << beyond.output;
  fs::remove(pr / "probe_shard-2-of-2.json");
  // Undamaged, both merge.
  for (const auto& [dir, output] : {std::pair{b, "bounds.csv"}, std::pair{pr, "probes.csv"}}) {
    const ToolRun r = run_tool("merge " + d.string() + " --out " + dir.string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir / output));
  }
}

}  // namespace
}  // namespace unjam
