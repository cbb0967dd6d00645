#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "unjam/analysis/power_law_fit.hpp"
#include "unjam/analysis/response_average.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {
namespace {

Vec2 quadrupole(double x, double y) {
  const double r = std::hypot(x, y);
  return {(x * x - y * y) / (r * r * r), 2.0 * x * y / (r * r * r)};
}

TEST(ResponseAverage, FixedPointSumIsOrderIndependent) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<double> v;
  for (int i = 0; i < 1000; ++i) v.push_back(uni(rng) * std::pow(10.0, 6.0 * uni(rng)));
  FixedPointSum forward, backward, halves_a, halves_b;
  for (double x : v) forward.add(x);
  for (auto it = v.rbegin(); it != v.rend(); ++it) backward.add(*it);
  for (std::size_t i = 0; i < v.size(); ++i) (i % 2 ? halves_a : halves_b).add(v[i]);
  halves_b.add(halves_a);
  EXPECT_EQ(forward, backward);
  EXPECT_EQ(forward, halves_b);
  // Exact for multiples of 2^-56; negative totals survive the (high, low) split.
  FixedPointSum s;
  s.add(-3.25);
  s.add(0.5);
  EXPECT_EQ(s.value(), -2.75);
  EXPECT_EQ(FixedPointSum::from_parts(s.high(), s.low()), s);
  EXPECT_THROW(s.add(std::nan("")), Error);
  EXPECT_THROW(s.add(5e9), Error);
}

TEST(ResponseAverage, GridValidation) {
  ResponseGrid g;
  g.half_width = 2.0;
  g.h = 0.3;  // 2W/h = 13.33: not an integer
  EXPECT_THROW(ResponseAverage{g}, Error);
  g.h = 0.5;
  g.r_min = 2.0;
  g.r_max = 1.0;
  EXPECT_THROW(ResponseAverage{g}, Error);
  const ResponseGrid c = ResponseGrid::for_cell(Cell{30.0, 25.0}, 1.5);
  EXPECT_NO_THROW(c.validate());
  EXPECT_EQ(c.field_side(), 32);  // h = 0.75, W = 16 h = 12 <= L_min / 2 = 12.5
  EXPECT_EQ(c.r_max, 12.5);
  EXPECT_EQ(c.r_edge(c.r_bins), c.r_max);
}

// Two probes whose contact frames are rotated by 90 degrees (n1 = +x, n2 = +y) about the same
// contact point, on the same lattice of grains. In frame k the field is g (Q(x, y) + e_k) with
// Q a quadrupole, e_1 = (1, 0), e_2 = (0, 1): the mean field is Q + (1/2, 1/2), count 2.
TEST(ResponseAverage, TwoProbesRotatedBy90DegreesGiveTheKnownMeanField) {
  const Cell cell{20.0, 20.0};
  const Vec2 r0(19.0, 10.0);  // the lattice crosses x = Lx
  const double g = 1e-9;
  ResponseGrid grid;
  grid.half_width = 3.0;
  grid.h = 1.0;  // bin centres +-0.5, +-1.5, +-2.5: invariant under a 90 degree rotation
  grid.r_min = 0.5;
  grid.r_max = 8.0;
  grid.r_bins = 4;
  ResponseAverage avg(grid);

  std::vector<double> x, y;
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i) {
      const Vec2 r = cell.wrap(r0 + Vec2(-2.5 + i, -2.5 + j));
      x.push_back(r.x());
      y.push_back(r.y());
    }
  const Vec2 e[2] = {Vec2(1.0, 0.0), Vec2(0.0, 1.0)};
  const Vec2 normals[2] = {Vec2(1.0, 0.0), Vec2(0.0, 1.0)};
  for (int k = 0; k < 2; ++k) {
    const ContactFrame frame{r0, normals[k], tangent(normals[k])};
    std::vector<Vec2> u_lab;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Vec2 q = frame.position(cell, Vec2(x[i], y[i]));
      const Vec2 u = g * (quadrupole(q.x(), q.y()) + e[k]);
      u_lab.push_back(u.x() * frame.n + u.y() * frame.t);
    }
    FrameField f;
    to_contact_frame(frame, cell, x, y, u_lab, f);
    avg.add_probe(k, f, g);
  }
  ASSERT_EQ(avg.probes(), 2u);
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 6; ++i) {
      const double X = -2.5 + i, Y = -2.5 + j;
      const Vec2 expected = quadrupole(X, Y) + Vec2(0.5, 0.5);
      EXPECT_EQ(avg.field_count(i, j), 2);
      EXPECT_NEAR(avg.field_mean(i, j).x(), expected.x(), 1e-12);
      EXPECT_NEAR(avg.field_mean(i, j).y(), expected.y(), 1e-12);
    }

  // response_field.csv: x fastest, bin centres, the same numbers.
  const CsvTable t = CsvTable::parse(avg.field_csv(), "response_field.csv");
  ASSERT_EQ(t.rows(), 36u);
  const std::size_t row = 2 * 6 + 4;  // i = 4, j = 2: (1.5, -0.5)
  EXPECT_EQ(t.number(row, t.column("x")), 1.5);
  EXPECT_EQ(t.number(row, t.column("y")), -0.5);
  EXPECT_NEAR(t.number(row, t.column("ux")), quadrupole(1.5, -0.5).x() + 0.5, 1e-12);
  EXPECT_NEAR(t.number(row, t.column("uy")), quadrupole(1.5, -0.5).y() + 0.5, 1e-12);
  EXPECT_EQ(t.integer(row, t.column("count")), 2);
}

TEST(ResponseAverage, FieldBinEdges) {
  ResponseGrid grid;
  grid.half_width = 1.0;
  grid.h = 1.0;
  ResponseAverage avg(grid);
  FrameField f{{-1.0, 1.0, 0.0, -0.25}, {-1.0, 0.0, 1.0, 0.25}, {1.0, 1.0, 1.0, 1.0}, {0.0, 0.0, 0.0, 0.0}};
  avg.add_probe(0, f, 1.0);
  EXPECT_EQ(avg.field_count(0, 0), 1);  // (-1, -1): lower edges are inside
  EXPECT_EQ(avg.field_count(1, 0), 0);
  EXPECT_EQ(avg.field_count(0, 1), 1);  // (-0.25, 0.25)
  EXPECT_EQ(avg.field_count(1, 1), 0);  // (1, 0) and (0, 1): upper edges are outside
  // response_field.csv: an empty bin's mean is NaN, a filled one's a number.
  const CsvTable t = CsvTable::parse(avg.field_csv(), "response_field.csv");
  ASSERT_EQ(t.rows(), 4u);
  EXPECT_EQ(t.number(0, t.column("ux")), 1.0);
  for (const char* col : {"ux", "uy"}) EXPECT_EQ(t.field(1, t.column(col)), "nan") << col;
  EXPECT_EQ(t.integer(1, t.column("count")), 0);
}

// d(r): probe 0 has |u|/g = 1 on four grains at r = 2, probe 1 has 3: d = 2, and the standard
// error over probes is sqrt(2 ((4 - 8)^2 + (12 - 8)^2)) / 8 = 1 (= std(1, 3) / sqrt 2).
TEST(ResponseAverage, ProfileMeanAndStandardError) {
  ResponseGrid grid;
  grid.r_min = 1.0;
  grid.r_max = 100.0;
  grid.r_bins = 2;  // [1, 10), [10, 100)
  ResponseAverage avg(grid);
  const double g = 2e-9;
  for (int p = 0; p < 2; ++p) {
    const double d = p == 0 ? 1.0 : 3.0;
    FrameField f{{2.0, 0.0, -2.0, 0.0, 0.5}, {0.0, 2.0, 0.0, -2.0, 0.0}, {}, {}};
    for (int i = 0; i < 5; ++i) {  // displacement d g in varied directions; grain 4 is below r_min
      f.ux.push_back(d * g * std::cos(1.3 * i));
      f.uy.push_back(d * g * std::sin(1.3 * i));
    }
    avg.add_probe(10 + p, f, g);
  }
  const RadialProfile prof = avg.profile();
  ASSERT_EQ(prof.size(), 2u);
  EXPECT_EQ(prof.r_lo[0], 1.0);
  EXPECT_EQ(prof.r_hi[1], 100.0);
  EXPECT_NEAR(prof.r_mid[0], std::sqrt(10.0), 1e-14);
  EXPECT_NEAR(prof.d_mean[0], 2.0, 1e-14);
  EXPECT_NEAR(prof.d_sem[0], 1.0, 1e-14);
  EXPECT_EQ(prof.count[0], 8);
  EXPECT_EQ(prof.probes[0], 2);
  EXPECT_EQ(prof.count[1], 0);
  EXPECT_EQ(prof.d_mean[1], 0.0);

  const CsvTable t = CsvTable::parse(avg.profile_csv(), "response_profile.csv");
  ASSERT_EQ(t.rows(), 2u);
  for (const char* col : {"r_lo", "r_hi", "r_mid", "d_mean", "d_sem", "count", "probes"}) EXPECT_NO_THROW(t.column(col));
  EXPECT_EQ(t.number(0, t.column("d_mean")), prof.d_mean[0]);
  EXPECT_EQ(t.integer(0, t.column("probes")), 2);
  // The empty bin [10, 100): no d, written NaN (the in-memory profile keeps 0, count 0).
  EXPECT_EQ(t.field(1, t.column("d_mean")), "nan");
  EXPECT_EQ(t.field(1, t.column("d_sem")), "nan");
  EXPECT_EQ(t.integer(1, t.column("count")), 0);
}

// A random probe: grains at random frame positions with displacements over many decades.
FrameField random_probe(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  FrameField f;
  for (int i = 0; i < 400; ++i) {
    f.x.push_back(12.0 * uni(rng));
    f.y.push_back(12.0 * uni(rng));
    const double scale = 1e-9 * std::pow(10.0, 3.0 * uni(rng));
    f.ux.push_back(scale * uni(rng));
    f.uy.push_back(scale * uni(rng));
  }
  return f;
}

ResponseGrid merge_grid() {
  ResponseGrid g;
  g.half_width = 10.0;
  g.h = 0.5;
  g.r_min = 0.5;
  g.r_max = 15.0;
  g.r_bins = 12;
  return g;
}

// Seven probes (ids 0..6): added one by one, or split over "threads" and merged in any order,
// give bit-identical accumulators, CSVs, checkpoints and fits.
TEST(ResponseAverage, MergeIsBitIdenticalForAnyGrouping) {
  const double g = 1e-9;
  std::vector<FrameField> probe;
  for (int p = 0; p < 7; ++p) probe.push_back(random_probe(100 + p));
  auto add = [&](ResponseAverage& avg, std::initializer_list<int> ids) {
    for (int p : ids) avg.add_probe(p, probe[p], g);
  };

  ResponseAverage serial(merge_grid());
  add(serial, {0, 1, 2, 3, 4, 5, 6});

  ResponseAverage a(merge_grid()), b(merge_grid()), c(merge_grid());
  add(a, {0, 1, 2});
  add(b, {3, 4});
  add(c, {5, 6});
  ResponseAverage in_order(merge_grid());
  in_order.merge(a);
  in_order.merge(b);
  in_order.merge(c);

  ResponseAverage d(merge_grid()), e(merge_grid()), f(merge_grid());
  add(d, {6, 0});
  add(e, {4, 2, 3});
  add(f, {5, 1});
  e.merge(f);
  d.merge(e);  // a different grouping, merged out of probe order

  for (const ResponseAverage* m : {&in_order, &d}) {
    EXPECT_TRUE(*m == serial);
    EXPECT_EQ(m->field_csv(), serial.field_csv());
    EXPECT_EQ(m->profile_csv(), serial.profile_csv());
    EXPECT_EQ(m->to_json().dump(), serial.to_json().dump());
    const FitWindow w{1.0, 12.0};
    const PowerLawFit f1 = fit_power_law(*m, w, 50, 9), f0 = fit_power_law(serial, w, 50, 9);
    EXPECT_EQ(f1.alpha, f0.alpha);
    EXPECT_EQ(f1.alpha_err, f0.alpha_err);
  }
}

TEST(ResponseAverage, RejectsDuplicatesAndBadInputUnchanged) {
  ResponseAverage avg(merge_grid());
  avg.add_probe(1, random_probe(1), 1e-9);
  const ResponseAverage before = avg;
  EXPECT_THROW(avg.add_probe(1, random_probe(2), 1e-9), Error);
  FrameField bad = random_probe(3);
  bad.ux[17] = std::nan("");
  EXPECT_THROW(avg.add_probe(2, bad, 1e-9), Error);
  EXPECT_THROW(avg.add_probe(2, random_probe(3), 0.0), Error);
  ResponseAverage other(merge_grid());
  other.add_probe(5, random_probe(5), 1e-9);
  other.add_probe(1, random_probe(1), 1e-9);
  EXPECT_THROW(avg.merge(other), Error);
  ResponseGrid g2 = merge_grid();
  g2.r_bins = 13;
  EXPECT_THROW(avg.merge(ResponseAverage(g2)), Error);
  EXPECT_TRUE(avg == before);
  EXPECT_TRUE(avg.has_probe(1));
  EXPECT_FALSE(avg.has_probe(2));
}

TEST(ResponseAverage, CheckpointRoundTripIsExact) {
  ResponseAverage avg(merge_grid());
  for (int p = 0; p < 4; ++p) avg.add_probe(3 * p + 1, random_probe(200 + p), 1e-9);

  const ResponseAverage from_text = ResponseAverage::from_json(nlohmann::json::parse(avg.to_json().dump()));
  EXPECT_TRUE(from_text == avg);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "unjam_test_response_average";
  std::filesystem::create_directories(dir);
  avg.save(dir / "checkpoint.json");
  ResponseAverage loaded = ResponseAverage::load(dir / "checkpoint.json");
  EXPECT_TRUE(loaded == avg);
  EXPECT_EQ(loaded.field_csv(), avg.field_csv());
  EXPECT_EQ(loaded.profile_csv(), avg.profile_csv());

  // Resuming: the loaded accumulator takes further probes exactly like the original.
  loaded.add_probe(100, random_probe(300), 1e-9);
  avg.add_probe(100, random_probe(300), 1e-9);
  EXPECT_TRUE(loaded == avg);

  write_file_atomic(dir / "broken.json", "{\"format\": \"unjam-response-average\"}");
  EXPECT_THROW(ResponseAverage::load(dir / "broken.json"), Error);
  std::filesystem::remove_all(dir);
}

TEST(ResponseAverage, CheckpointIntegersThatAreHugeFloatsAreRefused) {
  // Found by fuzz/fuzz_checkpoint_reader: a float where an integer is expected (a 128-bit
  // sum's parts, a count, a probe id, r_bins) was cast, undefined beyond the type's range.
  ResponseAverage avg(merge_grid());
  avg.add_probe(7, random_probe(11), 1e-9);
  const nlohmann::json good = avg.to_json();
  ASSERT_TRUE(ResponseAverage::from_json(good) == avg);
  const std::vector<std::pair<std::string, nlohmann::json::json_pointer>> places = {
      {"field sum", nlohmann::json::json_pointer("/field/ux_sum/0/1")},
      {"field sum", nlohmann::json::json_pointer("/field/uy_sum/3/0")},
      {"field count", nlohmann::json::json_pointer("/field/count/2")},
      {"probe id", nlohmann::json::json_pointer("/probes/0/id")},
      {"probe count", nlohmann::json::json_pointer("/probes/0/count/0")},
      {"r_bins", nlohmann::json::json_pointer("/grid/r_bins")},
  };
  for (const auto& [what, where] : places)
    for (const double huge : {-9.2233720368547758e19, 1e300}) {
      nlohmann::json j = good;
      j[where] = huge;
      SCOPED_TRACE(where.to_string() + " = " + j[where].dump());
      try {
        (void)ResponseAverage::from_json(j);
        ADD_FAILURE() << "accepted";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(what + " must be an integer in ["), std::string::npos) << e.what();
      }
    }
  // An integral float in range stays accepted (tools that write every number as a double).
  nlohmann::json j = good;
  j["grid"]["r_bins"] = static_cast<double>(good["grid"]["r_bins"].get<int>());
  EXPECT_TRUE(ResponseAverage::from_json(j) == avg);
}

}  // namespace
}  // namespace unjam
