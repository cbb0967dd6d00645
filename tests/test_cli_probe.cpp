// `unjam probe` end to end on the fixture p50-mu0.1 with the LP probe: F_crit of a single
// contact (--contact K) and of a seeded subset (--sample S) against the fixture's independent
// maxima fn_max (HiGHS, bounds-reference.csv: the LP probe's F_crit is that maximum), the
// opening of the probed pair in the written displacement field, and probes.csv against
// probe_summary.json.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "cli_fixture_checks.hpp"
#include "cli_run.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {
namespace {

namespace fs = std::filesystem;
using testing::printed_value;
using testing::read_json_file;
using testing::reference_bounds;
using testing::run_tool;

class CliProbe : public testing::FixtureCopy {
 protected:
  void SetUp() override { copy("p50-mu0.1"); }
  double F0() const { return read_json_file(dir_ / "meta.json")["F0"].get<double>(); }
  // A campaign (`campaign`: the command up to --out) run with `option` (e.g. "--cd-accept-residual
  // 1e-4") records `key` = value in its settings, and its checkpoint does not resume without the
  // option; the same campaign without it records no `key`. Returns the summary of the one without.
  nlohmann::json expect_recorded_where_set(const std::string& campaign, const std::string& option,
                                           const std::string& key, double value) {
    const fs::path recorded = root_ / "recorded", unrecorded = root_ / "unrecorded";
    testing::ToolRun r = run_tool(campaign + option + " --stop-after 1 --out " + q(recorded));
    EXPECT_EQ(r.exit_code, 3) << r.output;  // stopped after one probe
    r = run_tool(campaign + "--out " + q(recorded));
    EXPECT_NE(r.exit_code, 0) << r.output;  // the checkpoint's setting differs
    EXPECT_NE(r.output.find(key), std::string::npos) << r.output;
    r = run_tool(campaign + option + " --out " + q(recorded));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(read_json_file(recorded / "probe_summary.json")["settings"][key], value);
    r = run_tool(campaign + "--out " + q(unrecorded));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json without = read_json_file(unrecorded / "probe_summary.json");
    EXPECT_FALSE(without["settings"].contains(key));
    return without;
  }
  // Runs `command`, which must exit 0 and print every one of `phrases`.
  testing::ToolRun run_printing(const std::string& command, std::initializer_list<const char*> phrases) {
    testing::ToolRun r = run_tool(command);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    for (const char* phrase : phrases) EXPECT_NE(r.output.find(phrase), std::string::npos) << phrase << "\n" << r.output;
    return r;
  }
};

TEST_F(CliProbe, SingleContactLpEqualsTheReferenceMaximumAndOpensThePair) {
  const CsvTable contacts = CsvTable::read(dir_ / "contacts.csv");
  const auto ref = reference_bounds("p50-mu0.1");
  const double g = 1e-9;
  for (const int k : {1, 3}) {
    const fs::path out = root_ / ("one-" + std::to_string(k));
    fs::create_directories(out);
    const testing::ToolRun r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
                                        " --method lp --out " + q(out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const int a = static_cast<int>(contacts.integer(k, contacts.column("a")));
    const int b = static_cast<int>(contacts.integer(k, contacts.column("b")));
    ASSERT_EQ(ref.count({a, b}), 1u) << "contact " << k;
    const double fn_max = ref.at({a, b}).second, fn = contacts.number(k, contacts.column("fn"));
    // Printed with 6 decimals in units of F0.
    EXPECT_NEAR(printed_value(r.output, "F_crit / F0"), fn_max / F0(), 2e-6) << r.output;
    EXPECT_NEAR(printed_value(r.output, "F_cont / F0"), fn / F0(), 2e-6) << r.output;
    EXPECT_NE(r.output.find("converged yes"), std::string::npos) << r.output;

    // The field: one row per grain; u / g in ux_g, uy_g; the pair opens by g along n
    // (the kinematic field's residual: within 10 %).
    const CsvTable field = CsvTable::read(out / ("probe-" + std::to_string(k) + ".csv"));
    ASSERT_EQ(field.rows(), 50u);
    const std::size_t ux = field.column("ux"), uy = field.column("uy");
    for (std::size_t i = 0; i < field.rows(); ++i) {
      EXPECT_EQ(field.integer(i, field.column("id")), static_cast<std::int64_t>(i));
      EXPECT_NEAR(field.number(i, field.column("ux_g")), field.number(i, ux) / g, 1e-9);
    }
    const double nx = contacts.number(k, contacts.column("nx")), ny = contacts.number(k, contacts.column("ny"));
    const double opening = (field.number(b, ux) - field.number(a, ux)) * nx + (field.number(b, uy) - field.number(a, uy)) * ny;
    EXPECT_NEAR(opening / g, 1.0, 0.1) << "contact " << k;
  }
}

TEST_F(CliProbe, SampleProbesSeededForceCarryingContactsAndSummarisesThem) {
  const std::string args = " --sample 10 --method lp --quiet --threads 2 --out ";
  const fs::path out = root_ / "sample", again = root_ / "again", other = root_ / "other";
  for (const fs::path& d : {out, again, other}) fs::create_directories(d);
  testing::ToolRun r = run_tool("probe " + q(dir_) + args + q(out));
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const CsvTable probes = CsvTable::read(out / "probes.csv");
  const CsvTable contacts = CsvTable::read(dir_ / "contacts.csv");
  const auto ref = reference_bounds("p50-mu0.1");
  const double F0 = this->F0();
  ASSERT_EQ(probes.rows(), 10u);
  std::set<std::int64_t> seen;
  double sum_crit = 0.0, sum_cont = 0.0;
  for (std::size_t i = 0; i < probes.rows(); ++i) {
    const std::int64_t k = probes.integer(i, probes.column("contact"));
    EXPECT_TRUE(seen.insert(k).second) << "contact " << k << " probed twice";
    const int a = static_cast<int>(probes.integer(i, probes.column("a")));
    const int b = static_cast<int>(probes.integer(i, probes.column("b")));
    EXPECT_EQ(a, contacts.integer(k, contacts.column("a")));
    EXPECT_EQ(b, contacts.integer(k, contacts.column("b")));
    const double f_cont = probes.number(i, probes.column("f_cont"));
    const double f_crit = probes.number(i, probes.column("f_crit"));
    EXPECT_EQ(f_cont, contacts.number(k, contacts.column("fn")));
    EXPECT_GT(f_cont, 1e-9 * F0) << "a probed contact carries force";
    ASSERT_EQ(ref.count({a, b}), 1u);
    EXPECT_NEAR(f_crit, ref.at({a, b}).second, 1e-6 * F0) << "contact " << k;
    EXPECT_EQ(probes.field(i, probes.column("method")), "lp");
    EXPECT_EQ(probes.integer(i, probes.column("converged")), 1);
    sum_crit += f_crit;
    sum_cont += f_cont;
  }
  const nlohmann::json s = read_json_file(out / "probe_summary.json");
  EXPECT_EQ(s["probes"].get<int>(), 10);
  EXPECT_EQ(s["not_converged"].get<int>(), 0);
  EXPECT_EQ(s["method"], "lp");
  EXPECT_FALSE(s.contains("f_inertia_over_F0"));  // lp has no dynamics: no inertia of a step
  for (std::size_t i = 0; i < probes.rows(); ++i) EXPECT_EQ(probes.field(i, probes.column("f_inertia")), "");
  EXPECT_DOUBLE_EQ(s["F0"].get<double>(), F0);
  // <F_crit>/<F_cont>: a ratio of the means over the probed contacts.
  EXPECT_NEAR(s["F_crit_over_F_cont"].get<double>(), sum_crit / sum_cont, 1e-12);
  EXPECT_NEAR(s["F_cont_over_F0"].get<double>(), sum_cont / 10 / F0, 1e-12);
  {  // its standard error over the 10 contacts (the delta method, docs/probe.md "Campaigns")
    const double R = s["F_crit_over_F_cont"].get<double>();
    double e2 = 0.0;
    for (std::size_t i = 0; i < probes.rows(); ++i) {
      const double e = probes.number(i, probes.column("f_crit")) - R * probes.number(i, probes.column("f_cont"));
      e2 += e * e;
    }
    EXPECT_NEAR(s["F_crit_over_F_cont_err"].get<double>(), std::sqrt(e2 / 90.0) / (sum_cont / 10), 1e-12);
    EXPECT_GT(s["F_crit_over_F_cont_err"].get<double>(), 0.0);
  }
  EXPECT_NE(s["command"].get<std::string>().find("--sample 10"), std::string::npos);
  for (const char* f : {"response_field.csv", "response_profile.csv"})
    EXPECT_GT(CsvTable::read(out / f).rows(), 0u) << f;

  // The subset is seeded: the same seed gives the same bytes, another seed other contacts.
  r = run_tool("probe " + q(dir_) + args + q(again));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_file(again / "probes.csv"), read_file(out / "probes.csv"));
  r = run_tool("probe " + q(dir_) + args + q(other) + " --seed 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable second = CsvTable::read(other / "probes.csv");
  std::set<std::int64_t> seen2;
  for (std::size_t i = 0; i < second.rows(); ++i) seen2.insert(second.integer(i, second.column("contact")));
  EXPECT_EQ(seen2.size(), 10u);
  EXPECT_NE(seen2, seen);
}

TEST_F(CliProbe, TheExactProbeDefaultsToTheQuasiStaticTimeStep) {
  // Without --dt the exact probe takes dt = sqrt(g / 1e-5) (1e-2 at g = 1e-9; 0.1 at g = 1e-7),
  // the quasi-static limit (docs/probe.md, "The quasi-static limit"), recorded in the
  // summary; nlgs keeps 1e-3. The same bytes as --dt given explicitly, other bytes than
  // dt = 1e-3 (the inertial term).
  const std::string args = " --sample 3 --method cd --quiet --threads 1 --out ";
  const fs::path none = root_ / "dt-default", same = root_ / "dt-1e-2", paper = root_ / "dt-1e-3",
                 big = root_ / "g-1e-7";
  for (const fs::path& d : {none, same, paper, big}) fs::create_directories(d);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(none)).exit_code, 0);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(same) + " --dt 1e-2").exit_code, 0);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(paper) + " --dt 1e-3").exit_code, 0);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(big) + " --g 1e-7").exit_code, 0);
  EXPECT_DOUBLE_EQ(read_json_file(none / "probe_summary.json")["settings"]["dt"].get<double>(), 1e-2);
  EXPECT_NEAR(read_json_file(big / "probe_summary.json")["settings"]["dt"].get<double>(), 0.1, 1e-15);
  EXPECT_EQ(read_file(none / "probes.csv"), read_file(same / "probes.csv"));
  EXPECT_NE(read_file(none / "probes.csv"), read_file(paper / "probes.csv"));
  // g = 1e-7 at dt = 0.1 is the step of g = 1e-9 at dt = 1e-2 (the same g / dt^2).
  const CsvTable a = CsvTable::read(none / "probes.csv"), b = CsvTable::read(big / "probes.csv");
  ASSERT_EQ(a.rows(), b.rows());
  const CsvTable c = CsvTable::read(paper / "probes.csv");
  for (std::size_t i = 0; i < a.rows(); ++i) {
    EXPECT_NEAR(a.number(i, a.column("f_crit")) / b.number(i, b.column("f_crit")), 1.0, 1e-9) << "row " << i;
    // the inertia of the step, m |u| / dt^2, depends on g / dt^2 only too; at dt = 1e-3 it
    // is larger (the same field, near the quasi-static limit, over a 100 times smaller dt^2)
    const double fi = a.number(i, a.column("f_inertia"));
    EXPECT_NEAR(fi / b.number(i, b.column("f_inertia")), 1.0, 1e-6) << "row " << i;
    EXPECT_GT(c.number(i, c.column("f_inertia")) / fi, 30.0) << "row " << i;
  }
  const nlohmann::json inertia = read_json_file(none / "probe_summary.json")["f_inertia_over_F0"];
  EXPECT_EQ(inertia["probes"].get<int>(), 3);
  EXPECT_LE(inertia["median"].get<double>(), inertia["max"].get<double>());
  const fs::path nlgs = root_ / "nlgs-dt";
  fs::create_directories(nlgs);
  const testing::ToolRun r =
      run_tool("probe " + q(dir_) + " --sample 1 --method nlgs --max-sweeps 200 --quiet --threads 1 --out " + q(nlgs));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_DOUBLE_EQ(read_json_file(nlgs / "probe_summary.json")["settings"]["dt"].get<double>(), 1e-3);
}

TEST_F(CliProbe, MaxInertiaLeavesProbesOutOfTheAveragesOnly) {
  // --max-inertia X: a threshold above every probe's f_inertia changes no output but the
  // recorded setting; one below every probe leaves all of them out of the averages and the
  // means (their rows stay, counted as inertial).
  const std::string args = " --sample 4 --method cd --quiet --threads 1 --out ";
  const fs::path plain = root_ / "inertia-none", high = root_ / "inertia-high", low = root_ / "inertia-low";
  for (const fs::path& d : {plain, high, low}) fs::create_directories(d);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(plain)).exit_code, 0);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(high) + " --max-inertia 1").exit_code, 0);
  const testing::ToolRun r = run_tool("probe " + q(dir_) + args + q(low) + " --max-inertia 1e-12");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("left out of the means and averages: 4 probes with f_inertia above 1e-12 F0"),
            std::string::npos) << r.output;
  for (const char* f : {"probes.csv", "response_field.csv", "response_profile.csv"})
    EXPECT_EQ(read_file(plain / f), read_file(high / f)) << f;
  EXPECT_EQ(read_file(plain / "probes.csv"), read_file(low / "probes.csv"));
  EXPECT_NE(read_file(plain / "response_profile.csv"), read_file(low / "response_profile.csv"));
  const nlohmann::json a = read_json_file(plain / "probe_summary.json"), b = read_json_file(high / "probe_summary.json"),
                       c = read_json_file(low / "probe_summary.json");
  EXPECT_FALSE(a["settings"].contains("max_inertia_F0"));
  EXPECT_DOUBLE_EQ(b["settings"]["max_inertia_F0"].get<double>(), 1.0);
  EXPECT_EQ(a["inertial"].get<int>(), 0);
  EXPECT_EQ(b["inertial"].get<int>(), 0);
  EXPECT_EQ(c["inertial"].get<int>(), 4);
  EXPECT_EQ(a["F_crit_over_F_cont"], b["F_crit_over_F_cont"]);
  EXPECT_EQ(c["probes"].get<int>(), 4);
}

TEST_F(CliProbe, PartialWritesTheOutputsOfTheCheckpointAndLeavesTheCampaignToResume) {
  // A campaign stopped after 3 of 6 probes: --partial DIR writes the outputs of those 3 to DIR
  // (its summary says 3 of 6), probes nothing and changes nothing of the campaign, which then
  // resumes to the bytes of an uninterrupted run.
  const fs::path out = root_ / "campaign", part = root_ / "so-far", whole = root_ / "whole";
  for (const fs::path& d : {out, whole}) fs::create_directories(d);
  const std::string args = " --sample 6 --method lp --quiet --threads 1 --out ";
  testing::ToolRun r = run_tool("probe " + q(dir_) + args + q(out) + " --stop-after 3");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  const std::string checkpoint = read_file(out / "probe_checkpoint.json");
  r = run_tool("probe " + q(dir_) + args + q(out) + " --partial " + q(part));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 of 6 probes of"), std::string::npos) << r.output;
  EXPECT_EQ(read_file(out / "probe_checkpoint.json"), checkpoint);
  EXPECT_FALSE(fs::exists(out / "probes.csv"));
  const nlohmann::json s = read_json_file(part / "probe_summary.json");
  EXPECT_EQ(s["partial"]["probes_done"].get<int>(), 3);
  EXPECT_EQ(s["partial"]["probes_planned"].get<int>(), 6);
  EXPECT_TRUE(s["wall_seconds"].is_null());
  EXPECT_EQ(s["probes"].get<int>(), 3);
  const CsvTable t = CsvTable::read(part / "probes.csv");
  ASSERT_EQ(t.rows(), 3u);
  double f_cont = 0.0, f_crit = 0.0;
  for (std::size_t i = 0; i < t.rows(); ++i) {
    f_cont += t.number(i, t.column("f_cont"));
    f_crit += t.number(i, t.column("f_crit"));
  }
  EXPECT_NEAR(s["F_crit_over_F_cont"].get<double>(), f_crit / f_cont, 1e-12);

  // Refused: the campaign's own directory, a single contact, other settings, no checkpoint.
  r = run_tool("probe " + q(dir_) + args + q(out) + " --partial " + q(out));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("is the campaign's output directory"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + " --contact 1 --partial " + q(part));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--partial goes with --all or --sample"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + " --sample 6 --method lp --g 1e-8 --out " + q(out) + " --partial " + q(part));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("other settings"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + args + q(whole) + " --partial " + q(part));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no checkpoint of this campaign"), std::string::npos) << r.output;
  EXPECT_EQ(read_file(out / "probe_checkpoint.json"), checkpoint);

  // The campaign resumes and finishes as if never read; its first 3 rows are the partial's.
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(out)).exit_code, 0);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(whole)).exit_code, 0);
  EXPECT_EQ(read_file(out / "probes.csv"), read_file(whole / "probes.csv"));
  EXPECT_FALSE(read_json_file(out / "probe_summary.json").contains("partial"));
  const CsvTable all = CsvTable::read(out / "probes.csv");
  std::set<std::int64_t> finished;
  for (std::size_t i = 0; i < all.rows(); ++i) finished.insert(all.integer(i, all.column("contact")));
  for (std::size_t i = 0; i < t.rows(); ++i) EXPECT_EQ(finished.count(t.integer(i, t.column("contact"))), 1u);

  // A shard's checkpoint: planned are the shard's share of the sample, its contacts at places
  // p with p mod 3 = i in the sorted sample: 2 of the 6 for every shard, whatever the contacts'
  // numbers (one probe leaves it unfinished).
  const std::vector<int> sample(finished.begin(), finished.end());
  const int i = 1;
  const std::string shard = " --shard " + std::to_string(i) + "/3";
  const fs::path sharded = root_ / "sharded", shard_part = root_ / "shard-so-far";
  fs::create_directories(sharded);
  r = run_tool("probe " + q(dir_) + args + q(sharded) + shard + " --stop-after 1");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  r = run_tool("probe " + q(dir_) + args + q(sharded) + shard + " --partial " + q(shard_part));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json sp = read_json_file(shard_part / "probe_summary.json");
  EXPECT_EQ(sp["partial"]["probes_done"].get<int>(), 1);
  EXPECT_EQ(sp["partial"]["probes_planned"].get<int>(), 2);
  const CsvTable so_far = CsvTable::read(shard_part / "probes.csv");
  ASSERT_EQ(so_far.rows(), 1u);
  const auto first = so_far.integer(0, so_far.column("contact"));
  EXPECT_TRUE(first == sample[1] || first == sample[4]) << first;
}

TEST_F(CliProbe, ASingleProbeSaysItIsRunningEveryRunningEverySeconds) {
  // `--contact K --method cd --running-every 0`: the line "contact K: probing for T (N pieces
  // so far)" at every poll of the probe, N = 1, 2, 3, ..., at least the pieces of its path;
  // none with --quiet or the default interval (a probe of well under 5 min); the field's
  // bytes are those of a run without the lines; a negative interval is refused.
  const int k = 3;
  const auto probe = [&](const std::string& name, const std::string& extra) {
    const fs::path out = root_ / name;
    fs::create_directories(out);
    testing::ToolRun r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
                                  " --method cd --threads 1 --out " + q(out) + " " + extra);
    return std::pair{r, read_file(out / ("probe-" + std::to_string(k) + ".csv"))};
  };
  const auto [every, field_every] = probe("every", "--running-every 0");
  ASSERT_EQ(every.exit_code, 0) << every.output;
  const std::string line = "contact " + std::to_string(k) + ": probing for ";
  long long lines = 0;
  for (std::size_t at = every.output.find(line); at != std::string::npos; at = every.output.find(line, at + 1)) {
    const std::size_t open = every.output.find('(', at), end = every.output.find('\n', at);
    ASSERT_LT(open, end) << every.output.substr(at, end - at);
    EXPECT_EQ(std::stoll(every.output.substr(open + 1)), ++lines) << every.output.substr(at, end - at);
    EXPECT_NE(every.output.substr(open, end - open).find("pieces so far)"), std::string::npos);
  }
  const double pieces = printed_value(every.output, "sweeps/pivots");
  EXPECT_GT(pieces, 0.0) << every.output;
  EXPECT_GE(static_cast<double>(lines), pieces) << every.output;

  const auto [plain, field_plain] = probe("plain", "");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(plain.output.find(line), std::string::npos) << plain.output;
  EXPECT_EQ(field_plain, field_every);
  const auto [quiet, field_quiet] = probe("quiet", "--running-every 0 --quiet");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find(line), std::string::npos) << quiet.output;
  EXPECT_EQ(field_quiet, field_every);

  const testing::ToolRun bad = run_tool("probe " + q(dir_) + " --contact 3 --method cd --running-every -1 --out " +
                                        q(root_ / "bad"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--running-every"), std::string::npos) << bad.output;
}

TEST_F(CliProbe, TheSummaryCountsTheTimeOfEveryRunThatMadeTheCampaign) {
  // A campaign of 6 probes made in three runs (stopped after 2, 2, then finished): each save
  // of the checkpoint records the runs so far ("runs"), --partial and the summary report them
  // (all_runs), and the last run's own wall time and ranks stay as they were.
  const fs::path out = root_ / "campaign", part = root_ / "so-far";
  fs::create_directories(out);
  const std::string cmd = "probe " + q(dir_) + " --sample 6 --method lp --quiet --threads 1 --out " + q(out);
  const auto runs_of_checkpoint = [&] { return read_json_file(out / "probe_checkpoint.json").at("runs"); };
  testing::ToolRun r = run_tool(cmd + " --stop-after 2");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  const nlohmann::json first = runs_of_checkpoint();
  EXPECT_EQ(first.at("runs").get<int>(), 1);
  EXPECT_EQ(first.at("untimed").get<int>(), 0);
  EXPECT_GT(first.at("busy_seconds").get<double>(), 0.0);
  EXPECT_GE(first.at("wall_seconds").get<double>(), first.at("busy_seconds").get<double>());  // one thread
  r = run_tool(cmd + " --partial " + q(part));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_json_file(part / "probe_summary.json").at("all_runs"), first);
  EXPECT_NE(r.output.find("over 1 run: "), std::string::npos) << r.output;

  r = run_tool(cmd + " --stop-after 2");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  const nlohmann::json second = runs_of_checkpoint();
  EXPECT_EQ(second.at("runs").get<int>(), 2);
  EXPECT_GT(second.at("busy_seconds").get<double>(), first.at("busy_seconds").get<double>());
  EXPECT_GT(second.at("wall_seconds").get<double>(), first.at("wall_seconds").get<double>());

  r = run_tool(cmd);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("over 3 runs: "), std::string::npos) << r.output;
  const nlohmann::json s = read_json_file(out / "probe_summary.json");
  const nlohmann::json& all = s.at("all_runs");
  EXPECT_EQ(all.at("runs").get<int>(), 3);
  EXPECT_EQ(all.at("untimed").get<int>(), 0);
  ASSERT_EQ(s.at("ranks").size(), 1u);
  const double last_busy = s.at("ranks")[0].at("busy_seconds").get<double>();
  EXPECT_NEAR(all.at("busy_seconds").get<double>(), second.at("busy_seconds").get<double>() + last_busy, 1e-9);
  EXPECT_GE(all.at("wall_seconds").get<double>(),
            second.at("wall_seconds").get<double>() + s.at("wall_seconds").get<double>());

  // A checkpoint without the record (written before it was kept, or with it damaged) resumes
  // as before; its probes are counted as untimed.
  for (const nlohmann::json bad : {nlohmann::json(nullptr), nlohmann::json("x"),
                                   nlohmann::json{{"runs", -1}, {"wall_seconds", 1}, {"busy_seconds", 1}, {"untimed", 0}}}) {
    const fs::path again = root_ / "again";
    fs::remove_all(again);
    fs::create_directories(again);
    const std::string cmd2 = "probe " + q(dir_) + " --sample 6 --method lp --quiet --threads 1 --out " + q(again);
    ASSERT_EQ(run_tool(cmd2 + " --stop-after 2").exit_code, 3);
    nlohmann::json ck = read_json_file(again / "probe_checkpoint.json");
    if (bad.is_null()) ck.erase("runs");
    else ck["runs"] = bad;
    write_file_atomic(again / "probe_checkpoint.json", ck.dump());
    r = run_tool(cmd2);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("2 probes from a checkpoint that did not record its time"), std::string::npos) << r.output;
    const nlohmann::json a = read_json_file(again / "probe_summary.json").at("all_runs");
    EXPECT_EQ(a.at("runs").get<int>(), 1) << bad;
    EXPECT_EQ(a.at("untimed").get<int>(), 2) << bad;
    EXPECT_EQ(read_file(again / "probes.csv"), read_file(out / "probes.csv"));
  }
}

TEST_F(CliProbe, EachProbesCpuIsWrittenBesideTheResultsAndSurvivesResumesAndShards) {
  // probe_cpu.csv: one row per probe, the contacts of probes.csv, through a stop and a resume
  // (the checkpoint keeps the first run's probes' CPU) and through shards merged; --status and
  // the summary give its median; probes.csv stays the bytes of one uninterrupted run.
  const fs::path out = root_ / "campaign", whole = root_ / "whole", sharded = root_ / "sharded";
  for (const fs::path& d : {out, whole, sharded}) fs::create_directories(d);
  const std::string args = " --sample 6 --method cd --quiet --threads 1 --out ";
  testing::ToolRun r = run_tool("probe " + q(dir_) + args + q(out) + " --stop-after 2");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  EXPECT_EQ(read_json_file(out / "probe_checkpoint.json").at("probe_cpu").size(), 2u);
  r = run_tool("merge " + q(dir_) + " --out " + q(out) + " --status");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("CPU per probe (2 of the 2 done record it): median "), std::string::npos) << r.output;
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(out)).exit_code, 0);
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(whole)).exit_code, 0);
  for (int i = 0; i < 2; ++i)
    ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(sharded) + " --shard " + std::to_string(i) + "/2").exit_code, 0);
  r = run_tool("merge " + q(dir_) + " --out " + q(sharded));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("CPU per probe: median "), std::string::npos) << r.output;
  for (const fs::path& d : {out, whole, sharded}) {
    EXPECT_EQ(read_file(d / "probes.csv"), read_file(whole / "probes.csv")) << d;
    const CsvTable probes = CsvTable::read(d / "probes.csv"), cpu = CsvTable::read(d / "probe_cpu.csv");
    ASSERT_EQ(cpu.rows(), 6u) << d;
    for (std::size_t i = 0; i < cpu.rows(); ++i) {
      EXPECT_EQ(cpu.integer(i, cpu.column("contact")), probes.integer(i, probes.column("contact"))) << d;
      EXPECT_GE(cpu.number(i, cpu.column("cpu_seconds")), 0.0) << d;
    }
    const nlohmann::json c = read_json_file(d / "probe_summary.json").at("cpu_per_probe");
    EXPECT_EQ(c.at("probes").get<int>(), 6) << d;
    EXPECT_GE(c.at("max_seconds").get<double>(), c.at("median_seconds").get<double>()) << d;
  }
}

TEST_F(CliProbe, ACheckpointOfOtherSettingsNamesThemAndResumesWithThem) {
  // A cd campaign stopped at dt = 1e-3 (exit 3) is not resumed at the default dt: the error
  // names the setting and both values, the checkpoint is kept, and the same command with
  // --dt 1e-3 finishes it to the bytes of an uninterrupted run.
  const fs::path out = root_ / "resume-dt", whole = root_ / "whole-dt";
  for (const fs::path& d : {out, whole}) fs::create_directories(d);
  const std::string args = " --sample 4 --method cd --quiet --threads 1 --out ";
  testing::ToolRun r = run_tool("probe " + q(dir_) + args + q(out) + " --dt 1e-3 --stop-after 2");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  r = run_tool("probe " + q(dir_) + args + q(out));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("other settings (dt: 0.001 there, 0.01 here)"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "probe_checkpoint.json"));
  r = run_tool("probe " + q(dir_) + args + q(out) + " --dt 1e-3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(run_tool("probe " + q(dir_) + args + q(whole) + " --dt 1e-3").exit_code, 0);
  EXPECT_EQ(read_file(out / "probes.csv"), read_file(whole / "probes.csv"));
}

TEST_F(CliProbe, TheLpMethodsTolerancesFcritIsBoundsMaximumAtTheSameTolerance) {
  // --lp-tol: the lp probe's F_crit is `unjam bounds`' fn_max of the same contact over the same
  // set (--gap-tol 1e-6: the packing's touch gap, the default of a packing that records none)
  // at the same LP tolerance, to the bit, at the default 1e-9 and at 1e-8 (which moves some
  // maxima, so the test tells the two apart); the tolerance is recorded where set and a
  // checkpoint made with it is not resumed without it.
  const std::string campaign = "probe " + q(dir_) + " --sample 20 --method lp --quiet --threads 2 ";
  const nlohmann::json by_default = expect_recorded_where_set(campaign, " --lp-tol 1e-8", "lp_tolerance", 1e-8);
  EXPECT_EQ(by_default["settings"].value("lp_tolerance", 0.0), 0.0) << "the default is not written out";
  using Ends = std::map<std::pair<std::int64_t, std::int64_t>, double>;
  const auto column = [](const fs::path& csv, const char* name) {
    const CsvTable t = CsvTable::read(csv);
    Ends m;
    for (std::size_t i = 0; i < t.rows(); ++i)
      m[{t.integer(i, t.column("a")), t.integer(i, t.column("b"))}] = t.number(i, t.column(name));
    return m;
  };
  int moved = 0;
  const Ends crit_default = column(root_ / "unrecorded" / "probes.csv", "f_crit");
  const Ends crit_tolerant = column(root_ / "recorded" / "probes.csv", "f_crit");
  ASSERT_EQ(crit_default.size(), 20u);
  for (const auto& [tol, crit] : {std::pair{std::string(), crit_default}, std::pair{std::string(" --lp-tol 1e-8"), crit_tolerant}}) {
    const fs::path b = root_ / "b.csv";
    const testing::ToolRun r = run_tool("bounds " + q(dir_) + " --threads 2 --gap-tol 1e-6" + tol + " --out " + q(b));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const Ends fn_max = column(b, "fn_max");
    for (const auto& [ab, f] : crit) {
      ASSERT_EQ(fn_max.count(ab), 1u);
      EXPECT_EQ(f, fn_max.at(ab)) << ab.first << "-" << ab.second << tol;
    }
  }
  for (const auto& [ab, f] : crit_default) moved += f != crit_tolerant.at(ab) ? 1 : 0;
  EXPECT_GT(moved, 0) << "1e-8 and 1e-9 give the same maxima: the test cannot tell them apart";
}

TEST_F(CliProbe, AWindowIsRecordedAndRefusedWhereItDoesNotApply) {
  // --window 2.5 (docs/probe.md, "A window around the probed pair"): a cd campaign records it
  // in its settings, so a checkpoint made with it is not resumed without it; a single probe
  // writes the forces of the window's contacts only; lp and nlgs, and a radius <= 0, are
  // refused with exit 1.
  const fs::path out = root_ / "window", single = root_ / "window-single";
  for (const fs::path& d : {out, single}) fs::create_directories(d);
  const std::string args = " --sample 4 --method cd --quiet --threads 1 --out " + q(out);
  testing::ToolRun r = run_tool("probe " + q(dir_) + args + " --window 2.5 --stop-after 2");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  r = run_tool("probe " + q(dir_) + args);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("window_d"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + args + " --window 2.5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_json_file(out / "probe_summary.json")["settings"]["window_d"].get<double>(), 2.5);
  EXPECT_NE(r.output.find("d(r) and alpha are those of windows of 2.5 mean diameters"), std::string::npos)
      << r.output;
  const CsvTable rows = CsvTable::read(out / "probes.csv");
  ASSERT_EQ(rows.rows(), 4u);
  for (std::size_t i = 0; i < rows.rows(); ++i) EXPECT_EQ(rows.integer(i, rows.column("converged")), 1) << i;

  r = run_tool("probe " + q(dir_) + " --contact 1 --method cd --window 2.5 --quiet --out " + q(single));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable forces = CsvTable::read(single / "probe-1-forces.csv");
  EXPECT_GT(forces.rows(), 0u);
  EXPECT_LT(forces.rows(), CsvTable::read(dir_ / "contacts.csv").rows());
  for (const std::string method : {"lp", "nlgs"}) {
    r = run_tool("probe " + q(dir_) + " --contact 1 --window 2.5 --method " + method + " --out " + q(single));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("--window applies to the exact methods"), std::string::npos) << r.output;
  }
  r = run_tool("probe " + q(dir_) + " --contact 1 --method cd --window 0 --out " + q(single));
  EXPECT_EQ(r.exit_code, 1) << r.output;
}

TEST_F(CliProbe, TheExactStepsForcesFileHoldsASolutionAnyoneCanCheck) {
  // probe-K-forces.csv (docs/probe.md, "Which contacts the step opens and sets sliding"): per
  // contact the packing's fn0, the step's forces, its displacements in g and its state. Read
  // alone, they satisfy Signorini's and Coulomb's conditions with non-dilatant sliding to the
  // exactness tolerance, the states follow the stated rule, and the summary's counts are the
  // file's. Contact 5 opens two contacts and slides 29; contact 1 opens none.
  const double tol = 1e-6, F0v = F0(), mu = read_json_file(dir_ / "meta.json")["mu"].get<double>();
  const CsvTable packing = CsvTable::read(dir_ / "contacts.csv");
  for (const int k : {1, 5}) {
    const fs::path single = root_ / ("states-" + std::to_string(k));
    fs::create_directories(single);
    const testing::ToolRun r =
        run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) + " --method cd --out " + q(single));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const CsvTable t = CsvTable::read(single / ("probe-" + std::to_string(k) + "-forces.csv"));
    ASSERT_EQ(t.rows(), packing.rows());
    const std::size_t cfn0 = t.column("fn0"), cfn = t.column("fn"), cft = t.column("ft"), cun = t.column("un"),
                      cut = t.column("ut"), cst = t.column("state");
    int loaded = 0, opened = 0, sliding = 0, closed = 0, probed_rows = 0;
    for (std::size_t i = 0; i < t.rows(); ++i) {
      const int contact = static_cast<int>(t.integer(i, t.column("contact")));
      const double fn0 = t.number(i, cfn0), fn = t.number(i, cfn), ft = t.number(i, cft);
      const double un = t.number(i, cun), ut = t.number(i, cut);
      const std::string state(t.field(i, cst));
      EXPECT_EQ(fn0, packing.number(static_cast<std::size_t>(contact), packing.column("fn"))) << contact;
      EXPECT_GE(fn, 0.0) << contact;
      EXPECT_GE(un, -tol) << contact;                                 // no penetration
      if (fn > tol * F0v) EXPECT_LE(un, tol) << contact;              // a loaded pair stays closed
      EXPECT_LE(std::abs(ft), mu * fn + tol * F0v) << contact;        // inside the cone
      EXPECT_EQ(state == "open", fn <= tol * F0v) << contact << " " << state;
      if (state == "slide") {                                         // slips against its force, at the edge
        EXPECT_GT(std::abs(ut), tol) << contact;
        EXPECT_GE(std::abs(ft), mu * fn - tol * F0v) << contact;
        EXPECT_LE(ft * ut, 0.0) << contact;
      } else {
        EXPECT_TRUE(state == "stick" || state == "open") << contact << " " << state;
        if (state == "stick") EXPECT_LE(std::abs(ut), tol) << contact;
      }
      if (contact == k) {
        ++probed_rows;
        EXPECT_NEAR(fn / F0v, printed_value(r.output, "F_crit / F0"), 1e-6);
        EXPECT_NEAR(un, 0.0, tol);  // the probed pair opens by g
        continue;
      }
      if (fn0 > tol * F0v) {
        ++loaded;
        opened += state == "open";
        sliding += state == "slide";
      } else {
        closed += state != "open";
      }
    }
    EXPECT_EQ(probed_rows, 1);
    const std::string said = "of the " + std::to_string(loaded) + " other contacts loaded in the packing the step opens " +
                             std::to_string(opened) + " and slides " + std::to_string(sliding) + " (|u_t| > 1e-06 g), and " +
                             std::to_string(closed) + " of the " +
                             std::to_string(static_cast<int>(t.rows()) - 1 - loaded) + " without force close";
    EXPECT_NE(r.output.find(said), std::string::npos) << said << "\n" << r.output;
    EXPECT_EQ(opened, k == 5 ? 2 : 0);
    EXPECT_EQ(sliding, k == 5 ? 29 : 31);
  }
  // A campaign's probes.csv carries the same two counts per probe (opened, sliding; empty for
  // lp), and its summary their medians: the seeded sample's contact 56 as a single probe.
  const fs::path campaign = root_ / "states-campaign", lp = root_ / "states-lp", single = root_ / "states-56";
  for (const fs::path& d : {campaign, lp, single}) fs::create_directories(d);
  testing::ToolRun r = run_tool("probe " + q(dir_) + " --sample 4 --seed 1 --method cd --threads 2 --out " + q(campaign));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("that the step opens / sets sliding: median 1 / 27.5 over 4 probes"), std::string::npos)
      << r.output;
  const CsvTable rows = CsvTable::read(campaign / "probes.csv");
  ASSERT_EQ(rows.rows(), 4u);
  std::size_t at56 = rows.rows();
  for (std::size_t i = 0; i < rows.rows(); ++i)
    if (rows.integer(i, rows.column("contact")) == 56) at56 = i;
  ASSERT_LT(at56, rows.rows());
  r = run_tool("probe " + q(dir_) + " --contact 56 --method cd --out " + q(single));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string said = "the step opens " + std::string(rows.field(at56, rows.column("opened"))) + " and slides " +
                           std::string(rows.field(at56, rows.column("sliding"))) + " (";
  EXPECT_NE(r.output.find(said), std::string::npos) << said << "\n" << r.output;
  EXPECT_EQ(rows.integer(at56, rows.column("opened")), 6);
  EXPECT_EQ(read_json_file(campaign / "probe_summary.json")["step_states"]["probes"].get<int>(), 4);
  r = run_tool("probe " + q(dir_) + " --sample 2 --seed 1 --method lp --quiet --out " + q(lp));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable lp_rows = CsvTable::read(lp / "probes.csv");
  for (std::size_t i = 0; i < lp_rows.rows(); ++i) {
    EXPECT_EQ(lp_rows.field(i, lp_rows.column("opened")), "");
    EXPECT_EQ(lp_rows.field(i, lp_rows.column("sliding")), "");
  }
  EXPECT_FALSE(read_json_file(lp / "probe_summary.json").contains("step_states"));
}

TEST_F(CliProbe, ABudgetOfPiecesIsRecordedCountedAndLeavesTheOtherProbesAsTheyWere) {
  // --cd-max-pieces 70 on the seeded sample of 4 (docs/probe.md, "A budget of pieces per
  // probe"): contacts 42 and 56 take 66 and 65 pieces, 38 and 78 more. The probes within the
  // budget have the rows of a run without it; the others stop at 71 pieces without a
  // solution; the summary counts them; the setting is recorded (not resumed without it) and
  // refused for lp and below 0.
  const auto campaign = [&](const fs::path& out, const std::string& extra) {
    fs::create_directories(out);
    return run_tool("probe " + q(dir_) + " --sample 4 --method cd --threads 1 --out " + q(out) + extra);
  };
  const fs::path free = root_ / "budget-free", out = root_ / "budget";
  ASSERT_EQ(campaign(free, " --quiet").exit_code, 0);
  testing::ToolRun r = campaign(out, " --quiet --cd-max-pieces 70 --stop-after 1");
  ASSERT_EQ(r.exit_code, 3) << r.output;
  r = campaign(out, " --quiet");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cd_max_pieces"), std::string::npos) << r.output;
  r = campaign(out, " --cd-max-pieces 70");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("at most 70 pieces per probe"), std::string::npos) << r.output;
  const CsvTable a = CsvTable::read(free / "probes.csv"), b = CsvTable::read(out / "probes.csv");
  ASSERT_EQ(a.rows(), 4u);
  ASSERT_EQ(b.rows(), 4u);
  int stopped = 0;
  for (std::size_t i = 0; i < a.rows(); ++i) {
    const long long pieces = a.integer(i, a.column("sweeps"));
    if (pieces <= 70) {
      for (std::size_t c = 0; c < a.header().size(); ++c) EXPECT_EQ(b.field(i, c), a.field(i, c)) << i << " " << c;
    } else {
      ++stopped;
      EXPECT_EQ(b.integer(i, b.column("sweeps")), 71) << i;
      EXPECT_EQ(b.integer(i, b.column("converged")), 0) << i;
    }
  }
  EXPECT_EQ(stopped, 2);
  EXPECT_NE(r.output.find("stopped by the budget of 70 pieces per probe (--cd-max-pieces): 2 probes"),
            std::string::npos)
      << r.output;
  const nlohmann::json summary = read_json_file(out / "probe_summary.json");
  EXPECT_EQ(summary["settings"]["cd_max_pieces"].get<long long>(), 70);
  EXPECT_EQ(summary["over_budget"]["probes"].get<int>(), 2);
  EXPECT_EQ(summary["over_budget"]["exact"].get<int>(), 0);
  EXPECT_EQ(summary["without_solution"].get<int>(), 2);
  r = run_tool("probe " + q(dir_) + " --contact 38 --method cd --cd-max-pieces 70 --out " + q(out));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("spent the budget of --cd-max-pieces (70 pieces)"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + " --contact 38 --method lp --cd-max-pieces 70 --out " + q(out));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--cd-max-pieces applies to the cd method"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + " --contact 38 --method cd --cd-max-pieces -1 --out " + q(out));
  EXPECT_EQ(r.exit_code, 1) << r.output;
}

TEST_F(CliProbe, CompliantContinuationIsRecordedAndReachesTheStaticStartsSolutionsHere) {
  // --method cd --cd-start compliant on a seeded sample of p50-mu0.1: every probe exact, and
  // on this packing the same F_crit as the path from the static network within 1e-3
  // (docs/probe.md, "Where the path starts": one contact of the 82 differs by 2e-4). The
  // start is recorded in the summary's settings (and absent for the default start), so a
  // checkpoint of one start does not resume the other.
  const std::string args = " --sample 6 --method cd --quiet --threads 1 --out ";
  const fs::path soft = root_ / "compliant", rigid = root_ / "static";
  for (const fs::path& d : {soft, rigid}) fs::create_directories(d);
  testing::ToolRun r = run_tool("probe " + q(dir_) + args + q(soft) + " --cd-start compliant");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_tool("probe " + q(dir_) + args + q(rigid));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable a = CsvTable::read(soft / "probes.csv"), b = CsvTable::read(rigid / "probes.csv");
  ASSERT_EQ(a.rows(), 6u);
  ASSERT_EQ(b.rows(), 6u);
  for (std::size_t i = 0; i < a.rows(); ++i) {
    EXPECT_EQ(a.integer(i, a.column("contact")), b.integer(i, b.column("contact")));
    EXPECT_EQ(a.integer(i, a.column("converged")), 1) << "row " << i;
    EXPECT_LE(a.number(i, a.column("residual")), 1e-6) << "row " << i;
    const double f_soft = a.number(i, a.column("f_crit")), f_rigid = b.number(i, b.column("f_crit"));
    EXPECT_NEAR(f_soft / f_rigid, 1.0, 1e-3) << "row " << i;
  }
  const nlohmann::json js = read_json_file(soft / "probe_summary.json");
  const nlohmann::json jr = read_json_file(rigid / "probe_summary.json");
  EXPECT_EQ(js["settings"]["cd_start"], "compliant");
  EXPECT_EQ(js["settings"]["cd_softer_starts"], 2);  // recorded where it applies
  EXPECT_FALSE(jr["settings"].contains("cd_start"));
  EXPECT_FALSE(jr["settings"].contains("cd_softer_starts"));
  EXPECT_EQ(js["not_converged"].get<int>(), 0);
}

}  // namespace
TEST_F(CliProbe, TheInteriorPointStartIsRecordedExactAndTheSameForAnyThreadCount) {
  // --cd-start interior on a seeded sample of p50-mu0.1: every probe exact, F_crit within 1 %
  // of the static start's (at mu = 0.1 the exact solutions of one step differ by up to a few
  // 1e-3 here), the start and its fallback's softer starts recorded in the summary, the same
  // bytes with 1 and 2 threads, and the single probe lists the interior-point iterations.
  const std::string args = " --sample 6 --method cd --quiet --out ";
  const fs::path one = root_ / "interior1", two = root_ / "interior2", rigid = root_ / "static";
  testing::ToolRun r = run_tool("probe " + q(dir_) + args + q(one) + " --cd-start interior --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_tool("probe " + q(dir_) + args + q(two) + " --cd-start interior --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_tool("probe " + q(dir_) + args + q(rigid) + " --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_file(one / "probes.csv"), read_file(two / "probes.csv"));
  const CsvTable a = CsvTable::read(one / "probes.csv"), b = CsvTable::read(rigid / "probes.csv");
  ASSERT_EQ(a.rows(), 6u);
  for (std::size_t i = 0; i < a.rows(); ++i) {
    EXPECT_EQ(a.integer(i, a.column("converged")), 1) << "row " << i;
    EXPECT_LE(a.number(i, a.column("residual")), 1e-6) << "row " << i;
    EXPECT_NEAR(a.number(i, a.column("f_crit")) / b.number(i, b.column("f_crit")), 1.0, 1e-2) << "row " << i;
  }
  const nlohmann::json j = read_json_file(one / "probe_summary.json");
  EXPECT_EQ(j["settings"]["cd_start"], "interior");
  EXPECT_EQ(j["settings"]["cd_interior_states_pieces"], 0.1);  // CdPathSettings::interior_states_pieces
  EXPECT_EQ(j["settings"]["cd_interior_states_stall"], 20);  // CdPathSettings::interior_states_stall
  EXPECT_EQ(j["settings"]["cd_interior_states_retries"], 2);  // CdPathSettings::interior_states_retries
  EXPECT_EQ(j["settings"]["cd_interior_iterations"], 100);  // CdPathSettings::interior_max_iterations
  EXPECT_FALSE(j["settings"].contains("cd_interior_neighbourhood"));  // off by default, recorded where on
  EXPECT_EQ(j["settings"]["cd_softer_starts"], 2);
  const int k = static_cast<int>(a.integer(0, a.column("contact")));
  r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) + " --method cd --cd-start interior --out " +
               q(root_ / "single"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("interior-point start: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("path 1 from the interior point's states at compliance 0.001"), std::string::npos) << r.output;
  // Without the path from the iterate's states (--cd-interior-states-pieces 0): the first
  // path is the forces' states', and the campaign records no cd_interior_states_pieces, so a
  // checkpoint of either kind resumes only with its own (docs/probe.md, "The iterate's own
  // states"); the same for that path's cut where it stalls (--cd-interior-states-stall) and its
  // retry (--cd-interior-states-retries).
  r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
               " --method cd --cd-start interior --cd-interior-states-pieces 0 --out " + q(root_ / "single0"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("from the interior point's states"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("path 1 at compliance 0.001"), std::string::npos) << r.output;
  const std::string part = " --sample 3 --method cd --cd-start interior --threads 1 --out " + q(root_ / "part");
  r = run_tool("probe " + q(dir_) + part + " --stop-after 1");
  ASSERT_NE(r.exit_code, 0) << r.output;  // stopped, its checkpoint kept
  r = run_tool("probe " + q(dir_) + part + " --cd-interior-states-pieces 0");
  EXPECT_NE(r.exit_code, 0) << r.output;  // the checkpoint is the other start's
  EXPECT_NE(r.output.find("cd_interior_states_pieces"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + part + " --cd-interior-states-stall 0");
  EXPECT_NE(r.exit_code, 0) << r.output;  // nor without the cut where that path stalls
  EXPECT_NE(r.output.find("cd_interior_states_stall"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + part + " --cd-interior-states-retries 0");
  EXPECT_NE(r.exit_code, 0) << r.output;  // nor without that path's retry
  EXPECT_NE(r.output.find("cd_interior_states_retries"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + part + " --cd-interior-iterations 40");
  EXPECT_NE(r.exit_code, 0) << r.output;  // nor under the interior-point method's former cap
  EXPECT_NE(r.output.find("cd_interior_iterations"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + part + " --cd-interior-neighbourhood 1e-3");
  EXPECT_NE(r.exit_code, 0) << r.output;  // nor with the interior-point method's second run
  EXPECT_NE(r.output.find("cd_interior_neighbourhood"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + part);
  EXPECT_EQ(r.exit_code, 0) << r.output;  // and resumes with its own
  // Under the former cap of 40 the key is not recorded, so the checkpoints made before it was a
  // setting (which have no such key) resume with --cd-interior-iterations 40, and only so.
  const std::string part40 = " --sample 3 --method cd --cd-start interior --threads 1 --out " + q(root_ / "part40");
  r = run_tool("probe " + q(dir_) + part40 + " --cd-interior-iterations 40 --stop-after 1");
  ASSERT_NE(r.exit_code, 0) << r.output;
  EXPECT_FALSE(read_json_file(root_ / "part40" / "probe_checkpoint.json")["settings"].contains("cd_interior_iterations"));
  r = run_tool("probe " + q(dir_) + part40);
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cd_interior_iterations"), std::string::npos) << r.output;
  r = run_tool("probe " + q(dir_) + part40 + " --cd-interior-iterations 40");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
               " --method cd --cd-start interior --cd-interior-states-pieces -1 --out " + q(root_ / "bad"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
               " --method cd --cd-start interior --cd-interior-states-stall -1 --out " + q(root_ / "bad2"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
               " --method cd --cd-start interior --cd-interior-states-retries -1 --out " + q(root_ / "bad3"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
               " --method cd --cd-start interior --cd-interior-iterations 0 --out " + q(root_ / "bad4"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  for (const char* bad : {"-0.5", "1", "nan"}) {
    r = run_tool("probe " + q(dir_) + " --contact " + std::to_string(k) +
                 " --method cd --cd-start interior --cd-interior-neighbourhood " + bad + " --out " + q(root_ / "bad5"));
    EXPECT_NE(r.exit_code, 0) << bad << "\n" << r.output;
  }
}

TEST_F(CliProbe, SaysWhenTheInteriorPointMethodRanAgainInTheWideNeighbourhood) {
  // Contact 48 of p200-mu1: plain Mehrotra stalls at a natural residual of 0.53, the second run
  // in the wide neighbourhood ends at 2e-6 and its iterate is the start (docs/probe.md,
  // "Keeping the iterates centred"); without --cd-interior-neighbourhood there is no second run.
  const fs::path p200 = fs::path(UNJAM_FIXTURES_DIR) / "p200-mu1";
  testing::ToolRun r = run_tool("probe " + q(p200) + " --contact 48 --method cd --cd-start interior "
                                "--cd-interior-neighbourhood 1e-3 --threads 1 --out " + q(root_ / "wide"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("interior-point start: 100 iterations, natural residual 5."), std::string::npos) << r.output;
  // where the probe's time went: the interior-point method's and each path's CPU
  EXPECT_NE(r.output.find("(F0, g / dt^2); "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" pieces, "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" factorisations, "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" s of CPU\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("again in the wide neighbourhood: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("its iterate is the start"), std::string::npos) << r.output;
  r = run_tool("probe " + q(p200) + " --contact 48 --method cd --cd-start interior --threads 1 --out " +
               q(root_ / "plain"));
  EXPECT_EQ(r.output.find("again in the wide neighbourhood"), std::string::npos) << r.output;
  // contact 4: no path from the start's iterate is exact, and the other iterate's are listed
  r = run_tool("probe " + q(p200) + " --contact 4 --method cd --cd-start interior --cd-interior-neighbourhood 1e-3 "
               "--threads 1 --out " + q(root_ / "other"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("path 6 from the other iterate's states at compliance 0.001"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("from the other iterate's forces' states"), std::string::npos) << r.output;
}

TEST_F(CliProbe, TheContinuationStartsWhereTheUserSaysAndTheCampaignRecordsIt) {
  // Contact 14 of p200-mu1 (dt = 1e-3): from the default compliance 0.1 the lowering stops at
  // 0.012 and the restart below is exact; with --cd-compliant-start 1e-3 the first path is
  // exact (docs/probe.md, "Where the continuation starts"). A campaign records the setting where
  // it is not the default, and its checkpoint does not resume with another one.
  const fs::path p200 = fs::path(UNJAM_FIXTURES_DIR) / "p200-mu1";
  const std::string one = "probe " + q(p200) + " --contact 14 --dt 1e-3 --method cd --cd-start compliant --threads 1 ";
  testing::ToolRun r = run_tool(one + "--cd-compliant-start 1e-3 --out " + q(root_ / "low"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("path 1 at compliance 0.001: full opening; lowered to the rigid step"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("path 2"), std::string::npos) << r.output;
  r = run_tool(one + "--out " + q(root_ / "default"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("path 1 at compliance 0.1: full opening; 8 lowerings, stopped at compliance 0.012"),
            std::string::npos) << r.output;
  expect_recorded_where_set("probe " + q(dir_) + " --sample 2 --seed 1 --method cd --cd-start compliant --quiet --threads 1 ",
                            "--cd-compliant-start 1e-4", "cd_compliant_start", 1e-4);
}

TEST_F(CliProbe, StopsAtANearExactSolutionWhereTheUserAcceptsItAndTheCampaignRecordsIt) {
  // Contact 8 of p200-mu1 (quasi-static, compliant start): the first path ends near-exact at
  // 1.04e-5 g and the restart below it is exact. With --cd-accept-residual 1e-4 the probe stops
  // at the near-exact solution, says so and exits 0: a result the user asked for, not an error
  // (docs/probe.md, "Accepting a near-exact solution"). A campaign records the setting, and its
  // checkpoint does not resume without it.
  const fs::path p200 = fs::path(UNJAM_FIXTURES_DIR) / "p200-mu1";
  const std::string one = "probe " + q(p200) + " --contact 8 --method cd --cd-start compliant --threads 1 ";
  testing::ToolRun r = run_printing(
      one + "--cd-accept-residual 1e-4 --out " + q(root_ / "accepted"),
      {"converged NO", "near-exact: the search stopped at the first solution within --cd-accept-residual 0.0001 g"});
  EXPECT_EQ(r.output.find("path 2"), std::string::npos) << r.output;
  run_printing(one + "--out " + q(root_ / "exact"), {"converged yes", "path 2"});
  const nlohmann::json without =
      expect_recorded_where_set("probe " + q(p200) + " --sample 2 --seed 1 --method cd --cd-start compliant --quiet --threads 1 ",
                                "--cd-accept-residual 1e-4", "cd_accept_residual", 1e-4);
  EXPECT_FALSE(without.contains("accepted"));
  // The summary counts the near-exact probes within the residual: of --sample 3 --seed 11, contacts
  // 29 and 256 end near-exact (1.0e-6 and 5.5e-6 g), exact without the option.
  const std::string three = "probe " + q(p200) + " --sample 3 --seed 11 --method cd --cd-start compliant --threads 1 ";
  r = run_tool(three + "--cd-accept-residual 1e-4 --out " + q(root_ / "three"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("not converged: 2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("near-exact within the accepted residual of 0.0001 g (--cd-accept-residual): 2 probes"),
            std::string::npos) << r.output;
  const nlohmann::json three_summary = read_json_file(root_ / "three" / "probe_summary.json");
  EXPECT_EQ(three_summary["accepted"]["probes"], 2);
  EXPECT_EQ(three_summary["accepted"]["accept_residual"], 1e-4);
  r = run_tool(three + "--out " + q(root_ / "three-exact"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("not converged: 0"), std::string::npos) << r.output;
}

TEST_F(CliProbe, SettlesAtAnExactSolutionWhereTheUserSaysAndTheCampaignRecordsIt) {
  // Contact 34 of p200-mu1 (quasi-static, compliant start): the lowering passes a compliance of
  // 1e-5 with an exact solution and goes on down to 3.65e-7 (134 pieces); with
  // --cd-settle-compliance 1e-5 the probe ends there in 8, exact, and its path says so (docs/
  // probe.md, "Settling at an exact solution"). A campaign records the setting, says it, and
  // its checkpoint does not resume without it.
  const fs::path p200 = fs::path(UNJAM_FIXTURES_DIR) / "p200-mu1";
  const std::string one = "probe " + q(p200) + " --contact 34 --method cd --cd-start compliant --threads 1 ";
  run_printing(one + "--cd-settle-compliance 1e-5 --out " + q(root_ / "settled"),
               {"converged yes  sweeps/pivots 8 ",
                "path 1 at compliance 0.1: full opening; 14 lowerings, settled at compliance 6.1e-06"});
  run_printing(one + "--out " + q(root_ / "rigid"),
               {"converged yes  sweeps/pivots 134 ",
                "path 1 at compliance 0.1: full opening; 23 lowerings, stopped at compliance 3.65e-07 (loop)"});
  const std::string campaign =
      "probe " + q(p200) + " --sample 2 --seed 1 --method cd --cd-start compliant --quiet --threads 1 ";
  run_printing(campaign + "--cd-settle-compliance 1e-5 --out " + q(root_ / "says"),
               {"settling at exact solutions at compliances <= 1e-05"});
  // A budget's summary tells the stopped probes that are exact all the same: of --sample 6
  // --seed 1 under 100 pieces, contacts 162 (near-exact) and 244 (exact, 2.8e-7 g).
  const fs::path budget = root_ / "budget";
  run_printing("probe " + q(p200) + " --sample 6 --seed 1 --method cd --cd-start compliant --cd-max-pieces 100 "
                   "--quiet --threads 1 --out " + q(budget),
               {"stopped by the budget of 100 pieces per probe (--cd-max-pieces): 2 probes, 1 of them exact"});
  const CsvTable rows = CsvTable::read(budget / "probes.csv");
  int stopped_exact = 0;
  for (std::size_t i = 0; i < rows.rows(); ++i)
    stopped_exact += rows.integer(i, rows.column("sweeps")) > 100 && rows.integer(i, rows.column("converged")) == 1;
  EXPECT_EQ(stopped_exact, 1);
  EXPECT_EQ(read_json_file(budget / "probe_summary.json")["over_budget"]["exact"].get<int>(), stopped_exact);
  expect_recorded_where_set(campaign, "--cd-settle-compliance 1e-5", "cd_settle_compliance", 1e-5);
  expect_recorded_where_set(campaign, "--cd-lost-factor 1e3", "cd_lost_factor", 1e3);
  expect_recorded_where_set(campaign, "--cd-restart-floor 1e-3", "cd_restart_floor", 1e-3);
  run_printing(campaign + "--cd-restart-floor 1e-3 --out " + q(root_ / "floor"), {", no restart below compliance 0.001"});
}

TEST_F(CliProbe, SaysWhereTheCompliantContinuationStopped) {
  // Contact 73 of the frozen 100-disk structure at mu = 1, quasi-static, one starting
  // compliance: the lowering from 0.1 stops at a fold at 0.012 and no restart is exact. The
  // probe says so, names the compliance and lists every path (docs/probe.md, "Where the path
  // starts"), and exits 1.
  const fs::path frozen = fs::path(UNJAM_FIXTURES_DIR) / "p100-frozen-mu1";
  const fs::path out = root_ / "fold";
  fs::create_directories(out);
  const testing::ToolRun r = run_tool("probe " + q(frozen) + " --contact 73 --method cd --cd-start compliant "
                                      "--cd-softer-starts 0 --threads 1 --out " + q(out));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("the compliance's lowering stopped at 0.012 (the branch of soft solutions turns back "
                          "there), and the other paths listed below found no exact solution"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("path 1 at compliance 0.1: full opening; 8 lowerings, stopped at compliance 0.012"),
            std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("--cd-start compliant takes"), std::string::npos) << r.output;  // it is the start
  EXPECT_NE(r.output.find("--cd-compliant-start below 0.012 starts the continuation past that fold"),
            std::string::npos) << r.output;
  // and so it does: from 1e-3 the first path is lowered to an exact step
  const testing::ToolRun low = run_tool("probe " + q(frozen) + " --contact 73 --method cd --cd-start compliant "
                                        "--cd-softer-starts 0 --cd-compliant-start 1e-3 --threads 1 --out " +
                                        q(root_ / "past-the-fold"));
  EXPECT_EQ(low.exit_code, 0) << low.output;
  EXPECT_NE(low.output.find("path 1 at compliance 0.001: full opening; lowered to the rigid step"), std::string::npos)
      << low.output;
}

TEST_F(CliProbe, RecordsTheContinuationInDtsSettingsAndSaysWhereItEndedShort) {
  // The continuation in dt's settings (--cd-inertial-*) are recorded where set, and a checkpoint
  // made with one does not resume without it (docs/probe.md, "The quasi-static step as the
  // limit of vanishing inertia").
  const fs::path p200 = fs::path(UNJAM_FIXTURES_DIR) / "p200-mu1";
  const std::string campaign =
      "probe " + q(p200) + " --sample 2 --seed 1 --method cd --cd-start inertial --cd-max-pieces 150 --quiet --threads 1 ";
  expect_recorded_where_set(campaign, "--cd-inertial-jumps 2", "cd_inertial_jumps", 2);
  expect_recorded_where_set(campaign, "--cd-inertial-factor 3", "cd_inertial_factor", 3.0);
  // Contact 82 (tests/test_cd_step.cpp): the interior start's share of 100 pieces spent at a
  // near-exact solution, the continuation's one stage from dt / 1000 not exact, the rest of the
  // budget unspent. The probe says so and exits 1.
  const testing::ToolRun r = run_tool("probe " + q(p200) + " --contact 82 --method cd --cd-start interior-inertial "
                                      "--cd-max-pieces 100000 --cd-interior-share 0.001 --cd-inertial-factor 1000 "
                                      "--cd-inertial-stages 1 --cd-inertial-halvings 0 --cd-inertial-jumps 0 "
                                      "--threads 1 --out " + q(root_ / "share"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("the interior-point start spent its share of the budget (--cd-interior-share of "
                          "--cd-max-pieces) before an exact solution, and the continuation in dt ended short"),
            std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("spent the budget of --cd-max-pieces"), std::string::npos) << r.output;
}

TEST_F(CliProbe, SaysWhenTheBranchFromTheStaticNetworkClosesOnItself) {
  // Contact 49 of p200-mu1 at dt = 1e-3: the branch of the step through the static network
  // turns back at ~2.3e-5 of the opening and closes on itself, at every compliance tried
  // (docs/probe.md, "Why a path fails"). The single probe says so, exits 1 and names the
  // other selection, which solves it.
  const fs::path p200 = fs::path(UNJAM_FIXTURES_DIR) / "p200-mu1";
  const fs::path out = root_ / "loop";
  fs::create_directories(out);
  testing::ToolRun r = run_tool("probe " + q(p200) + " --contact 49 --method cd --dt 1e-3 --threads 1 --out " + q(out));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("through the static network closes on itself, turning back at 2.29e-05 of the opening"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--cd-start compliant"), std::string::npos) << r.output;
  // Every path followed is listed: the first and its two retries at other compliances.
  EXPECT_NE(r.output.find("path 1 at compliance 1e-07: stopped at 2.29e-05 of the opening (loop); no solution"),
            std::string::npos) << r.output;
  EXPECT_NE(r.output.find("path 3 at compliance 1e-08: "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("path 4 "), std::string::npos) << r.output;
  r = run_tool("probe " + q(p200) + " --contact 49 --method cd --dt 1e-3 --cd-start compliant --threads 1 --out " + q(out));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("path 1 at compliance 0.1: full opening; lowered to the rigid step; residual "),
            std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("path 2 "), std::string::npos) << r.output;
}

}  // namespace unjam
