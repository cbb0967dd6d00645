#pragma once
// Shared by the end-to-end tests of `unjam probe` and `unjam ensemble` (test_cli_probe.cpp,
// test_cli_ensemble.cpp): a fresh writable copy of a fixture packing, and the fixture's
// independent references read by grain pair.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam::testing {

// A copy of fixture `name` in a fresh temporary directory, removed at the end of the test.
class FixtureCopy : public ::testing::Test {
 protected:
  void copy(const std::string& name) {
    root_ = std::filesystem::temp_directory_path() /
            ("unjam-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
             "-" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(root_);
    dir_ = copy_fixture(name, root_);
  }
  void TearDown() override {
    if (!root_.empty()) std::filesystem::remove_all(root_);
  }
  // The path quoted for the shell.
  static std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

  std::filesystem::path root_, dir_;
};

inline nlohmann::json read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << "cannot read " << path;
  nlohmann::json j;
  if (in) in >> j;
  return j;
}

// The fixture's bounds-reference.csv (HiGHS): (a, b) -> (fn_min, fn_max), force units.
inline std::map<std::pair<int, int>, std::pair<double, double>> reference_bounds(const std::string& fixture) {
  const CsvTable t = CsvTable::read(std::filesystem::path(UNJAM_FIXTURES_DIR) / fixture / "bounds-reference.csv");
  std::map<std::pair<int, int>, std::pair<double, double>> out;
  const std::size_t a = t.column("a"), b = t.column("b"), lo = t.column("fn_min"), hi = t.column("fn_max");
  for (std::size_t r = 0; r < t.rows(); ++r)
    out[{static_cast<int>(t.integer(r, a)), static_cast<int>(t.integer(r, b))}] = {t.number(r, lo), t.number(r, hi)};
  return out;
}

// The number printed after `label` in a tool's output, e.g. "F_crit / F0 1.234567".
inline double printed_value(const std::string& output, const std::string& label) {
  const std::size_t at = output.find(label);
  EXPECT_NE(at, std::string::npos) << "no '" << label << "' in\n" << output;
  if (at == std::string::npos) return 0.0;
  std::istringstream in(output.substr(at + label.size()));
  double v = 0.0;
  in >> v;
  return v;
}

}  // namespace unjam::testing
