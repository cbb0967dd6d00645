// End-to-end tests of `unjam info`: the real executable on the fixture and on broken copies.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "unjam/core/atomic_file.hpp"

namespace unjam {
namespace {

namespace fs = std::filesystem;

const fs::path kFixtures = UNJAM_FIXTURES_DIR;

using CommandResult = testing::ToolRun;
CommandResult run_info(const std::string& args) { return testing::run_tool("info " + args); }

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// A writable copy of the p50 fixture in a fresh temp directory, removed at the end.
class BrokenCopy : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    root_ = fs::temp_directory_path() / ("unjam-cli-" + name + "-" + std::to_string(std::random_device{}()));
    dir_ = root_ / "p50";
    fs::create_directories(root_);
    fs::copy(kFixtures / "p50-mu0.1", dir_, fs::copy_options::recursive);
    for (const auto& e : fs::directory_iterator(dir_))
      fs::permissions(e.path(), fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::add);
  }
  void TearDown() override { fs::remove_all(root_); }

  void write(const char* file, const std::string& text) { std::ofstream(dir_ / file, std::ios::binary) << text; }
  std::string read(const char* file) { return read_file(dir_ / file); }

  // Runs `unjam info` on the copy and expects a one-line error containing `phrase`.
  void expect_error(const std::string& phrase) {
    const CommandResult r = run_info(quoted(dir_));
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(r.output.rfind("unjam: error: ", 0), 0u) << r.output;
    EXPECT_NE(r.output.find(phrase), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }

  fs::path root_, dir_;
};

// The value printed after a label, e.g. value_of(out, "rattlers") == "6 (N' = 44)".
std::string value_of(const std::string& out, const std::string& label) {
  const auto pos = out.find("\n" + label + " ");
  if (pos == std::string::npos) return {};
  const auto begin = out.find_first_not_of(' ', pos + 1 + label.size());
  return out.substr(begin, out.find('\n', begin) - begin);
}

TEST(CliInfo, PrintsTheFixtureStatistics) {
  const CommandResult r = run_info(quoted(kFixtures / "p50-mu0.1"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(value_of(r.output, "N"), "50");
  EXPECT_EQ(value_of(r.output, "mu"), "0.1");
  EXPECT_EQ(value_of(r.output, "seed"), "3");
  EXPECT_EQ(value_of(r.output, "phi").substr(0, 5), "0.829");
  EXPECT_EQ(value_of(r.output, "z (rattlers excluded)").substr(0, 4), "3.68");
  EXPECT_EQ(value_of(r.output, "rattlers"), "6 (N' = 44)");
  EXPECT_EQ(value_of(r.output, "contacts: carrying force / listed").substr(0, 7), "81 / 82");
  EXPECT_EQ(value_of(r.output, "P_in / P_ext"), "1");
  EXPECT_NE(value_of(r.output, "overlap: max / mean").find("4.62"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("written by unjam"), std::string::npos);
  EXPECT_EQ(r.output.find("isostatic"), std::string::npos);  // mu > 0
}

TEST(CliInfo, JsonHasTheSameNumbers) {
  const CommandResult r = run_info(quoted(kFixtures / "p50-mu0.1") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j.at("N"), 50);
  EXPECT_EQ(j.at("seed"), 3);
  EXPECT_EQ(j.at("rattlers"), 6);
  EXPECT_EQ(j.at("contacts_force_carrying"), 81);
  EXPECT_EQ(j.at("contacts_listed"), 82);
  EXPECT_NEAR(j.at("phi").get<double>(), 0.829, 5e-4);
  EXPECT_NEAR(j.at("z").get<double>(), 2.0 * 81 / 44, 1e-12);
  EXPECT_NEAR(j.at("P_in_over_P_ext").get<double>(), 1.0, 1e-6);
  EXPECT_LT(j.at("max_force_residual_over_F0").get<double>(), 1e-11);
  EXPECT_FALSE(j.contains("isostatic_excess"));
  // The contact rows fit the positions (packing/geometry_check.hpp): the gaps to rounding.
  EXPECT_LT(j.at("geometry_worst_over_tolerance").get<double>(), 1.0);
  EXPECT_LT(j.at("geometry_max_gap_mismatch").get<double>(), 1e-9);
  EXPECT_LT(j.at("geometry_max_branch_mismatch").get<double>(), 1e-9);
}

TEST_F(BrokenCopy, WorstGeometryMismatchIsReported) {
  // A branch vector off by 1e-7 R_max, within the tolerance: read, and shown by info.
  std::string text = read("contacts.csv");
  text.replace(text.find("0.63641642194092007"), 19, "0.63641652194092007");
  write("contacts.csv", text);
  const CommandResult r = run_info(quoted(dir_) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_NEAR(j.at("geometry_max_branch_mismatch").get<double>(), 1e-7, 1e-9);
  EXPECT_GT(j.at("geometry_worst_over_tolerance").get<double>(), 0.05);
  const CommandResult text_run = run_info(quoted(dir_));
  EXPECT_NE(value_of(text_run.output, "geometry mismatch: l / n / gap").find("contact 1)"), std::string::npos)
      << text_run.output;
}

TEST_F(BrokenCopy, FileInsteadOfDirectory) {
  const CommandResult r = run_info(quoted(dir_ / "meta.json"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("is a file, not a packing directory"), std::string::npos) << r.output;
}

TEST_F(BrokenCopy, IsostaticCountShownAtMuZero) {
  std::string meta = read("meta.json");
  meta.replace(meta.find("0.10000000000000001"), 19, "0");
  write("meta.json", meta);
  const CommandResult r = run_info(quoted(dir_));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(value_of(r.output, "isostatic count N_c - (2N' - 1)"), "-6");  // 81 - 87
}

TEST_F(BrokenCopy, MissingDirectory) {
  fs::remove_all(dir_);
  expect_error("does not exist");
}

TEST_F(BrokenCopy, MissingContacts) {
  fs::remove(dir_ / "contacts.csv");
  expect_error("missing contacts.csv");
}

TEST_F(BrokenCopy, TruncatedParticles) {
  const std::string text = read("particles.csv");
  write("particles.csv", text.substr(0, text.find("\n20,") + 30));  // ends inside line 22
  expect_error("particles.csv line 22: expected 7 fields, found 3 (truncated file?)");
}

TEST_F(BrokenCopy, NaNValue) {
  std::string text = read("contacts.csv");
  text.replace(text.find("0.44218368048285484"), 19, "NaN");
  write("contacts.csv", text);
  expect_error("contacts.csv line 2, column 'fn': 'NaN' is not a finite number");
}

TEST_F(BrokenCopy, WrongColumnName) {
  std::string text = read("particles.csv");
  text.replace(text.find("radius"), 6, "radii");
  write("particles.csv", text);
  expect_error("particles.csv: missing column 'radius'");
}

TEST_F(BrokenCopy, CorruptedMeta) {
  write("meta.json", read("meta.json").substr(0, 20));
  expect_error("meta.json: not valid JSON");
}

TEST_F(BrokenCopy, NoArgumentIsAUsageError) {
  const CommandResult r = run_info("");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("dir"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace unjam
