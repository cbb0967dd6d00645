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

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/csv_table.hpp"
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

// A writable copy of a fixture packing.
fs::path copy_fixture(const std::string& name, const fs::path& to) {
  const fs::path dst = to / name;
  fs::copy(kFixtures / name, dst, fs::copy_options::recursive);
  for (const auto& e : fs::directory_iterator(dst))
    fs::permissions(e.path(), fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::add);
  return dst;
}

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
  c.gap = -0.0;
  c.fn = 1.0 / 7.0;
  c.ft = -0.0;
  p.contacts = {c};
  p.meta.P_ext = 0.3;
  p.meta.mu = 0.1;
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
  EXPECT_EQ(q.meta.P_ext, p.meta.P_ext);
  EXPECT_EQ(q.meta.mu, p.meta.mu);
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
  EXPECT_DOUBLE_EQ(p.meta.mu, 0.1);
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
                   {"meta.json: N = 50 but particles.csv has 49 rows"}}),
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

TEST(PackingIo, LargePackingLoadsFast) {
  TempDir tmp;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Packing p;
  p.cell = {100.0, 100.0};
  p.particles.resize(8000);
  for (std::size_t i = 0; i < 8000; ++i) {
    p.particles.x[i] = 100.0 * u(rng);
    p.particles.y[i] = 100.0 * u(rng);
    p.particles.radius[i] = 0.5 + 0.5 * u(rng);
    p.particles.vx[i] = u(rng) - 0.5;
  }
  for (int k = 0; k < 20000; ++k) {
    Contact c;
    c.a = k % 8000;
    c.b = (k * 7 + 1) % 8000;
    if (c.a == c.b) c.b = (c.b + 1) % 8000;
    c.l = {u(rng), u(rng)};
    c.n = c.l.normalized();
    c.gap = -1e-6 * u(rng);
    c.fn = u(rng);
    c.ft = 0.1 * (u(rng) - 0.5);
    p.contacts.push_back(c);
  }
  write_packing(tmp.path(), p);
  const auto t0 = std::chrono::steady_clock::now();
  const Packing q = read_packing(tmp.path());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(q.size(), 8000u);
  EXPECT_EQ(q.contacts.size(), 20000u);
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

TEST(CsvTable, WriterRowsRoundTrip) {
  CsvWriter w({"i", "v", "s"});
  w.cell(-3).cell(0.1).cell("x").end_row();
  w.cell(std::int64_t{1} << 60).cell(-0.0).cell("y").end_row();
  EXPECT_EQ(w.str(), "i,v,s\n-3,0.1,x\n1152921504606846976,-0,y\n");
  w.cell(1);
  EXPECT_THROW(w.end_row(), std::logic_error);
}

}  // namespace
}  // namespace unjam
