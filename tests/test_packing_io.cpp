#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_run.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/csv_table.hpp"
#include "unjam/packing/geometry_check.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam {
namespace {

namespace fs = std::filesystem;

const fs::path kFixtures = UNJAM_FIXTURES_DIR;

// A fresh, empty directory under the system temp dir, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info->name();  // "Test/Param" for parametrized tests
    std::replace(name.begin(), name.end(), '/', '_');
    path_ = fs::temp_directory_path() / ("unjam-io-" + name + "-" + std::to_string(std::random_device{}()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

using testing::copy_fixture;

void write_text(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// Replaces the first occurrence of `from` in a file by `to`.
void edit_file(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = read_file(path);
  const auto pos = text.find(from);
  ASSERT_NE(pos, std::string::npos) << from;
  text.replace(pos, from.size(), to);
  write_text(path, text);
}

// Expects read_packing(dir) to throw unjam::Error whose message contains every phrase.
void expect_read_error(const fs::path& dir, std::initializer_list<std::string> phrases) {
  try {
    read_packing(dir);
    ADD_FAILURE() << "read_packing(" << dir << ") did not throw";
  } catch (const Error& e) {
    for (const std::string& phrase : phrases)
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos)
          << "message: " << e.what() << "\nexpected phrase: " << phrase;
  }
}

// Two disks touching along a diagonal, with awkward doubles everywhere.
Packing awkward_packing() {
  Packing p;
  p.cell = {10.0 / 3.0, 0.1 * 37.0};
  p.particles.resize(2);
  p.particles.x = {0.1, 1.0 / 3.0 + 1.0};
  p.particles.y = {1e-300, 2.0 / 3.0};
  p.particles.radius = {0.5 + 1e-16, std::nextafter(1.0, 0.0)};
  p.particles.vx = {-0.0, 1e-310};
  p.particles.vy = {-1e300, 5e-324};
  p.particles.omega = {std::numeric_limits<double>::max(), -std::numeric_limits<double>::min()};
  Contact c;
  c.a = 0;
  c.b = 1;
  c.l = {1.0 / 3.0 + 0.9, 2.0 / 3.0 - 1e-300};
  c.n = c.l.normalized();
  p.particles.radius[1] = c.l.norm() - p.particles.radius[0];  // touching: |l| = R_a + R_b
  c.gap = -0.0;
  c.fn = 1.0 / 7.0;
  c.ft = -0.0;
  p.contacts = {c};
  p.meta.contact.P_ext = 0.3;
  p.meta.contact.mu = 0.1;
  p.meta.seed = 18446744073709551615ULL;
  p.meta.settings = {{"dt", 0.01}, {"sweeps", 200}};
  p.meta.command = "unjam pack --N 2";
  p.state = {123.456, 98765, -1.0 / 3.0, true};
  return p;
}

bool same_bits(double a, double b) { return std::signbit(a) == std::signbit(b) && (a == b || (a != a && b != b)); }

TEST(PackingIo, RoundTripIsBitExact) {
  TempDir tmp;
  const Packing p = awkward_packing();
  write_packing(tmp.path() / "pk", p);
  const Packing q = read_packing(tmp.path() / "pk");

  EXPECT_EQ(q.cell.Lx, p.cell.Lx);
  EXPECT_EQ(q.cell.Ly, p.cell.Ly);
  ASSERT_EQ(q.size(), 2u);
  const auto same = [](const std::vector<double>& u, const std::vector<double>& v) {
    ASSERT_EQ(u.size(), v.size());
    for (std::size_t i = 0; i < u.size(); ++i) EXPECT_TRUE(same_bits(u[i], v[i])) << u[i] << " vs " << v[i];
  };
  same(q.particles.x, p.particles.x);
  same(q.particles.y, p.particles.y);
  same(q.particles.radius, p.particles.radius);
  same(q.particles.vx, p.particles.vx);
  same(q.particles.vy, p.particles.vy);
  same(q.particles.omega, p.particles.omega);
  ASSERT_EQ(q.contacts.size(), 1u);
  const Contact &c = q.contacts[0], &d = p.contacts[0];
  EXPECT_EQ(c.a, d.a);
  EXPECT_EQ(c.b, d.b);
  EXPECT_TRUE(c.n == d.n);
  EXPECT_TRUE(c.l == d.l);
  EXPECT_TRUE(same_bits(c.gap, d.gap));
  EXPECT_TRUE(same_bits(c.fn, d.fn));
  EXPECT_TRUE(same_bits(c.ft, d.ft));
  EXPECT_EQ(q.meta.contact.P_ext, p.meta.contact.P_ext);
  EXPECT_EQ(q.meta.contact.mu, p.meta.contact.mu);
  EXPECT_EQ(q.meta.seed, p.meta.seed);
  EXPECT_EQ(q.meta.settings, p.meta.settings);
  EXPECT_EQ(q.meta.command, p.meta.command);
  EXPECT_FALSE(q.meta.program_version.empty());
  EXPECT_EQ(q.state.time, p.state.time);
  EXPECT_EQ(q.state.step, p.state.step);
  EXPECT_EQ(q.state.lambda, p.state.lambda);
  EXPECT_EQ(q.state.is_static, p.state.is_static);
}

TEST(PackingIo, MetaRecordsVersionCountCellAndForceUnit) {
  TempDir tmp;
  Packing p = awkward_packing();
  p.cell = {5.0, 5.0};
  write_packing(tmp.path(), p);
  const auto meta = nlohmann::json::parse(read_file(tmp.path() / "meta.json"));
  EXPECT_EQ(meta.at("format_version"), kPackingFormatVersion);
  EXPECT_EQ(meta.at("N"), 2);
  EXPECT_EQ(meta.at("L"), 5.0);  // square cell
  EXPECT_EQ(meta.at("Lx"), 5.0);
  EXPECT_EQ(meta.at("F0").get<double>(), p.force_unit());
  EXPECT_TRUE(meta.at("checksums").contains("particles.csv"));
  EXPECT_TRUE(meta.at("checksums").contains("contacts.csv"));
  EXPECT_EQ(read_file(tmp.path() / "particles.csv").substr(0, 27), "id,x,y,radius,vx,vy,omega\n0");
  EXPECT_EQ(read_file(tmp.path() / "contacts.csv").substr(0, 26), "a,b,nx,ny,lx,ly,gap,fn,ft\n");
}

TEST(PackingIo, WriteKeepsOtherFilesAndLeavesNoTemporaries) {
  TempDir tmp;
  write_text(tmp.path() / "probes.csv", "contact,F_crit\n0,1.5\n");
  write_packing(tmp.path(), awkward_packing());
  write_packing(tmp.path(), awkward_packing());  // overwrite
  EXPECT_EQ(read_file(tmp.path() / "probes.csv"), "contact,F_crit\n0,1.5\n");
  for (const auto& e : fs::directory_iterator(tmp.path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  EXPECT_NO_THROW(read_packing(tmp.path()));
}

TEST(PackingIo, FixtureP50Loads) {
  const Packing p = read_packing(kFixtures / "p50-mu0.1");
  EXPECT_EQ(p.size(), 50u);
  EXPECT_EQ(p.contacts.size(), 82u);
  EXPECT_DOUBLE_EQ(p.cell.Lx, 10.575537479681529);
  EXPECT_EQ(p.cell.Lx, p.cell.Ly);
  EXPECT_DOUBLE_EQ(p.meta.contact.mu, 0.1);
  EXPECT_EQ(p.meta.seed, 3u);
  EXPECT_NEAR(p.force_unit(), 1.5121258295097544, 1e-12);
  EXPECT_DOUBLE_EQ(p.contacts[0].gap, -7.0503746241179499e-07);  // given in the file
}

TEST(PackingIo, FixtureLattice16LoadsWithDefaultsAndComputedGaps) {
  const Packing p = read_packing(kFixtures / "lattice16");
  EXPECT_EQ(p.size(), 16u);
  EXPECT_EQ(p.contacts.size(), 48u);
  EXPECT_EQ(p.cell.Lx, 8.0);
  EXPECT_DOUBLE_EQ(p.cell.Ly, 6.928203230275509);
  EXPECT_EQ(p.particles.vx, std::vector<double>(16, 0.0));  // absent columns
  EXPECT_EQ(p.particles.omega, std::vector<double>(16, 0.0));
  for (const Contact& c : p.contacts) EXPECT_NEAR(c.gap, 0.0, 1e-12);  // no gap column
  EXPECT_EQ(p.meta.seed, 0u);
  EXPECT_TRUE(p.meta.program_version.empty());
}

TEST(PackingIo, ColumnsInAnyOrderAndUnknownColumnsIgnored) {
  TempDir tmp;
  const fs::path dir = copy_fixture("lattice16", tmp.path());
  std::string text = "radius,extra,y,x,id\n";
  const Packing ref = read_packing(dir);
  for (int i = 15; i >= 0; --i)
    text += "1.0,7," + std::to_string(ref.particles.y[i]) + "," + std::to_string(ref.particles.x[i]) + "," +
            std::to_string(i) + "\n";
  write_text(dir / "particles.csv", text);
  const Packing p = read_packing(dir);
  ASSERT_EQ(p.size(), 16u);
  for (std::size_t i = 0; i < 16; ++i) {
    EXPECT_NEAR(p.particles.x[i], ref.particles.x[i], 1e-6);
    EXPECT_NEAR(p.particles.y[i], ref.particles.y[i], 1e-6);
  }
}

struct BrokenCase {
  const char* name;
  std::function<void(const fs::path&)> damage;  // applied to a copy of p50-mu0.1
  std::vector<std::string> phrases;
};

void PrintTo(const BrokenCase& c, std::ostream* os) { *os << c.name; }

class PackingIoRejects : public ::testing::TestWithParam<BrokenCase> {};

TEST_P(PackingIoRejects, ReportsTheProblem) {
  TempDir tmp;
  const fs::path dir = copy_fixture("p50-mu0.1", tmp.path());
  GetParam().damage(dir);
  try {
    read_packing(dir);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    for (const std::string& phrase : GetParam().phrases)
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos)
          << "message: " << e.what() << "\nexpected phrase: " << phrase;
  }
}

const fs::path kP = "particles.csv", kC = "contacts.csv", kM = "meta.json";

INSTANTIATE_TEST_SUITE_P(
    Broken, PackingIoRejects,
    ::testing::Values(
        BrokenCase{"MissingDirectory", [](const fs::path& d) { fs::remove_all(d); }, {"does not exist"}},
        BrokenCase{"MissingContacts", [](const fs::path& d) { fs::remove(d / kC); }, {"missing contacts.csv"}},
        BrokenCase{"MissingMeta", [](const fs::path& d) { fs::remove(d / kM); }, {"missing meta.json"}},
        BrokenCase{"MetaNotJson", [](const fs::path& d) { write_text(d / kM, "{\"L\": 10,"); },
                   {"meta.json", "not valid JSON"}},
        BrokenCase{"MetaWithoutL", [](const fs::path& d) { write_text(d / kM, "{\"P_ext\": 1, \"mu\": 0.1}"); },
                   {"meta.json", "cell size"}},
        BrokenCase{"MetaWithoutLy",
                   [](const fs::path& d) { write_text(d / kM, "{\"Lx\": 10.6, \"P_ext\": 1, \"mu\": 0.1}"); },
                   {"meta.json", "missing 'Ly'"}},
        BrokenCase{"MetaWithoutPext", [](const fs::path& d) { write_text(d / kM, "{\"L\": 10.6, \"mu\": 0.1}"); },
                   {"meta.json", "missing 'P_ext'"}},
        BrokenCase{"MetaWithoutMu", [](const fs::path& d) { write_text(d / kM, "{\"L\": 10.6, \"P_ext\": 1}"); },
                   {"meta.json", "missing 'mu'"}},
        BrokenCase{"NegativeL", [](const fs::path& d) { edit_file(d / kM, "\"L\": 10.5", "\"L\": -10.5"); },
                   {"cell size must be positive"}},
        BrokenCase{"ZeroPext", [](const fs::path& d) { edit_file(d / kM, "\"P_ext\": 1", "\"P_ext\": 0"); },
                   {"'P_ext' must be positive"}},
        BrokenCase{"NegativeMu", [](const fs::path& d) { edit_file(d / kM, "\"mu\": 0.1", "\"mu\": -0.1"); },
                   {"'mu' must not be negative"}},
        BrokenCase{"StringMu", [](const fs::path& d) { edit_file(d / kM, "\"mu\": 0.10000000000000001", "\"mu\": \"x\""); },
                   {"'mu' must be a number"}},
        BrokenCase{"NewerFormat",
                   [](const fs::path& d) { edit_file(d / kM, "{", "{\"format_version\": 99, "); },
                   {"format_version 99 is newer"}},
        BrokenCase{"WrongN", [](const fs::path& d) { edit_file(d / kM, "\"N\": 50", "\"N\": 51"); },
                   {"N = 51", "50 rows"}},
        // An integer field holding a float beyond int64's range: was cast (undefined behaviour).
        BrokenCase{"HugeFloatN", [](const fs::path& d) { edit_file(d / kM, "\"N\": 50", "\"N\": 1e300"); },
                   {"meta.json: 'N' must be an integer in [", "found 1e+300"}},
        BrokenCase{"MissingColumn", [](const fs::path& d) { edit_file(d / kC, ",fn,", ",f_n,"); },
                   {"contacts.csv: missing column 'fn'"}},
        BrokenCase{"MissingRadius", [](const fs::path& d) { edit_file(d / kP, "radius", "r"); },
                   {"particles.csv: missing column 'radius'"}},
        BrokenCase{"TruncatedRow",
                   [](const fs::path& d) {
                     const std::string t = read_file(d / kP);
                     write_text(d / kP, t.substr(0, t.find("\n11,") + 31));  // inside the row of id 11 (line 13)
                   },
                   {"particles.csv line 13: expected 7 fields, found", "(truncated file?)"}},
        BrokenCase{"NonNumeric", [](const fs::path& d) { edit_file(d / kP, "\n4,", "\n4,abc"); },
                   {"particles.csv line 6", "column 'x'", "'abc", "not a finite number"}},
        BrokenCase{"NaN", [](const fs::path& d) { edit_file(d / kC, "0.44218368048285484", "nan"); },
                   {"contacts.csv line 2", "column 'fn'", "'nan' is not a finite number"}},
        BrokenCase{"Infinite", [](const fs::path& d) { edit_file(d / kC, "0.44218368048285484", "-inf"); },
                   {"contacts.csv line 2", "not a finite number"}},
        BrokenCase{"ZeroRadius", [](const fs::path& d) { edit_file(d / kP, "0.77938299481158957", "0"); },
                   {"particles.csv line 2", "radius must be positive"}},
        BrokenCase{"IdOutOfRange", [](const fs::path& d) { edit_file(d / kP, "\n4,", "\n50,"); },
                   {"particles.csv line 6", "id 50 out of range"}},
        BrokenCase{"DuplicateId", [](const fs::path& d) { edit_file(d / kP, "\n4,", "\n3,"); },
                   {"particles.csv line 6", "duplicate id 3"}},
        BrokenCase{"NonIntegerId", [](const fs::path& d) { edit_file(d / kP, "\n4,", "\n4.5,"); },
                   {"column 'id'", "not an integer"}},
        BrokenCase{"ContactIndexOutOfRange", [](const fs::path& d) { edit_file(d / kC, "\n0,7,", "\n0,70,"); },
                   {"contacts.csv line 3", "grain index 70 out of range"}},
        BrokenCase{"NegativeContactIndex", [](const fs::path& d) { edit_file(d / kC, "\n0,7,", "\n-1,7,"); },
                   {"contacts.csv line 3", "grain index -1 out of range"}},
        BrokenCase{"SelfContact", [](const fs::path& d) { edit_file(d / kC, "\n0,7,", "\n7,7,"); },
                   {"contacts.csv line 3", "with itself"}},
        BrokenCase{"NormalNotUnit",
                   [](const fs::path& d) { edit_file(d / kC, "0.42692162722827404", "0.4369216"); },
                   {"contacts.csv line 3", "not a unit vector"}},
        BrokenCase{"EmptyContacts", [](const fs::path& d) { write_text(d / kC, ""); },
                   {"contacts.csv: empty file"}},
        BrokenCase{"EmptyParticles", [](const fs::path& d) { write_text(d / kP, "\n\n"); },
                   {"particles.csv: empty file"}},
        BrokenCase{"HeaderOnlyParticles",
                   [](const fs::path& d) {
                     write_text(d / kM, "{\"L\": 10, \"P_ext\": 1, \"mu\": 0}");
                     write_text(d / kP, "id,x,y,radius\n");
                   },
                   {"particles.csv: no particles"}},
        BrokenCase{"MissingRow",
                   [](const fs::path& d) {
                     const std::string t = read_file(d / kP);
                     const auto row = t.find("\n11,");
                     write_text(d / kP, t.substr(0, row) + t.substr(t.find('\n', row + 1)));
                   },
                   {"meta.json: N = 50 but particles.csv has 49 rows"}},
        // Geometrically impossible packings (packing/geometry_check.hpp).
        BrokenCase{"CellTooSmall", [](const fs::path& d) { edit_file(d / kM, "\"L\": 10.575537479681529", "\"L\": 3"); },
                   {"meta.json", "the grains' area is", "too small for its grains"}},
        BrokenCase{"HugeRadius", [](const fs::path& d) { edit_file(d / kP, "0.77938299481158957", "1e6"); },
                   {"too small for its grains or a radius is wrong"}},
        BrokenCase{"LxDisagreesWithL",
                   [](const fs::path& d) { edit_file(d / kM, "{", "{\"Lx\": 11, \"Ly\": 10.575537479681529, "); },
                   {"'L' = 10.575537479681529 disagrees with 'Lx' = 11"}},
        BrokenCase{"SwappedContact", [](const fs::path& d) { edit_file(d / kC, "\n0,7,", "\n7,0,"); },
                   {"contacts.csv line 3", "contact 1 (grains 7-0)", "branch vector", "but the positions give"}},
        BrokenCase{"DuplicateContact",
                   [](const fs::path& d) {
                     const std::string t = read_file(d / kC);
                     const auto row = t.find("\n0,7,");
                     write_text(d / kC, t + t.substr(row + 1, t.find('\n', row + 1) - row));
                   },
                   {"contacts.csv line 84", "grains 0 and 7 are listed twice (also on line 3)"}},
        BrokenCase{"ReversedDuplicate",
                   [](const fs::path& d) {
                     const std::string t = read_file(d / kC);
                     write_text(d / kC, t + "7,0,-0.42692162722827404,0.90428862881535921,-0.63641642194092007,"
                                            "1.3480322777014315,-1.4088336084405739e-06,1,0\n");
                   },
                   {"grains 7 and 0 are listed twice (also on line 3)"}},
        BrokenCase{"NotNeighbours", [](const fs::path& d) { edit_file(d / kC, "\n0,7,", "\n0,30,"); },
                   {"contacts.csv line 3", "(grains 0-30) does not fit the positions and the cell"}},
        BrokenCase{"BranchVectorOff",
                   [](const fs::path& d) { edit_file(d / kC, "0.63641642194092007", "0.73641642194092007"); },
                   {"contacts.csv line 3", "contact 1 (grains 0-7)", "is not l / |l| = (0.47941703130800717"}},
        BrokenCase{"GapOff", [](const fs::path& d) { edit_file(d / kC, "-1.4088336084405739e-06", "-0.01"); },
                   {"contacts.csv line 3", "gap -0.01 is not |l| - R_a - R_b"}}),
    [](const ::testing::TestParamInfo<BrokenCase>& info) { return std::string(info.param.name); });

TEST(PackingIo, ChecksumsDetectAModifiedTable) {
  TempDir tmp;
  write_packing(tmp.path(), awkward_packing());
  std::string text = read_file(tmp.path() / "contacts.csv");
  text.back() = ' ';  // a single changed byte that still parses
  text += "\n";
  write_text(tmp.path() / "contacts.csv", text);
  expect_read_error(tmp.path(), {"contacts.csv does not match meta.json",
                                 "the packing was modified or its write was interrupted"});
}

TEST(PackingIo, ChecksumsDetectAnInterruptedWrite) {
  // New tables written, the old meta.json kept: as if the write stopped before meta.json.
  TempDir tmp;
  Packing p = awkward_packing();
  write_packing(tmp.path() / "old", p);
  p.particles.x[0] = 0.2;
  write_packing(tmp.path() / "new", p);
  fs::copy_file(tmp.path() / "old" / "meta.json", tmp.path() / "new" / "meta.json",
                fs::copy_options::overwrite_existing);
  expect_read_error(tmp.path() / "new", {"particles.csv does not match meta.json"});
}

TEST(PackingIo, ChecksumsOfAnotherFormAreRefused) {
  // "checksums": "x" used to switch the integrity check off.
  TempDir tmp;
  write_packing(tmp.path(), awkward_packing());
  for (const char* bad : {R"("x")", R"({"particles.csv": "x"})", R"({})", "null"}) {
    auto meta = nlohmann::json::parse(read_file(tmp.path() / "meta.json"));
    meta["checksums"] = nlohmann::json::parse(bad);
    write_text(tmp.path() / "meta.json", meta.dump());
    expect_read_error(tmp.path(), {"meta.json: 'checksums' must give", "delete the whole 'checksums' entry"});
  }
}

// The states a write_packing stopped by SIGKILL can leave: the new version's files as *.new,
// some of them already renamed into place. Each must read as one complete version.
TEST(PackingIo, AWriteStoppedAtAnyPointLeavesOneCompleteVersion) {
  TempDir tmp;
  const Packing old_p = awkward_packing();
  Packing new_p = old_p;
  new_p.state.step += 1;
  new_p.particles.vx[0] = 0.25;
  write_packing(tmp.path() / "new", new_p);
  const std::vector<std::string> files = {"particles.csv", "contacts.csv", "meta.json"};
  // stage: files of the new version written as *.new (0..3), then renamed into place (0..3).
  for (int written = 0; written <= 3; ++written) {
    for (int renamed = 0; renamed <= (written == 3 ? 3 : 0); ++renamed) {
      SCOPED_TRACE("written " + std::to_string(written) + ", renamed " + std::to_string(renamed));
      const fs::path dir = tmp.path() / ("stop-" + std::to_string(written) + "-" + std::to_string(renamed));
      write_packing(dir, old_p);
      for (int i = 0; i < written; ++i)
        fs::copy_file(tmp.path() / "new" / files[i], dir / (files[i] + (i < renamed ? "" : ".new")),
                      fs::copy_options::overwrite_existing);
      write_text(dir / "contacts.csv.tmp.999999999", "a,b\n");  // a temporary of a killed process
      const bool is_new = written == 3;
      const Packing q = read_packing(dir);
      EXPECT_EQ(q.state.step, is_new ? new_p.state.step : old_p.state.step);
      EXPECT_EQ(q.particles.vx[0], is_new ? new_p.particles.vx[0] : old_p.particles.vx[0]);
      // The next write completes or discards the stopped one and removes the temporary.
      write_packing(dir, new_p);
      for (const auto& e : fs::directory_iterator(dir))
        EXPECT_TRUE(std::count(files.begin(), files.end(), e.path().filename().string())) << e.path();
      EXPECT_EQ(read_packing(dir).state.step, new_p.state.step);
    }
  }
}

// Seeded random damage of the fixture's files, byte by byte: the reader gives a clear error
// (unjam::Error) or a packing that passes the geometric check, never another exception,
// a crash or a hang.
TEST(PackingIo, RandomDamageGivesAnErrorOrAConsistentPacking) {
  TempDir tmp;
  const fs::path dir = copy_fixture("p50-mu0.1", tmp.path());
  const std::string files[] = {"particles.csv", "contacts.csv", "meta.json"};
  std::string original[3];
  for (int f = 0; f < 3; ++f) original[f] = read_file(dir / files[f]);
  std::mt19937_64 rng(16);
  int accepted = 0, refused = 0;
  const char alphabet[] = "0123456789.,-+eE\n\r {}\":naif\xEF\xBB\xBF";
  for (int trial = 0; trial < 600; ++trial) {
    const int f = trial % 3;
    std::string text = original[f];
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const std::size_t at = rng() % text.size();
      switch (rng() % 5) {
        case 0: text[at] = alphabet[rng() % (sizeof alphabet - 1)]; break;  // a plausible byte
        case 1: text[at] = static_cast<char>(rng() % 256); break;           // any byte
        case 2: text.erase(at, 1 + rng() % 8); break;
        case 3: text.insert(at, text.substr(rng() % text.size(), 1 + rng() % 40)); break;  // repeat a piece
        default: text.resize(at); break;                                     // truncated
      }
    }
    write_text(dir / files[f], text);
    SCOPED_TRACE("trial " + std::to_string(trial) + ", " + files[f]);
    try {
      const Packing p = read_packing(dir);
      ++accepted;
      EXPECT_TRUE(check_geometry(p).ok());
      EXPECT_LE(p.packing_fraction(), 1.0);
      for (std::size_t i = 0; i < p.size(); ++i)
        EXPECT_TRUE(std::isfinite(p.particles.x[i]) && p.particles.radius[i] > 0.0);
    } catch (const Error& e) {
      ++refused;
      EXPECT_GT(std::string(e.what()).size(), 10u);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not an unjam::Error: " << e.what();
    }
    write_text(dir / files[f], original[f]);
  }
  EXPECT_GT(refused, 300);
  EXPECT_GT(accepted, 0);  // damage in a force, a velocity, a trailing digit is not detectable
}

TEST(PackingIo, LargePackingLoadsFast) {
  TempDir tmp;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Packing p;
  p.cell = {150.0, 150.0};  // phi 0.65
  p.particles.resize(8000);
  for (std::size_t i = 0; i < 8000; ++i) {
    p.particles.x[i] = 150.0 * u(rng);
    p.particles.y[i] = 150.0 * u(rng);
    p.particles.radius[i] = 0.5 + 0.5 * u(rng);
    p.particles.vx[i] = u(rng) - 0.5;
  }
  // 20000 contacts: grain b placed touching grain a (b > a), with the geometry of its row.
  for (int k = 0; k < 20000; ++k) {
    Contact c;
    c.a = k % 4000;
    c.b = 4000 + (k * 7 + 1) % 4000;
    const double phi = 2.0 * M_PI * u(rng);
    c.n = {std::cos(phi), std::sin(phi)};
    c.l = c.n * (p.particles.radius[c.a] + p.particles.radius[c.b]);
    p.particles.x[c.b] = p.particles.x[c.a] + c.l.x();
    p.particles.y[c.b] = p.particles.y[c.a] + c.l.y();
    c.fn = u(rng);
    c.ft = 0.1 * (u(rng) - 0.5);
    p.contacts.push_back(c);
  }
  // Each row from the final positions (a grain b moved by a later row).
  for (Contact& c : p.contacts) {
    c.l = p.cell.min_image(p.particles.position(c.b) - p.particles.position(c.a));
    c.n = c.l.normalized();
    c.gap = c.l.norm() - p.particles.radius[c.a] - p.particles.radius[c.b];
  }
  std::sort(p.contacts.begin(), p.contacts.end(), [](const Contact& x, const Contact& y) { return std::pair(x.a, x.b) < std::pair(y.a, y.b); });
  p.contacts.erase(std::unique(p.contacts.begin(), p.contacts.end(), [](const Contact& x, const Contact& y) { return x.a == y.a && x.b == y.b; }), p.contacts.end());
  p.contacts.erase(std::remove_if(p.contacts.begin(), p.contacts.end(), [&](const Contact& c) { return c.gap > 0.5; }), p.contacts.end());
  write_packing(tmp.path(), p);
  const auto t0 = std::chrono::steady_clock::now();
  const Packing q = read_packing(tmp.path());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(q.size(), 8000u);
  EXPECT_GT(q.contacts.size(), 2000u);
  EXPECT_EQ(q.contacts.size(), p.contacts.size());
  EXPECT_EQ(q.contacts.back().fn, p.contacts.back().fn);
  EXPECT_LT(seconds, 1.0);
}

TEST(CsvTable, LooksUpColumnsByNameAndParsesTypedValues) {
  const CsvTable t = CsvTable::parse(" b , a\r\n\n 2.5, +7 \r\n-1e-3,3.0\n", "t.csv");
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.column("a"), 1u);
  EXPECT_FALSE(t.find_column("c"));
  EXPECT_EQ(t.number(0, t.column("b")), 2.5);
  EXPECT_EQ(t.integer(0, t.column("a")), 7);
  EXPECT_EQ(t.integer(1, t.column("a")), 3);
  EXPECT_EQ(t.number(1, 0), -1e-3);
  EXPECT_EQ(t.line(1), 4u);
  EXPECT_THROW(t.column("c"), Error);
  EXPECT_THROW(CsvTable::parse("a,a\n1,2\n", "dup.csv"), Error);
}

TEST(CsvTable, ByteOrderMarkAndCarriageReturnLineEndsAreRead) {
  // A spreadsheet's UTF-8 BOM used to give "missing column 'a'", CR-only line ends
  // "column '0' appears twice".
  const CsvTable bom = CsvTable::parse("\xEF\xBB\xBF" "a,b\n1,2\n", "bom.csv");
  EXPECT_EQ(bom.column("a"), 0u);
  EXPECT_EQ(bom.integer(0, 0), 1);
  const CsvTable cr = CsvTable::parse("a,b\r1,2\r3,4\r", "cr.csv");
  ASSERT_EQ(cr.rows(), 2u);
  EXPECT_EQ(cr.integer(1, cr.column("b")), 4);
}

TEST(CsvTable, WriterRowsRoundTrip) {
  CsvWriter w({"i", "v", "s"});
  w.cell(-3).cell(0.1).cell("x").end_row();
  w.cell(std::int64_t{1} << 60).cell(-0.0).cell("y").end_row();
  EXPECT_EQ(w.str(), "i,v,s\n-3,0.1,x\n1152921504606846976,-0,y\n");
  w.cell(1);
  EXPECT_THROW(w.end_row(), std::logic_error);
}

TEST(PackingIo, ContactModelIsTypedAndKeepsItsJsonKeys) {
  // The typed contact model (PackingMeta::contact) is read from meta.json's mu, P_ext,
  // settings.dynamics.M_lambda and settings.static.touch_gap and written back to the same
  // keys: a packing read and written again keeps its settings, old files read.
  TempDir tmp;
  const fs::path dir = copy_fixture("p50-mu1", tmp.path());
  const auto meta0 = nlohmann::json::parse(read_file(dir / "meta.json"));
  Packing p = read_packing(dir);
  EXPECT_EQ(p.meta.contact.mu, meta0["mu"].get<double>());
  EXPECT_EQ(p.meta.contact.P_ext, meta0["P_ext"].get<double>());
  EXPECT_EQ(p.meta.contact.M_lambda, meta0["settings"]["dynamics"]["M_lambda"].get<double>());
  EXPECT_EQ(p.meta.contact.touch_gap, meta0["settings"]["static"]["touch_gap"].get<double>());
  const auto settings_of = [](const fs::path& d) {
    return nlohmann::json::parse(read_file(d / "meta.json"))["settings"];
  };
  write_packing(tmp.path() / "same", p);
  EXPECT_EQ(settings_of(tmp.path() / "same").dump(), meta0["settings"].dump());

  // A changed model is written to the same keys.
  p.meta.contact.M_lambda = 0.5;
  p.meta.contact.touch_gap = 3e-6;
  write_packing(tmp.path() / "changed", p);
  const auto changed = settings_of(tmp.path() / "changed");
  EXPECT_EQ(changed["dynamics"]["M_lambda"].get<double>(), 0.5);
  EXPECT_EQ(changed["static"]["touch_gap"].get<double>(), 3e-6);
  const Packing q = read_packing(tmp.path() / "changed");
  EXPECT_EQ(q.meta.contact.M_lambda, 0.5);
  EXPECT_EQ(q.meta.contact.touch_gap, 3e-6);

  // Settings without the model's keys (a hand-made packing) read as the defaults and are
  // written as they are.
  Packing bare = p;
  bare.meta.settings = {{"dt", 0.01}};
  bare.meta.contact.M_lambda = ContactModel{}.M_lambda;
  bare.meta.contact.touch_gap = ContactModel{}.touch_gap;
  write_packing(tmp.path() / "bare", bare);
  EXPECT_EQ(settings_of(tmp.path() / "bare"), bare.meta.settings);
  const Packing b = read_packing(tmp.path() / "bare");
  EXPECT_EQ(b.meta.contact.M_lambda, 100.0);
  EXPECT_EQ(b.meta.contact.touch_gap, 1e-6);

  // A model entry that is not a number is refused when the packing is read.
  std::string text = read_file(dir / "meta.json");
  const std::string key = "\"M_lambda\": 100.0";
  ASSERT_NE(text.find(key), std::string::npos);
  text.replace(text.find(key), key.size(), "\"M_lambda\": \"heavy\"");
  write_text(dir / "meta.json", text);
  try {
    (void)read_packing(dir);
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("M_lambda must be a number"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace unjam
