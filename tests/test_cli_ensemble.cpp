// `unjam ensemble` end to end on the fixture p50-mu0.1: the LP intervals in ensemble.csv
// against the fixture's independent ones (HiGHS, bounds-reference.csv), both samplers' ranges
// inside them, F_crit of the LP probe equal to fn_max on every force-carrying contact, and
// ensemble.json against ensemble.csv (and its command line); a fixed seed gives the same
// bytes; --help of ensemble and bounds gives the defaults; `unjam threshold` brackets the
// friction threshold; --lp-tol and --open-tol give the intervals of `unjam bounds`.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cli_fixture_checks.hpp"
#include "cli_run.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {
namespace {

namespace fs = std::filesystem;
using testing::read_json_file;
using testing::reference_bounds;
using testing::run_tool;

class CliEnsemble : public testing::FixtureCopy {
 protected:
  void SetUp() override { copy("p50-mu0.1"); }
};

TEST_F(CliEnsemble, LpIntervalsSampledRangesAndCriticalForces) {
  const std::string command = "ensemble " + q(dir_) + " --samples 300 --probe lp --threads 2";
  const testing::ToolRun r = run_tool(command);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable t = CsvTable::read(dir_ / "ensemble.csv");
  const nlohmann::json j = read_json_file(dir_ / "ensemble.json");
  const double F0 = read_json_file(dir_ / "meta.json")["F0"].get<double>();
  const auto ref = reference_bounds("p50-mu0.1");
  const double tol = 1e-6 * F0;

  ASSERT_EQ(t.rows(), ref.size()) << "the admissible set: every force-carrying or touching contact";
  const auto col = [&t](const char* name) { return t.column(name); };
  int probed = 0;
  for (std::size_t i = 0; i < t.rows(); ++i) {
    const int a = static_cast<int>(t.integer(i, col("a"))), b = static_cast<int>(t.integer(i, col("b")));
    ASSERT_EQ(ref.count({a, b}), 1u) << a << "-" << b;
    const auto [lo, hi] = ref.at({a, b});
    const double fn_min = t.number(i, col("fn_min")), fn_max = t.number(i, col("fn_max"));
    EXPECT_NEAR(fn_min, lo, tol) << a << "-" << b;
    EXPECT_NEAR(fn_max, hi, tol) << a << "-" << b;
    for (const std::string s : {"hr_", "walk_"}) {
      const double mn = t.number(i, t.column(s + "min")), mx = t.number(i, t.column(s + "max"));
      const double mean = t.number(i, t.column(s + "mean"));
      EXPECT_GE(mn, fn_min - tol) << s << " " << a << "-" << b;
      EXPECT_LE(mx, fn_max + tol) << s << " " << a << "-" << b;
      EXPECT_LE(mn, mean) << s << " " << a << "-" << b;
      EXPECT_LE(mean, mx) << s << " " << a << "-" << b;
      EXPECT_GE(t.number(i, t.column(s + "std")), 0.0);
    }
    if (t.number(i, col("fn")) > 1e-9 * F0) {
      ++probed;
      EXPECT_NEAR(t.number(i, col("f_crit")), fn_max, tol) << a << "-" << b;
      EXPECT_EQ(t.field(i, col("f_crit_method")), "lp");
      EXPECT_EQ(t.integer(i, col("probe_converged")), 1);
    } else {
      EXPECT_EQ(t.field(i, col("f_crit")), "") << "no probe of a contact without force";
    }
  }
  EXPECT_EQ(probed, 81);

  EXPECT_NE(j["command"].get<std::string>().find("ensemble " + dir_.string() + " --samples 300"),
            std::string::npos) << "ensemble.json records the command line";
  EXPECT_EQ(j["contacts_used"].get<std::size_t>(), t.rows());
  EXPECT_DOUBLE_EQ(j["F0"].get<double>(), F0);
  EXPECT_EQ(j["samples"].get<int>(), 300);
  EXPECT_EQ(j["probe"]["method"], "lp");
  EXPECT_EQ(j["probe"]["contacts_probed"].get<int>(), probed);
  EXPECT_EQ(j["probe"]["unconverged"].get<int>(), 0);
  EXPECT_NEAR(j["probe"]["f_crit_over_fn_max"]["min"].get<double>(), 1.0, 1e-6);
  EXPECT_NEAR(j["probe"]["f_crit_over_fn_max"]["max"].get<double>(), 1.0, 1e-6);
  EXPECT_EQ(j["probe"]["f_crit_over_fn_max"]["within_1_percent"].get<int>(), probed);
  for (const char* m : {"hit_and_run", "walk"}) {
    EXPECT_EQ(j["methods"][m]["samples"].get<int>(), 300) << m;
    const double eta = j["methods"][m]["eta"].get<double>();
    const double coverage = j["methods"][m]["mean_coverage_of_lp_width"].get<double>();
    EXPECT_GT(eta, 0.0) << m;
    EXPECT_GT(coverage, 0.0) << m;
    EXPECT_LE(coverage, 1.0 + 1e-9) << m;
  }

  // The same seed: the same table, on another thread count.
  const std::string first = read_file(dir_ / "ensemble.csv");
  const testing::ToolRun again = run_tool("ensemble " + q(dir_) + " --samples 300 --probe lp --threads 1");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(read_file(dir_ / "ensemble.csv"), first);
}

TEST_F(CliEnsemble, OneSamplerWithoutProbesWritesOnlyItsColumns) {
  const testing::ToolRun r =
      run_tool("ensemble " + q(dir_) + " --samples 50 --method hit-and-run --probe none --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable t = CsvTable::read(dir_ / "ensemble.csv");
  EXPECT_EQ(t.header(), (std::vector<std::string>{"a", "b", "fn", "fn_min", "fn_max", "hr_min",
                                                  "hr_max", "hr_mean", "hr_std"}));
  const nlohmann::json j = read_json_file(dir_ / "ensemble.json");
  EXPECT_TRUE(j["methods"].contains("hit_and_run"));
  EXPECT_FALSE(j["methods"].contains("walk"));
  EXPECT_EQ(j["probe"]["method"], "none");
  EXPECT_FALSE(j["probe"].contains("contacts_probed"));
}

// --lp-tol and --open-tol (docs/ensemble.md, "The LP's tolerances") give ensemble.csv the
// intervals `unjam bounds` gives with the same tolerances, to the bit, and ensemble.json
// records them; the defaults are recorded too. --open-tol 1e-3 zeroes some minima the default
// leaves positive on this packing, so the comparison can tell the tolerances apart.
TEST_F(CliEnsemble, LpTolerancesGiveTheIntervalsOfBoundsAndAreRecorded) {
  const auto intervals = [](const fs::path& csv) {
    const CsvTable t = CsvTable::read(csv);
    std::map<std::pair<std::int64_t, std::int64_t>, std::pair<double, double>> m;  // both round-trip
    for (std::size_t i = 0; i < t.rows(); ++i)
      m[{t.integer(i, t.column("a")), t.integer(i, t.column("b"))}] = {
          t.number(i, t.column("fn_min")), t.number(i, t.column("fn_max"))};
    return m;
  };
  const std::string args = " --samples 50 --method hit-and-run --probe none --threads 2";
  ASSERT_EQ(run_tool("ensemble " + q(dir_) + args).exit_code, 0);
  const auto by_default = intervals(dir_ / "ensemble.csv");
  const nlohmann::json d = read_json_file(dir_ / "ensemble.json");
  EXPECT_EQ(d["parameters"]["lp_tolerance"].get<double>(), 1e-9);
  EXPECT_EQ(d["parameters"]["open_tol_F0"].get<double>(), 1e-9);

  const std::string tols = " --lp-tol 1e-8 --open-tol 1e-3";
  const testing::ToolRun e = run_tool("ensemble " + q(dir_) + args + tols);
  ASSERT_EQ(e.exit_code, 0) << e.output;
  const auto tolerant = intervals(dir_ / "ensemble.csv");
  const nlohmann::json j = read_json_file(dir_ / "ensemble.json");
  EXPECT_EQ(j["parameters"]["lp_tolerance"].get<double>(), 1e-8);
  EXPECT_EQ(j["parameters"]["open_tol_F0"].get<double>(), 1e-3);
  const testing::ToolRun b = run_tool("bounds " + q(dir_) + " --threads 2" + tols + " --out " + q(dir_ / "b.csv"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_EQ(tolerant, intervals(dir_ / "b.csv")) << "the ensemble's intervals are bounds' with the same tolerances";
  ASSERT_EQ(tolerant.size(), by_default.size());
  const double F0 = read_json_file(dir_ / "meta.json")["F0"].get<double>();
  int zeroed = 0;
  for (const auto& [ab, ends] : tolerant) {
    const double lo = by_default.at(ab).first;
    if (lo > 1e-9 * F0 && lo <= 1e-3 * F0) {
      ++zeroed;
      EXPECT_EQ(ends.first, 0.0) << ab.first << "-" << ab.second;
    }
  }
  EXPECT_GT(zeroed, 0) << "no minimum in (1e-9, 1e-3] F0: the test cannot tell the open tolerances apart";

  // The lp probe solves the LP at the ensemble's tolerance: over the probe's own set (the
  // packing's touch gap, 1e-6 here) its F_crit is fn_max to the bit (at 1e-8, where some
  // maxima differ from the default's; test_cli_probe shows they do).
  const testing::ToolRun p = run_tool("ensemble " + q(dir_) +
                                      " --samples 50 --method hit-and-run --probe lp --threads 2 --gap-tol 1e-6 --lp-tol 1e-8");
  ASSERT_EQ(p.exit_code, 0) << p.output;
  const CsvTable t = CsvTable::read(dir_ / "ensemble.csv");
  int probed = 0;
  for (std::size_t i = 0; i < t.rows(); ++i) {
    if (t.field(i, t.column("f_crit")).empty()) continue;
    ++probed;
    EXPECT_EQ(t.number(i, t.column("f_crit")), t.number(i, t.column("fn_max"))) << "row " << i;
  }
  EXPECT_EQ(probed, 81);
  const nlohmann::json pj = read_json_file(dir_ / "ensemble.json");
  EXPECT_EQ(pj["probe"]["f_crit_over_fn_max"]["min"].get<double>(), 1.0);
  EXPECT_EQ(pj["probe"]["f_crit_over_fn_max"]["max"].get<double>(), 1.0);
}

TEST_F(CliEnsemble, TheCdProbeTakesTheSettingsOfUnjamProbeAndRecordsThem) {
  // --cd-start and the other --cd-* options reach the ensemble's cd probes: their F_crit is that
  // of `unjam probe --all` with the same options, to the bit, and ensemble.json records the
  // settings as the probe campaign does; the default records only its start.
  const std::string cd = " --probe cd --cd-start interior --cd-max-pieces 4000";
  testing::ToolRun r = run_tool("ensemble " + q(dir_) + " --samples 20 --method hit-and-run --threads 2" + cd);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = read_json_file(dir_ / "ensemble.json");
  EXPECT_EQ(j["probe"]["settings"]["start"], "interior");
  EXPECT_EQ(j["probe"]["settings"]["cd_max_pieces"], 4000);
  const fs::path out = root_ / "all";
  r = run_tool("probe " + q(dir_) + " --all --method cd --cd-start interior --cd-max-pieces 4000 --quiet --threads 2 --out " + q(out));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json campaign = read_json_file(out / "probe_summary.json")["settings"];
  for (const auto& [key, value] : campaign.items())
    if (key.rfind("cd_", 0) == 0 && key != "cd_start") EXPECT_EQ(j["probe"]["settings"][key], value) << key;
  std::map<std::pair<std::int64_t, std::int64_t>, double> by_probe;
  const CsvTable probes = CsvTable::read(out / "probes.csv");
  for (std::size_t i = 0; i < probes.rows(); ++i)
    by_probe[{probes.integer(i, probes.column("a")), probes.integer(i, probes.column("b"))}] =
        probes.number(i, probes.column("f_crit"));
  const CsvTable t = CsvTable::read(dir_ / "ensemble.csv");
  int probed = 0;
  for (std::size_t i = 0; i < t.rows(); ++i) {
    if (t.field(i, t.column("f_crit")).empty()) continue;
    ++probed;
    const std::pair<std::int64_t, std::int64_t> ab{t.integer(i, t.column("a")), t.integer(i, t.column("b"))};
    ASSERT_EQ(by_probe.count(ab), 1u);
    EXPECT_EQ(t.number(i, t.column("f_crit")), by_probe.at(ab)) << ab.first << "-" << ab.second;
  }
  EXPECT_EQ(probed, 81);
  ASSERT_EQ(run_tool("ensemble " + q(dir_) + " --samples 20 --method hit-and-run --probe cd").exit_code, 0);
  const nlohmann::json d = read_json_file(dir_ / "ensemble.json")["probe"]["settings"];
  EXPECT_EQ(d["start"], "static");
  for (const auto& [key, value] : d.items()) EXPECT_NE(key.rfind("cd_", 0), 0u) << key << " recorded at its default";
}

// `unjam threshold` on p50-mu0.1 (its threshold is 0.048): the bracket in the JSON and the
// report, the parameters and the command; continued from a bracket; bad brackets, options and
// a missing packing are refused with nothing written.
TEST_F(CliEnsemble, ThresholdBracketsTheFrictionThreshold) {
  const testing::ToolRun r = run_tool("threshold " + q(dir_) + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = read_json_file(dir_ / "friction_threshold.json");
  const double lo = j["mu_s_low"].get<double>(), hi = j["mu_s_high"].get<double>();
  EXPECT_GT(lo, 0.048);
  EXPECT_LT(hi, 0.0482);
  EXPECT_LE(hi - lo, 1e-4 + 1e-15);
  EXPECT_EQ(j["mu"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(j["mu_s_over_mu"].get<double>(), hi / 0.1);
  EXPECT_EQ(j["lps"].get<int>(), 12);
  EXPECT_GT(j["simplex_iterations"].get<long long>(), 0);
  EXPECT_EQ(j["contacts_used"].get<int>(), 81);
  EXPECT_EQ(j["parameters"]["rel_tol"].get<double>(), 1e-3);
  EXPECT_TRUE(j["parameters"]["between"].is_null());
  EXPECT_NE(j["command"].get<std::string>().find("threshold"), std::string::npos);
  EXPECT_FALSE(j["program_version"].get<std::string>().empty());
  EXPECT_NE(r.output.find("friction threshold mu_s in ("), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("mu_s / mu = 0.48"), std::string::npos) << r.output;
  // Continued from a coarser bracket: the same end.
  const fs::path out = dir_ / "from.json";
  const testing::ToolRun c = run_tool("threshold " + q(dir_) + " --between 0.025 0.05 --out " + q(out));
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const nlohmann::json k = read_json_file(out);
  EXPECT_EQ(k["mu_s_high"].get<double>(), hi);
  EXPECT_EQ(k["mu_s_low"].get<double>(), lo);
  EXPECT_NE(c.output.find("threshold: 1 / "), std::string::npos) << "progress lines: " << c.output;
  const fs::path none = dir_ / "none.json";
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--between 0.05 0.1", "not empty at mu_low = 0.05"},
      {"--between 0.01 0.04", "empty at mu_high = 0.04"},
      {"--between 0.1 0.05", "0 <= mu_low < mu_high"},
      {"--between 0.1", "--between"},
      {"--rel-tol 1", "--rel-tol must be in (0, 1)"},
      {"--rel-tol 0", "must be a finite number > 0"}};
  for (const auto& [args, phrase] : bad) {
    const testing::ToolRun b = run_tool("threshold " + q(dir_) + " " + args + " --out " + q(none));
    EXPECT_EQ(b.exit_code, 1) << args << "\n" << b.output;
    EXPECT_NE(b.output.find(phrase), std::string::npos) << args << "\n" << b.output;
    EXPECT_LT(b.output.size(), 400u) << b.output;
    EXPECT_FALSE(fs::exists(none)) << args;
  }
  const testing::ToolRun missing = run_tool("threshold " + q(dir_ / "missing") + " --out " + q(none));
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_NE(missing.output.find("unjam: error:"), std::string::npos) << missing.output;
  EXPECT_FALSE(fs::exists(none));
}

// A stopped `unjam threshold` (--stop-after, as Ctrl-C) keeps its bracket in
// friction_threshold_checkpoint.json; the same command resumes from it without solving its ends
// again and ends on the bracket of one uninterrupted run, with every run's LPs counted, and
// removes the checkpoint. A checkpoint of other settings, a damaged one, or --between beside
// one is refused, and the checkpoint kept.
TEST_F(CliEnsemble, ThresholdStoppedResumesToTheBracketOfOneRun) {
  const fs::path whole = dir_ / "whole.json", out = dir_ / "t.json", cp = dir_ / "t_checkpoint.json";
  ASSERT_EQ(run_tool("threshold " + q(dir_) + " --quiet --out " + q(whole)).exit_code, 0);
  const nlohmann::json w = read_json_file(whole);
  const testing::ToolRun stopped = run_tool("threshold " + q(dir_) + " --quiet --stop-after 5 --out " + q(out));
  EXPECT_EQ(stopped.exit_code, 3) << stopped.output;
  EXPECT_NE(stopped.output.find("run the same command again to continue"), std::string::npos) << stopped.output;
  ASSERT_TRUE(fs::exists(cp));
  EXPECT_FALSE(fs::exists(out));
  const nlohmann::json c = read_json_file(cp);
  EXPECT_EQ(c["lps"].get<int>(), 5);
  const std::string saved = read_file(cp);
  const auto refused = [&](const std::string& args, const std::string& phrase) {
    const testing::ToolRun b = run_tool("threshold " + q(dir_) + " --quiet --out " + q(out) + " " + args);
    EXPECT_EQ(b.exit_code, 1) << args << "\n" << b.output;
    EXPECT_NE(b.output.find(phrase), std::string::npos) << args << "\n" << b.output;
    EXPECT_EQ(read_file(cp), saved) << args;
    EXPECT_FALSE(fs::exists(out)) << args;
  };
  refused("--rel-tol 2e-3", "rel_tol: 0.001 there, 0.002 here");
  refused("--between 0.025 0.05", "run without --between to continue it");
  const testing::ToolRun resumed = run_tool("threshold " + q(dir_) + " --out " + q(out));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("resuming from mu_s in ("), std::string::npos) << resumed.output;
  EXPECT_FALSE(fs::exists(cp));
  const nlohmann::json r = read_json_file(out);
  EXPECT_EQ(r["mu_s_low"].get<double>(), w["mu_s_low"].get<double>());
  EXPECT_EQ(r["mu_s_high"].get<double>(), w["mu_s_high"].get<double>());
  EXPECT_EQ(r["lps"].get<int>(), 12);
  EXPECT_EQ(r["runs"].get<int>(), 2);
  EXPECT_EQ(r["resumed_from"][0].get<double>(), c["mu_low"].get<double>());
  EXPECT_EQ(r["resumed_from"][1].get<double>(), c["mu_high"].get<double>());
  EXPECT_TRUE(w["resumed_from"].is_null());
  EXPECT_EQ(w["runs"].get<int>(), 1);
  // A damaged checkpoint is refused and kept.
  write_file_atomic(cp, "{\"settings\": ");
  fs::remove(out);
  const testing::ToolRun damaged = run_tool("threshold " + q(dir_) + " --quiet --out " + q(out));
  EXPECT_EQ(damaged.exit_code, 1) << damaged.output;
  EXPECT_NE(damaged.output.find("is not a threshold checkpoint"), std::string::npos) << damaged.output;
  EXPECT_TRUE(fs::exists(cp));
  EXPECT_FALSE(fs::exists(out));
}

// --help gives every option's default (CLI11 prints it after the type: "--samples INT=20000").
TEST(CliHelp, BoundsAndEnsembleShowTheirDefaults) {
  const testing::ToolRun e = run_tool("ensemble --help");
  ASSERT_EQ(e.exit_code, 0) << e.output;
  for (const char* d : {"--method TEXT:{hit-and-run,walk,both}=both", "--samples INT:NUMBER > 0=20000",
                        "--seed UINT:SEED=1", "--thin INT:NUMBER >= 0=0", "--burn-in INT:NUMBER >= 0=0",
                        "--kick FLOAT:NUMBER >= 0=1", "--walk-tol FLOAT:NUMBER > 0=1e-10",
                        "--probe-g FLOAT:NUMBER > 0=1e-09", "--probe-dt FLOAT:NUMBER >= 0=0",
                        "--probe-velocity-tol FLOAT:NUMBER > 0=1e-06", "--gap-tol FLOAT:NUMBER >= 0=1e-09",
                        "--fn-tol FLOAT:NUMBER >= 0=1e-09", "--threads INT:NUMBER >= 0=0",
                        "--lp-tol FLOAT:(NUMBER > 0) AND (FLOAT in [1e-12 - 1e-06])=1e-09",
                        "--open-tol FLOAT:(NUMBER > 0) AND (FLOAT in [0 - 0.001])=1e-09"})
    EXPECT_NE(e.output.find(d), std::string::npos) << d << " in\n" << e.output;
  const testing::ToolRun b = run_tool("bounds --help");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  for (const char* d : {"--gap-tol FLOAT:NUMBER >= 0=1e-09", "--fn-tol FLOAT:NUMBER >= 0=1e-09",
                        "--threads INT:NUMBER >= 0=0", "--method TEXT:{barrier,simplex}=barrier"})
    EXPECT_NE(b.output.find(d), std::string::npos) << d << " in\n" << b.output;
}

}  // namespace
}  // namespace unjam
